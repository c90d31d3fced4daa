// The PowerBall model (mjcf/powerball/) on its test gimbal (powerball_gimbal.xml), the shell
// driven by the test, against closed forms (README "Physics"; notation of powerball_truth.h:
// spin omega about the axle a, precession nu of the axle relative to the shell, groove
// rolling radius R, tip radius r, spin inertia I_s; all read back from the compiled model).
//
// 1. Rolling without slip: the tip on the wall has contact-point velocity (nu R - omega r) b,
//    so rolling means omega = (R/r) nu.
// 2. Wall couple: turning L = I_s omega a at nu needs M = I_s omega nu (along b); only the
//    tip contacts can supply it.
// 3. Spin-up law: with the groove normal e3 running round a cone of half-angle alpha at the
//    axle's rate, phase delta ahead of the axle (delta = 0: the axle on the groove's line of
//    nodes, the high side 90 deg ahead of it), tip friction gives
//    omega' = (r/R) omega nu sin(alpha) cos(delta), and with rolling
//    d(1/nu)/dt = -(r/R) sin(alpha) cos(delta).
// 4. Start-up: at omega = 0 there is no gyroscopic couple, no normal force and no friction.
// 5. A frictionless groove (condim 1) transmits no torque about the axle: no spin-up.
// 6. Free spin, shell still, no contact: an axisymmetric rotor keeps omega exactly.
// 7. Losses (README "Losses"): the spin alone carries air drag c omega and the axle's friction
//    T_c in the ring, so a free rotor coasts down by I_s omega' = -T_c - c omega:
//    omega(t) = (omega_0 + T_c / c) exp(-t c / I_s) - T_c / c.
// The spin-up comes out of the tip-wall contacts: the model has no gear, equality or
// scripted coupling (test LoadsWithTheReadmeEstimates checks that nothing else couples).
// Tests 1 to 6 are of the groove's mechanics: they take the spin's losses out (LosslessSpin),
// so that the closed forms hold exactly; test 7 puts them back.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include "lab/devices/powerball_truth.h"
#include "mujoco_fixture.h"

namespace vlab::lab {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;
constexpr double kRpm = 2.0 * kPi / 60.0;  // rad/s per rpm

double Wrap(double angle) { return std::remainder(angle, 2.0 * kPi); }

// gimbal angles (qx about x, then qy about the turned y) that put the shell's z at
// e3 = (sin alpha cos psi, sin alpha sin psi, cos alpha): e3 = (sin qy, -sin qx cos qy, cos qx cos qy)
void GimbalAngles(double alpha, double psi, double* qx, double* qy) {
  *qy = std::asin(std::sin(alpha) * std::cos(psi));
  *qx = std::atan2(-std::sin(alpha) * std::sin(psi), std::cos(alpha));
}

class PowerballRig : public vlab::test::MujocoTest {
 protected:
  void SetUp() override {
    model_ = LoadModel("mjcf/powerball/powerball_gimbal.xml");
    data_ = MakeData(model_);
    ball_ = PowerballBinding::Bind(*model_, "powerball_gimbal.xml");
    gimbal_x_ = model_->jnt_dofadr[mj_name2id(model_, mjOBJ_JOINT, "gimbal_x")];
    gimbal_y_ = model_->jnt_dofadr[mj_name2id(model_, mjOBJ_JOINT, "gimbal_y")];
  }

  double RollingRatio() const { return ball_.groove_radius_m / ball_.tip_radius_m; }

  // the groove's mechanics alone: no air drag or axle friction on the spin
  void LosslessSpin() {
    model_->dof_damping[ball_.spin_dof] = 0.0;
    model_->dof_frictionloss[ball_.spin_dof] = 0.0;
  }

  // the rotor rolling on the upper wall at omega (nu = omega r / R), tilted to touch it
  void StartRolling(double omega) {
    mj_resetData(model_, data_);
    const double touch = std::asin(0.942e-3 / ball_.groove_radius_m);  // README: R sin 2 deg play
    data_->qpos[model_->jnt_qposadr[mj_name2id(model_, mjOBJ_JOINT, "pb_tilt")]] = touch;
    data_->qvel[ball_.spin_dof] = omega;
    data_->qvel[ball_.precess_dof] = omega / RollingRatio();
    mj_forward(model_, data_);
    phase_started_ = false;
  }

  // computed-torque PD on the gimbal (50 Hz, critically damped for the 0.006 kg m^2
  // armature plus the ball) so that e3 follows the cone (alpha, psi) turning at psi_dot
  void Drive(double alpha, double alpha_dot, double psi, double psi_dot) {
    constexpr double kInertia = 0.0065, kOmegaServo = 2.0 * kPi * 50.0, h = 1e-5;
    constexpr double kp = kInertia * kOmegaServo * kOmegaServo, kd = 2.0 * kInertia * kOmegaServo;
    double x0, y0, x1, y1, xp, yp, xm, ym;
    GimbalAngles(alpha, psi, &x0, &y0);
    GimbalAngles(alpha + alpha_dot * h, psi + psi_dot * h, &x1, &y1);
    GimbalAngles(alpha, psi + h, &xp, &yp);
    GimbalAngles(alpha, psi - h, &xm, &ym);
    const double ax = (xp - 2.0 * x0 + xm) / (h * h) * psi_dot * psi_dot;
    const double ay = (yp - 2.0 * y0 + ym) / (h * h) * psi_dot * psi_dot;
    data_->ctrl[0] =
        kInertia * ax + kp * Wrap(x0 - data_->qpos[gimbal_x_]) + kd * ((x1 - x0) / h - data_->qvel[gimbal_x_]);
    data_->ctrl[1] =
        kInertia * ay + kp * Wrap(y0 - data_->qpos[gimbal_y_]) + kd * ((y1 - y0) / h - data_->qvel[gimbal_y_]);
  }

  // the cone locked to the axle, as a wrist would do it: a phase oscillator psi turning at
  // the rolling rate of the spin, (r/R) omega (what the ball's counter tells), pulled
  // towards the axle's azimuth + s (delta - 90 deg) (s = sign of nu) at kLock = 20 rad/s at
  // most; alpha ramped up over the first second (a step slams the tips)
  void DriveLocked(const PowerballTruth& t, double alpha, double delta) {
    constexpr double kLock = 20.0;
    const double ramp = std::min(1.0, data_->time);
    const double s = t.nu >= 0.0 ? 1.0 : -1.0;
    const double target = std::atan2(t.axle[1], t.axle[0]) + s * (delta - 0.5 * kPi);
    if (!phase_started_) psi_ = target, phase_started_ = true;
    const double rate = s * std::abs(t.omega) / RollingRatio() + kLock * Wrap(target - psi_) / kPi;
    Drive(alpha * ramp, data_->time < 1.0 ? alpha : 0.0, psi_, rate);
    psi_ += rate * model_->opt.timestep;
  }

  // measured cone: half-angle of e3 and its phase ahead of the axle's line of nodes
  static double ConeAlpha(const PowerballTruth& t) { return std::acos(std::min(1.0, t.normal[2])); }
  static double ConeDelta(const PowerballTruth& t) {
    const double s = t.nu >= 0.0 ? 1.0 : -1.0;
    return Wrap(s * Wrap(std::atan2(t.normal[1], t.normal[0]) - std::atan2(t.axle[1], t.axle[0])) + 0.5 * kPi);
  }

  bool Step() {
    mj_step(model_, data_);
    return !vlab::test::AnyWarning(*data_);
  }

  // the shell held still, the axle in the groove plane, the rotor spun to omega0 and left for
  // 5 s: the largest |omega - law(t)|, and the tip contacts seen (false on a solver warning)
  template <typename Law>
  bool CoastWithTheShellStill(double omega0, Law law, double* worst, int* contacts) {
    mj_resetData(model_, data_);
    data_->qvel[ball_.spin_dof] = omega0;
    mj_forward(model_, data_);
    *worst = 0.0;
    *contacts = 0;
    while (data_->time < 5.0) {
      Drive(0.0, 0.0, 0.0, 0.0);
      if (!Step()) return false;
      const PowerballTruth t = MeasurePowerball(*model_, *data_, ball_);
      *worst = std::max(*worst, std::abs(t.omega - law(data_->time)));
      *contacts += t.contacts;
    }
    return true;
  }

  mjModel* model_ = nullptr;
  mjData* data_ = nullptr;
  PowerballBinding ball_;
  int gimbal_x_ = -1, gimbal_y_ = -1;
  double psi_ = 0.0;  // cone phase of DriveLocked
  bool phase_started_ = false;
};

TEST_F(PowerballRig, LoadsWithTheReadmeEstimates) {
  EXPECT_NEAR(ball_.groove_radius_m, 0.027, 1e-12);
  EXPECT_NEAR(ball_.tip_radius_m, 0.0012, 1e-12);
  EXPECT_NEAR(ball_.spin_inertia, 2e-5, 1e-15);
  EXPECT_NEAR(model_->body_mass[ball_.rotor_body], 0.060, 1e-12);
  EXPECT_EQ(model_->opt.timestep, 1e-4);
  EXPECT_EQ(model_->opt.integrator, mjINT_EULER);
  EXPECT_EQ(model_->opt.cone, mjCONE_ELLIPTIC);
  EXPECT_EQ(model_->opt.solver, mjSOL_PGS);
  // nothing but the contacts couples spin and precession: no equality, tendon, damping,
  // joint friction or armature on the ring's and the tilt's joints; the spin carries its own
  // losses only (README "Losses": air 1.5e-7 N m s, axle friction 2e-5 N m), which act on
  // the spin alone
  EXPECT_EQ(model_->neq, 0);
  EXPECT_EQ(model_->ntendon, 0);
  for (int dof : {ball_.precess_dof, ball_.tilt_dof}) {
    EXPECT_EQ(model_->dof_damping[dof], 0.0);
    EXPECT_EQ(model_->dof_frictionloss[dof], 0.0);
    EXPECT_EQ(model_->dof_armature[dof], 0.0);
  }
  EXPECT_EQ(model_->dof_damping[ball_.spin_dof], 1.5e-7);
  EXPECT_EQ(model_->dof_frictionloss[ball_.spin_dof], 2e-5);
  EXPECT_EQ(model_->dof_armature[ball_.spin_dof], 0.0);
  for (int tip : {ball_.tip_plus, ball_.tip_minus}) {
    EXPECT_EQ(model_->geom_condim[tip], 3);
    EXPECT_EQ(model_->geom_friction[3 * tip], 0.3);
  }
}

// 1 and 2 at constant speed: the shell held still, the rotor started rolling at 2,000, 5,000
// and 10,000 rpm. The rolling ratio holds to 1 % and the couple to 5 % after 0.2 s
// (bounds of the issue; measured: 0.155 % and 0.156 %, README "Tests": the rolling figure is the
// tilted ring's share nu sin 2 deg, counted in omega relative to the shell).
TEST_F(PowerballRig, RollsAtRoverRAndTheWallsCarryTheGyroscopicCouple) {
  LosslessSpin();
  for (double rpm : {2000.0, 5000.0, 10000.0}) {
    StartRolling(rpm * kRpm);
    double worst_roll = 0.0, worst_couple = 0.0;
    int samples = 0;
    while (data_->time < 0.6) {
      Drive(0.0, 0.0, 0.0, 0.0);
      ASSERT_TRUE(Step()) << rpm << " rpm, t " << data_->time;
      if (data_->time < 0.2) continue;
      const PowerballTruth t = MeasurePowerball(*model_, *data_, ball_);
      const double expected_couple = ball_.spin_inertia * t.omega * t.nu;
      worst_roll = std::max(worst_roll, std::abs(t.omega - RollingRatio() * t.nu) / std::abs(t.omega));
      worst_couple = std::max(worst_couple, std::abs(t.CoupleNorm() / expected_couple - 1.0));
      ++samples;
    }
    EXPECT_GT(samples, 3000);
    EXPECT_LE(worst_roll, 0.01) << rpm << " rpm";
    EXPECT_LE(worst_couple, 0.05) << rpm << " rpm";
    const PowerballTruth end = MeasurePowerball(*model_, *data_, ball_);
    // it rolled: the spin is still there (no dissipation while rolling)
    EXPECT_NEAR(end.omega, rpm * kRpm, 0.01 * rpm * kRpm) << rpm << " rpm";
    RecordProperty("rolling_" + std::to_string(int(rpm)), std::to_string(worst_roll));
    RecordProperty("couple_" + std::to_string(int(rpm)), std::to_string(worst_couple));
  }
}

// 3: from 2,000 rpm, alpha = 10 deg, delta = 30 deg, until 8,000 rpm. 1/nu falls on a
// line whose slope is -(r/R) sin(alpha) cos(delta), with alpha and delta measured on the
// shell (the servo's lag leaves them within 0.5 deg of the command). Bound +-10 % (issue;
// measured -0.3 %). Along the way the tips roll (1 %) and carry I_s omega nu (5 %).
TEST_F(PowerballRig, SpinUpFollowsTheRateLawFrom2000To8000Rpm) {
  LosslessSpin();
  StartRolling(2000.0 * kRpm);
  std::vector<double> times, inverse_nu;
  double sum_gain = 0.0, worst_roll = 0.0, worst_couple = 0.0, omega = 0.0;
  while (data_->time < 20.0 && omega < 8000.0 * kRpm) {
    const PowerballTruth t = MeasurePowerball(*model_, *data_, ball_);
    omega = t.omega;
    DriveLocked(t, 10.0 * kDeg, 30.0 * kDeg);
    ASSERT_TRUE(Step()) << "t " << data_->time;
    if (data_->time < 1.2) continue;  // the cone ramps up over 1 s
    times.push_back(data_->time);
    inverse_nu.push_back(1.0 / t.nu);
    sum_gain += std::sin(ConeAlpha(t)) * std::cos(ConeDelta(t));
    worst_roll = std::max(worst_roll, std::abs(t.omega - RollingRatio() * t.nu) / std::abs(t.omega));
    worst_couple = std::max(worst_couple, std::abs(t.CoupleNorm() / (ball_.spin_inertia * t.omega * t.nu) - 1.0));
  }
  ASSERT_GE(omega, 8000.0 * kRpm) << "no spin-up within 20 s";
  const double n = double(times.size());
  // least-squares slope of 1/nu against t
  double mean_t = 0.0, mean_y = 0.0;
  for (size_t i = 0; i < times.size(); ++i) {
    mean_t += times[i] / n;
    mean_y += inverse_nu[i] / n;
  }
  double stt = 0.0, sty = 0.0;
  for (size_t i = 0; i < times.size(); ++i) {
    stt += (times[i] - mean_t) * (times[i] - mean_t);
    sty += (times[i] - mean_t) * (inverse_nu[i] - mean_y);
  }
  const double slope = sty / stt;
  const double predicted = -(ball_.tip_radius_m / ball_.groove_radius_m) * sum_gain / n;
  // the commanded cone: sin 10 deg cos 30 deg
  EXPECT_NEAR(sum_gain / n, std::sin(10.0 * kDeg) * std::cos(30.0 * kDeg), 0.01 * std::sin(10.0 * kDeg));
  EXPECT_NEAR(slope / predicted, 1.0, 0.10) << "slope " << slope << " predicted " << predicted;
  EXPECT_LE(worst_roll, 0.01);
  EXPECT_LE(worst_couple, 0.05);
  RecordProperty("slope_ratio", std::to_string(slope / predicted));
  RecordProperty("time_to_8000", std::to_string(data_->time));
}

// 4: from rest, 10 s of a 5 Hz, 10 deg cone: no couple, no friction, no spin-up. Bound
// 100 rpm (issue). Measured 52 rpm: the shell's own rate about the axle, 2 pi 5 Hz x
// sin 10 deg = 5.5 rad/s, seen as spin relative to the shell by a rotor that stays put.
TEST_F(PowerballRig, StartUpFromRestStaysBelow100Rpm) {
  LosslessSpin();
  mj_resetData(model_, data_);
  mj_forward(model_, data_);
  const double rate = 2.0 * kPi * 5.0;
  double worst = 0.0;
  while (data_->time < 10.0) {
    const double ramp = std::min(1.0, data_->time);
    Drive(10.0 * kDeg * ramp, data_->time < 1.0 ? 10.0 * kDeg : 0.0, rate * data_->time, rate);
    ASSERT_TRUE(Step()) << "t " << data_->time;
    worst = std::max(worst, std::abs(MeasurePowerball(*model_, *data_, ball_).omega));
  }
  EXPECT_LT(worst, 100.0 * kRpm);
  // the wobble was there: the shell's axis ran round the cone
  const PowerballTruth end = MeasurePowerball(*model_, *data_, ball_);
  EXPECT_NEAR(ConeAlpha(end), 10.0 * kDeg, 0.5 * kDeg);
  RecordProperty("max_rpm", std::to_string(worst / kRpm));
}

// 5: the spin-up drive of test 3 for 6 s, once with the groove frictionless (condim 1 on
// both tips), once as built: frictionless gains no more than 2 % (issue); as built the same
// drive gains more than 50 % (the rate law gives 2,000 -> 3,100 rpm in 6 s).
TEST_F(PowerballRig, FrictionlessGrooveDoesNotSpinUp) {
  LosslessSpin();
  auto run = [&](int condim) {
    // a contact takes the larger condim of its two geoms: set the walls' too
    for (const char* geom : {"pb_tip_plus", "pb_tip_minus", "pb_wall_upper", "pb_wall_lower"}) {
      model_->geom_condim[mj_name2id(model_, mjOBJ_GEOM, geom)] = condim;
    }
    StartRolling(2000.0 * kRpm);
    double top = 0.0;
    while (data_->time < 6.0) {
      const PowerballTruth t = MeasurePowerball(*model_, *data_, ball_);
      top = std::max(top, std::abs(t.omega));
      DriveLocked(t, 10.0 * kDeg, 30.0 * kDeg);
      if (!Step()) return -1.0;
    }
    return top;
  };
  const double frictionless = run(1);
  const double with_friction = run(3);
  EXPECT_GT(frictionless, 0.0) << "warning in the frictionless run";
  EXPECT_LE(frictionless, 1.02 * 2000.0 * kRpm);
  EXPECT_GE(with_friction, 1.5 * 2000.0 * kRpm);
  RecordProperty("frictionless_max_rpm", std::to_string(frictionless / kRpm));
  RecordProperty("friction_max_rpm", std::to_string(with_friction / kRpm));
}

// Out of sync: the same drive with the cone half a turn off (delta = 180 deg) brakes the
// rotor: the rate law with cos(delta) = -1, 1/nu rising at (r/R) sin(alpha). From 5,000 rpm
// over 3 s (alpha ramped linearly over the first second: the integral of sin(alpha) is
// (1 - cos 10 deg) / (10 deg in rad) + 2 sin 10 deg) the law gives 3,450 rpm; bound +-10 %
// on 1/nu's rise, as for the spin-up (measured 3,460 rpm).
TEST_F(PowerballRig, OutOfPhaseWobbleBrakesTheRotorByTheRateLaw) {
  LosslessSpin();
  StartRolling(5000.0 * kRpm);
  const double inverse_nu0 = 1.0 / data_->qvel[ball_.precess_dof];
  while (data_->time < 3.0) {
    const PowerballTruth t = MeasurePowerball(*model_, *data_, ball_);
    DriveLocked(t, 10.0 * kDeg, 180.0 * kDeg);
    ASSERT_TRUE(Step()) << "t " << data_->time;
  }
  const PowerballTruth end = MeasurePowerball(*model_, *data_, ball_);
  const double alpha = 10.0 * kDeg;
  const double sin_integral = (1.0 - std::cos(alpha)) / alpha + (data_->time - 1.0) * std::sin(alpha);
  const double predicted_rise = (ball_.tip_radius_m / ball_.groove_radius_m) * sin_integral;
  EXPECT_NEAR((1.0 / end.nu - inverse_nu0) / predicted_rise, 1.0, 0.10);
  EXPECT_LT(end.slip, 0.01) << "braked by rolling, not by sliding";
  RecordProperty("end_rpm", std::to_string(end.Rpm()));
}

// Out of sync, the other way: an open-loop cone at twice the rolling rate of 2,000 rpm
// (free-running phase, as a beginner's wrist): the wobble and the axle drift through every
// phase, so the friction pushes as often as it brakes ("no resistance, the rotor may slap
// around", DS 5.2 / rpmpower). Over 4 s the tips slip (measured: slip ratio up to 0.9999,
// rolling reads 0.0015; bound 0.1) and the spin stays below 2,200 rpm (+10 %; measured top
// 2,054 rpm), where the locked cone of the spin-up test is past 2,600 rpm by 4 s.
TEST_F(PowerballRig, AnUnsynchronisedWobbleSlipsAndGainsNothing) {
  LosslessSpin();
  StartRolling(2000.0 * kRpm);
  const double rate = 2.0 * data_->qvel[ball_.precess_dof];
  double worst_slip = 0.0, top = 0.0;
  while (data_->time < 4.0) {
    const double ramp = std::min(1.0, data_->time);
    Drive(10.0 * kDeg * ramp, data_->time < 1.0 ? 10.0 * kDeg : 0.0, rate * data_->time, rate);
    ASSERT_TRUE(Step()) << "t " << data_->time;
    const PowerballTruth t = MeasurePowerball(*model_, *data_, ball_);
    if (data_->time > 1.0) worst_slip = std::max(worst_slip, t.slip);
    top = std::max(top, t.Rpm());
  }
  EXPECT_GT(worst_slip, 0.1);
  EXPECT_LT(top, 2200.0);
  RecordProperty("worst_slip", std::to_string(worst_slip));
  RecordProperty("top_rpm", std::to_string(top));
}

// 6: shell held still, the axle in the groove plane clear of both walls, 2,000 rpm, the
// spin's losses out: an axisymmetric rotor about its symmetry axis has no gyroscopic torque, so omega
// stays to 1e-6 over 5 s (issue) and nothing touches.
TEST_F(PowerballRig, FreeSpinIsConservedWithTheShellStill) {
  LosslessSpin();
  const double omega0 = 2000.0 * kRpm;
  double worst = 0.0;
  int contacts = 0;
  ASSERT_TRUE(CoastWithTheShellStill(
      omega0, [&](double) { return omega0; }, &worst, &contacts));
  worst /= omega0;
  EXPECT_LE(worst, 1e-6);
  EXPECT_EQ(contacts, 0);
  char drift[32];
  std::snprintf(drift, sizeof drift, "%.3g", worst);
  RecordProperty("drift", drift);
}

// 7: the same still shell with the spin's losses as built, from 12,000 rpm for 5 s: the rotor
// follows I_s omega' = -T_c - c omega (header) within 0.5 % of the speed lost (measured
// below), and loses about 100 rpm/s at the start (README "Losses"). Contact would add
// losses the law leaves out: none may occur.
TEST_F(PowerballRig, FreeSpinCoastsDownByTheLossLaw) {
  const double omega0 = 12000.0 * kRpm;
  const double c = model_->dof_damping[ball_.spin_dof], friction = model_->dof_frictionloss[ball_.spin_dof];
  ASSERT_GT(c, 0.0);
  ASSERT_GT(friction, 0.0);
  const double tau = ball_.spin_inertia / c, offset = friction / c;
  double worst = 0.0;
  int contacts = 0;
  ASSERT_TRUE(CoastWithTheShellStill(
      omega0, [&](double t) { return (omega0 + offset) * std::exp(-t / tau) - offset; }, &worst, &contacts));
  const double end = MeasurePowerball(*model_, *data_, ball_).omega;
  const double lost = omega0 - end;
  // about 100 rpm/s: 400 to 600 rpm in 5 s
  EXPECT_GT(lost, 400.0 * kRpm);
  EXPECT_LT(lost, 600.0 * kRpm);
  EXPECT_LE(worst, 0.005 * lost);
  EXPECT_EQ(contacts, 0);
  RecordProperty("rpm_lost_in_5_s", std::to_string(lost / kRpm));
  RecordProperty("worst_vs_law_rpm", std::to_string(worst / kRpm));
}

}  // namespace
}  // namespace vlab::lab
