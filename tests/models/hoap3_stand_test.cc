// HOAP-3 physics in scenes/hoap3.xml: standing, squatting and waving under a joint
// position servo (models/hoap3_balance.h), read through the foot FSRs and the IMU.
//
// Closed forms checked every physics step (1 kHz):
//   - the eight FSRs sum to the robot's weight m g (static equilibrium; the scripted
//     motions are slow, so within 2 % throughout);
//   - the centre of pressure from the FSRs stays inside the support polygon (the convex
//     hull of the pads) with a margin, and at rest equals the ground projection of the
//     centre of mass (moment balance about the COM);
//   - at rest the accelerometer reads +g along the world vertical, the gyro reads 0.
// Also: no MuJoCo warning, only the FSR pads touch anything, and the robot ends where it
// started (no slip, no sag). Measured values are printed and recorded as test properties.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <iostream>
#include <string>

#include <gtest/gtest.h>

#include "models/hoap3_balance.h"
#include "models/model_test_util.h"
#include "mujoco_fixture.h"

namespace vlab::models::testing {
namespace {

constexpr double kDt = 0.001;
constexpr double kSettle_s = 0.5;  // the pads sink ~0.5 mm into the floor at first

double Quintic(double s) {
  s = std::clamp(s, 0.0, 1.0);
  return s * s * s * (10 - 15 * s + 6 * s * s);
}

struct RunStats {
  double worst_force_error = 0;  // max |sum F / (m g) - 1| after settling
  double min_margin_m = 1e9;     // smallest CoP margin inside the support polygon
  double max_cop_com_m = 0;      // max |CoP - COM_xy| while at rest
  long foreign_contacts = 0;     // contacts other than pad-floor
  double steps_per_s = 0;        // wall-clock speed (reported only)
};

class Hoap3Stand : public vlab::test::MujocoTest {
 protected:
  void SetUp() override {
    model_ = LoadModel("scenes/hoap3.xml");
    data_ = MakeData(m());
    ResetToKey(m(), d(), "stand");
    balance_ = Hoap3Balance::Create(m());
    ASSERT_NE(balance_, nullptr);
    q_stand_ = balance_->Positions(*d());
    for (int b = 0; b < m()->nbody; ++b) mass_ += m()->body_mass[b];
    weight_N_ = mass_ * -m()->opt.gravity[2];
  }
  const mjModel* m() const { return model_; }
  mjData* d() const { return data_; }

  // Runs until duration_s with q_ref = reference(t); at_rest(t) marks times at which the
  // robot is static (CoP = COM projection is checked then).
  RunStats Run(double duration_s, const std::function<Eigen::VectorXd(double)>& reference,
               const std::function<bool(double)>& at_rest) {
    RunStats stats;
    const auto start = std::chrono::steady_clock::now();
    long steps = 0;
    while (d()->time < duration_s - 0.5 * kDt) {
      mj_step1(m(), d());
      balance_->Actuate(reference(d()->time), *d());
      mj_step2(m(), d());
      ++steps;
      for (int i = 0; i < d()->ncon; ++i) {
        const std::string g1 = mj_id2name(m(), mjOBJ_GEOM, d()->contact[i].geom1);
        const std::string g2 = mj_id2name(m(), mjOBJ_GEOM, d()->contact[i].geom2);
        stats.foreign_contacts += !(g1 == "floor" && g2.find("foot_") != std::string::npos);
      }
      if (d()->time < kSettle_s) continue;
      const FootReading feet = balance_->ReadFeet(*d());
      stats.worst_force_error = std::max(stats.worst_force_error, std::abs(feet.force_sum_N / weight_N_ - 1));
      stats.min_margin_m = std::min(stats.min_margin_m, feet.margin_m);
      if (at_rest(d()->time)) {
        const Eigen::Vector2d com(d()->subtree_com[3], d()->subtree_com[4]);
        stats.max_cop_com_m = std::max(stats.max_cop_com_m, (feet.cop_W - com).norm());
      }
    }
    const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    stats.steps_per_s = steps / std::max(wall_s, 1e-9);
    return stats;
  }

  void Report(const RunStats& s) {
    std::cout << "  FSR sum error max " << 100 * s.worst_force_error << " % of m g = " << weight_N_ << " N (" << mass_
              << " kg); CoP margin min " << 1000 * s.min_margin_m << " mm; |CoP - COM| at rest max "
              << 1000 * s.max_cop_com_m << " mm; " << s.steps_per_s << " steps/s (with the servo)\n";
    RecordProperty("fsr_sum_error_percent", std::to_string(100 * s.worst_force_error));
    RecordProperty("cop_margin_mm", std::to_string(1000 * s.min_margin_m));
    RecordProperty("steps_per_s", std::to_string(s.steps_per_s));
  }

  Eigen::Vector3d BodyPos(const char* body) const { return Vec3(d()->xpos + 3 * Id(m(), mjOBJ_BODY, body)); }

  const mjModel* model_ = nullptr;
  mjData* data_ = nullptr;
  std::unique_ptr<Hoap3Balance> balance_;
  Eigen::VectorXd q_stand_;
  double mass_ = 0, weight_N_ = 0;
};

TEST_F(Hoap3Stand, StandsThirtySecondsOnItsFsrs) {
  const Eigen::Vector3d pelvis0 = BodyPos("hoap3_pelvis"), right0 = BodyPos("hoap3_r_foot");
  const Eigen::Vector3d chest_up0 = Mat3(d()->xmat + 9 * Id(m(), mjOBJ_BODY, "hoap3_chest")).col(2);
  const RunStats s = Run(
      30.0, [&](double) { return q_stand_; }, [](double t) { return t > 1.0; });
  Report(s);
  // standing still the FSRs carry the weight: measured 1.9e-5 of m g after settling, x 10
  // (the squat below accelerates the COM and keeps its 2 %)
  EXPECT_LT(s.worst_force_error, 2e-4);
  EXPECT_GT(s.min_margin_m, 0.02);
  EXPECT_LT(s.max_cop_com_m, 1e-3);
  EXPECT_EQ(s.foreign_contacts, 0);
  // still standing where it stood: sag of the contact only, no slip, no lean
  EXPECT_LT((BodyPos("hoap3_pelvis") - pelvis0).norm(), 2e-3);
  EXPECT_LT((BodyPos("hoap3_r_foot") - right0).head<2>().norm(), 1e-4);
  const Eigen::Vector3d chest_up = Mat3(d()->xmat + 9 * Id(m(), mjOBJ_BODY, "hoap3_chest")).col(2);
  EXPECT_LT(std::acos(std::min(1.0, chest_up.dot(chest_up0))), 1.0 * M_PI / 180);
  // IMU at rest: specific force +g along the world vertical, no rotation rate
  const int accel = Id(m(), mjOBJ_SENSOR, "hoap3_accel"), gyro = Id(m(), mjOBJ_SENSOR, "hoap3_gyro");
  const Eigen::Matrix3d r_imu = Mat3(d()->site_xmat + 9 * Id(m(), mjOBJ_SITE, "hoap3_imu"));
  const Eigen::Vector3d f_W = r_imu * Vec3(d()->sensordata + m()->sensor_adr[accel]);
  EXPECT_LT((f_W - Eigen::Vector3d(0, 0, -m()->opt.gravity[2])).norm(), 0.01 * 9.81);
  EXPECT_LT(Vec3(d()->sensordata + m()->sensor_adr[gyro]).norm(), 1e-3);
}

// Squat (knees 0.4 -> 1.2 rad in 2 s, hold, up in 2 s), then a right-arm wave (upper arm
// out to the side, turned so the forearm points up, elbow swinging 0.8 rad at 1 Hz) and back.
TEST_F(Hoap3Stand, SquatsAndWavesWithTheCopInsideTheSupportPolygon) {
  const int rk = balance_->Index("RL_J4"), rh = balance_->Index("RL_J3"), ra = balance_->Index("RL_J5");
  const int lk = balance_->Index("LL_J4"), lh = balance_->Index("LL_J3"), la = balance_->Index("LL_J5");
  const int roll = balance_->Index("RA_J2"), yaw = balance_->Index("RA_J3"), elbow = balance_->Index("RA_J4");
  ASSERT_TRUE(rk >= 0 && rh >= 0 && ra >= 0 && lk >= 0 && lh >= 0 && la >= 0 && roll >= 0 && yaw >= 0 && elbow >= 0);
  const double knee0 = q_stand_[rk];
  const auto reference = [&](double t) {
    Eigen::VectorXd q = q_stand_;
    // squat: 1-3 s down, 3-4 s hold, 4-6 s up; soles stay flat (hip = ankle = knee / 2)
    const double s = t < 4 ? Quintic((t - 1) / 2) : 1 - Quintic((t - 4) / 2);
    const double knee = knee0 + 0.8 * s;
    q[rk] = knee, q[rh] = knee / 2, q[ra] = -knee / 2;
    q[lk] = -knee, q[lh] = -knee / 2, q[la] = knee / 2;
    // wave: 7-8 s arm out, 8-11 s elbow swings, 11-12 s arm back
    const double out = t < 11 ? Quintic(t - 7) : 1 - Quintic(t - 11);
    q[roll] = q_stand_[roll] - 1.3 * out;
    q[yaw] = q_stand_[yaw] + 1.3 * out;
    const double swing = (t > 8 && t < 11) ? 0.4 * std::sin(2 * M_PI * (t - 8)) : 0.0;
    q[elbow] = q_stand_[elbow] + out * (0.8 + swing);
    return q;
  };
  const auto at_rest = [](double t) { return (t > 0.6 && t < 1) || (t > 3.3 && t < 4) || t > 12.5; };
  const Eigen::Vector3d pelvis0 = BodyPos("hoap3_pelvis"), right0 = BodyPos("hoap3_r_foot");
  // run in two parts to see the bottom of the squat
  RunStats s = Run(3.9, reference, at_rest);
  const double squat_depth = pelvis0.z() - BodyPos("hoap3_pelvis").z();
  EXPECT_NEAR(balance_->Positions(*d())[rk], knee0 + 0.8, 0.05);
  EXPECT_GT(squat_depth, 0.025) << "2 x 0.105 m x (cos 0.2 - cos 0.6) = 0.033 m";
  double elbow_min = 1e9, elbow_max = -1e9;
  const RunStats tail = Run(
      13.0,
      [&](double t) {
        const Eigen::VectorXd q = reference(t);
        if (t > 9 && t < 10) {
          elbow_min = std::min(elbow_min, d()->qpos[QposAdr(m(), "RA_J4")]);
          elbow_max = std::max(elbow_max, d()->qpos[QposAdr(m(), "RA_J4")]);
        }
        return q;
      },
      at_rest);
  s.worst_force_error = std::max(s.worst_force_error, tail.worst_force_error);
  s.min_margin_m = std::min(s.min_margin_m, tail.min_margin_m);
  s.max_cop_com_m = std::max(s.max_cop_com_m, tail.max_cop_com_m);
  s.foreign_contacts += tail.foreign_contacts;
  s.steps_per_s = tail.steps_per_s;
  Report(s);
  std::cout << "  squat depth " << 1000 * squat_depth << " mm, elbow swing " << elbow_max - elbow_min << " rad\n";
  EXPECT_GT(elbow_max - elbow_min, 0.6);
  EXPECT_LT(s.worst_force_error, 0.02);
  EXPECT_GT(s.min_margin_m, 0.015);
  EXPECT_LT(s.max_cop_com_m, 1e-3);
  EXPECT_EQ(s.foreign_contacts, 0);
  EXPECT_LT((BodyPos("hoap3_pelvis") - pelvis0).norm(), 2e-3);
  EXPECT_LT((BodyPos("hoap3_r_foot") - right0).head<2>().norm(), 1e-4);
}

// Without the servo the robot must fall: the standing test above can fail.
TEST_F(Hoap3Stand, FallsWithoutTheServo) {
  for (int i = 0; i < 3000; ++i) mj_step(m(), d());
  EXPECT_LT(BodyPos("hoap3_pelvis").z(), 0.2);
}

}  // namespace
}  // namespace vlab::models::testing
