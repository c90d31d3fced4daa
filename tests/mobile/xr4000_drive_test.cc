// The Nomad XR4000's drive (mjcf/nomad_xr4000) against closed forms.
//
// Each planar joint is a mass (or yaw inertia) driven by a velocity servo F = kv (v_c - v)
// clipped to +-F_max, so
//   - a step below the force limit is first order: v(t) = v_c (1 - exp(-t / tau)),
//     tau = M / kv, with no steady-state error (nothing resists a constant velocity);
//   - a larger step accelerates at F_max / M until v_c - v < F_max / kv;
//   - commands beyond ctrlrange are clipped to the velocity limit;
//   - the axes are independent: a pure vy command moves the base sideways with no x motion
//     and no yaw (holonomic).
// M and the yaw inertia are computed here from the data sheet (30 kg body, 4 casters of
// 7.92 kg at 0.2159 m, Iz 2.1 + 4 x 0.0253 kg m^2), not read from the model.
#include <algorithm>
#include <cmath>
#include <iostream>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include "mobile/mobile_scene.h"

namespace vlab::testing {
namespace {

constexpr double kBaseMass = 30.0 + 4 * (2.72 + 5.2);                                     // kg, DATASHEET 2
constexpr double kBaseYawInertia = 2.1 + 4 * (0.00332 + 0.022 + 7.92 * 0.2159 * 0.2159);  // kg m^2
constexpr double kKvLinear = 5000, kKvYaw = 325;                                          // xr4000_actuators.xml
constexpr double kForceMax = 96.4, kTorqueMax = 19.5;                                     // N, N m
constexpr double kSpeedMax = 1.0, kYawRateMax = 2.0;                                      // m/s, rad/s

class MobileXr4000DriveTest : public vlab::test::MujocoTest {
 protected:
  void SetUp() override {
    m_ = LoadModel("tests/mobile/data/xr4000_base.xml");
    d_ = MakeData(m_);
    for (const char* name : {"base_x", "base_y", "base_yaw"}) act_.push_back(RequireId(m_, mjOBJ_ACTUATOR, name));
    for (const char* name : {"base_x", "base_y", "base_yaw"}) {
      dof_.push_back(m_->jnt_dofadr[RequireId(m_, mjOBJ_JOINT, name)]);
    }
  }

  // time (s) at which axis `axis` first reaches `fraction` of `command` from rest, stepping
  // at most `seconds`; the state keeps running until then
  double RiseTime(int axis, double command, double fraction, double seconds) {
    d_->ctrl[act_[axis]] = command;
    for (int k = 1; k <= static_cast<int>(seconds / m_->opt.timestep); ++k) {
      const double v_before = d_->qvel[dof_[axis]];
      mj_step(m_, d_);
      const double v = d_->qvel[dof_[axis]];
      if (v >= fraction * command) {
        // linear interpolation inside the step
        const double s = (fraction * command - v_before) / (v - v_before);
        return (k - 1 + s) * m_->opt.timestep;
      }
    }
    return -1;
  }

  // time at which the explicit (velocity-actuator) update v += h / tau (v_c - v) crosses
  // 1 - exp(-1) of a step, for a continuous time constant tau
  double SampledTimeConstant(double tau) const {
    const double h = m_->opt.timestep;
    return -h / std::log(1 - h / tau);
  }

  const mjModel* m_ = nullptr;
  mjData* d_ = nullptr;
  std::vector<int> act_, dof_;
};

TEST_F(MobileXr4000DriveTest, ModelInertiaEqualsTheDataSheet) {
  mj_forward(m_, d_);
  std::vector<mjtNum> M(m_->nv * m_->nv);
  mj_fullM(m_, M.data(), d_->qM);
  EXPECT_NEAR(M[0], kBaseMass, 1e-9);
  EXPECT_NEAR(M[m_->nv + 1], kBaseMass, 1e-9);
  EXPECT_NEAR(M[2 * m_->nv + 2], kBaseYawInertia, 1e-3);
}

TEST_F(MobileXr4000DriveTest, SmallVelocityStepIsFirstOrder) {
  const double command = 0.01;  // m/s: kv * 0.01 = 50 N < F_max
  const double tau_expected = kBaseMass / kKvLinear;
  const double tau = RiseTime(0, command, 1 - std::exp(-1.0), 1.0);
  // run on to steady state (2 s = 160 time constants)
  for (int k = 0; k < 2000; ++k) mj_step(m_, d_);
  const double error = command - d_->qvel[dof_[0]];
  std::cout << "vx step 0.01 m/s: time constant " << tau * 1e3 << " ms (M/kv = " << tau_expected * 1e3
            << " ms), steady-state error " << error << " m/s\n";
  // the integrator samples the exponential: v_k = v_c (1 - (1 - h / tau)^k), so 1 - exp(-1)
  // is reached at t = -h / ln(1 - h / tau), about half a step before tau
  EXPECT_NEAR(tau, SampledTimeConstant(tau_expected), 0.002 * tau_expected);
  EXPECT_LT(std::abs(error), 1e-12);

  // the yaw axis likewise: tau = I / kv
  mj_resetData(m_, d_);
  const double yaw_tau_expected = kBaseYawInertia / kKvYaw;
  const double yaw_tau = RiseTime(2, 0.02, 1 - std::exp(-1.0), 1.0);  // kv * 0.02 = 6.5 N m < 19.5
  std::cout << "wz step 0.02 rad/s: time constant " << yaw_tau * 1e3 << " ms (I/kv = " << yaw_tau_expected * 1e3
            << " ms)\n";
  EXPECT_NEAR(yaw_tau, SampledTimeConstant(yaw_tau_expected), 0.002 * yaw_tau_expected);
}

TEST_F(MobileXr4000DriveTest, LargeStepIsAccelerationLimited) {
  d_->ctrl[act_[1]] = kSpeedMax;
  double max_accel = 0;
  for (int k = 0; k < 300; ++k) {
    mj_step(m_, d_);
    max_accel = std::max(max_accel, std::abs(d_->qacc[dof_[1]]));
  }
  // saturated for the first 0.3 s: v = a t with a = F_max / M
  const double a_expected = kForceMax / kBaseMass;
  const double a_mean = d_->qvel[dof_[1]] / 0.3;
  for (int k = 0; k < 3000; ++k) {
    mj_step(m_, d_);
    max_accel = std::max(max_accel, std::abs(d_->qacc[dof_[1]]));
  }
  std::cout << "vy step 1 m/s: acceleration " << a_mean << " m/s^2 (F_max/M = " << a_expected << "), final speed "
            << d_->qvel[dof_[1]] << " m/s\n";
  EXPECT_NEAR(a_mean, a_expected, 1e-3 * a_expected);
  EXPECT_LE(max_accel, a_expected * (1 + 1e-9));
  EXPECT_NEAR(d_->qvel[dof_[1]], kSpeedMax, 1e-9);
}

TEST_F(MobileXr4000DriveTest, CommandsBeyondTheLimitsAreClipped) {
  d_->ctrl[act_[0]] = 3.0;
  d_->ctrl[act_[1]] = -3.0;
  d_->ctrl[act_[2]] = 5.0;
  double max_speed = 0, max_rate = 0;
  for (int k = 0; k < 4000; ++k) {
    mj_step(m_, d_);
    max_speed = std::max({max_speed, std::abs(d_->qvel[dof_[0]]), std::abs(d_->qvel[dof_[1]])});
    max_rate = std::max(max_rate, std::abs(d_->qvel[dof_[2]]));
  }
  std::cout << "commands 3 m/s, -3 m/s, 5 rad/s: largest speed " << max_speed << " m/s, yaw rate " << max_rate
            << " rad/s\n";
  EXPECT_LE(max_speed, kSpeedMax * (1 + 1e-9));
  EXPECT_LE(max_rate, kYawRateMax * (1 + 1e-9));
  EXPECT_NEAR(d_->qvel[dof_[0]], kSpeedMax, 1e-9);
  EXPECT_NEAR(d_->qvel[dof_[1]], -kSpeedMax, 1e-9);
  EXPECT_NEAR(d_->qvel[dof_[2]], kYawRateMax, 1e-9);
  // the drive effort never exceeded its limits
  for (int i = 0; i < 3; ++i) {
    EXPECT_LE(std::abs(d_->actuator_force[act_[i]]), (i < 2 ? kForceMax : kTorqueMax) * (1 + 1e-12));
  }
}

TEST_F(MobileXr4000DriveTest, PureSidewaysCommandMovesSidewaysWithoutYaw) {
  // 2 s at 0.5 m/s in y, then stop
  d_->ctrl[act_[1]] = 0.5;
  for (int k = 0; k < 2000; ++k) mj_step(m_, d_);
  d_->ctrl[act_[1]] = 0;
  for (int k = 0; k < 1000; ++k) mj_step(m_, d_);
  const mjtNum* q = d_->qpos;
  // distance: 0.5 m/s for 2 s; what the start-up (force-limited ramp, then first order)
  // loses against the command, the stop gives back, as its response is the mirror image
  std::cout << "pure vy: x " << q[0] << " m, y " << q[1] << " m, yaw " << q[2] << " rad\n";
  EXPECT_EQ(q[0], 0.0);
  EXPECT_EQ(q[2], 0.0);
  EXPECT_NEAR(q[1], 1.0, 1e-3);
}

}  // namespace
}  // namespace vlab::testing
