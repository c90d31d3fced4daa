// The yo-yo simulator's core (src/yoyosim/yoyosim.h) against closed forms: the hand's
// servo as a linear second-order system, the yo-yo's descent a = g m r^2 / (m r^2 + J)
// (DATASHEET §6.3), and in the moving hand's frame g replaced by g + a_hand.
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "core/core_errors.h"
#include "mujoco_fixture.h"
#include "yoyosim/yoyosim.h"

namespace vlab::yoyosim {
namespace {

constexpr const char* kScene = VLAB_SOURCE_DIR "/mjcf/yoyo/yoyo_moving_hand.xml";

std::string Text(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3g", value);
  return text;
}

/// The hand's x servo as the compiled model has it: M x'' + c x' + k x = k u.
struct Servo {
  double mass = 0, damping = 0, stiffness = 0;
  /// Response at t to a set-point that ramps from 0 to 1 over [0, T], then holds:
  /// (R(t) - R(t - T)) / T, R = the unit-ramp response, from the poles p1, p2.
  double RampStep(double t, double T) const { return (Ramp(t) - (t > T ? Ramp(t - T) : 0.0)) / T; }
  double Ramp(double t) const {
    using C = std::complex<double>;
    const C disc = std::sqrt(C(damping * damping - 4 * mass * stiffness, 0));
    const C p1 = (-damping + disc) / (2 * mass), p2 = (-damping - disc) / (2 * mass);
    const C r = t + (p2 * (std::exp(p1 * t) - 1.0) / p1 - p1 * (std::exp(p2 * t) - 1.0) / p2) / (p1 - p2);
    return r.real();
  }
};

class YoyoSimTest : public vlab::test::MujocoTest {
 protected:
  void SetUp() override {
    SimConfig config;
    config.scene = kScene;
    sim_ = YoyoSim::Create(config);
    WatchData(sim_->data());
    const mjModel* m = sim_->model();
    const int drop = mj_name2id(m, mjOBJ_JOINT, "yoyo_drop");
    drop_dof_ = m->jnt_dofadr[drop];
    drop_qpos_ = m->jnt_qposadr[drop];
    const YoyoParams& y = sim_->yoyo();
    share_ = y.mass * y.axle_radius * y.axle_radius /
             (y.mass * y.axle_radius * y.axle_radius + y.spin_inertia);  // a / g on a taut string
  }
  /// Runs n periods, each with the set-point `at(t_end)` of the period's end (world).
  template <typename At>
  void Run(int n, At at) {
    for (int i = 0; i < n; ++i) {
      const Vec3 target = at(sim_->time() + sim_->period_s());
      ASSERT_TRUE(sim_->SetTarget(target.data()));
      ASSERT_TRUE(sim_->Step());
    }
  }
  double Drop() const { return sim_->data()->qvel[drop_dof_]; }  // d', m/s (downward, hand frame)

  std::unique_ptr<YoyoSim> sim_;
  std::unique_ptr<YoyoSim> first_sim_;  // a test's first simulator, watched (WatchData) until TearDown
  int drop_dof_ = -1, drop_qpos_ = -1;
  double share_ = 0;
  double point_[7] = {}, yoyo_[7] = {};
};

TEST_F(YoyoSimTest, ReadsTheSceneContract) {
  const YoyoParams& y = sim_->yoyo();
  EXPECT_DOUBLE_EQ(y.mass, 0.05);
  EXPECT_NEAR(y.spin_inertia, 3.0625e-5, 1e-12);
  EXPECT_NEAR(y.axle_radius, 0.008, 1e-15);
  EXPECT_DOUBLE_EQ(y.string_length, 1.0);
  for (int i = 0; i < 3; ++i) {
    EXPECT_DOUBLE_EQ(sim_->start()[i], i == 2 ? 1.5 : 0.0);
    EXPECT_DOUBLE_EQ(sim_->workspace_max()[i] - sim_->start()[i], 0.5);
    EXPECT_DOUBLE_EQ(sim_->workspace_min()[i] - sim_->start()[i], -0.5);
  }
  sim_->SamplePoint(point_);
  EXPECT_EQ(point_[0], 1.0) << "holding before the first set-point";
  sim_->SampleYoyo(yoyo_);
  EXPECT_NEAR(yoyo_[3], 1.5 - 0.0449558333, 1e-12) << "centre d0 below the hand";
}

TEST_F(YoyoSimTest, RefusesBadPeriodsScenesAndTargets) {
  SimConfig config;
  config.scene = kScene;
  config.period_s = 0.0015;
  try {
    YoyoSim::Create(config);
    ADD_FAILURE() << "a period of 1.5 timesteps was taken";
  } catch (const vlab::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--period 0.0015 s"), std::string::npos) << e.what();
  }
  config.scene = "no/such/scene.xml";
  try {
    YoyoSim::Create(config);
    ADD_FAILURE() << "a missing scene was loaded";
  } catch (const vlab::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("scene 'no/such/scene.xml'"), std::string::npos) << e.what();
  }
  const double outside[3] = {0.0, 0.0, 2.0 + 1e-9}, nan[3] = {0.0, std::nan(""), 1.5};
  EXPECT_FALSE(sim_->SetTarget(outside));
  EXPECT_FALSE(sim_->SetTarget(nan));
  EXPECT_DOUBLE_EQ(sim_->target()[2], 1.5);
}

// a 5 cm set-point step in x (moved over one period by the interpolator) against the
// closed-form response of M x'' + c x' + k x = k u, and against the same servo stepped by
// an independent semi-implicit Euler (MuJoCo's integrator); the yo-yo rides along in x
TEST_F(YoyoSimTest, HandFollowsTheSetPointAsItsServo) {
  const mjModel* m = sim_->model();
  const int hand = mj_name2id(m, mjOBJ_BODY, "hand");
  const int servo = mj_name2id(m, mjOBJ_ACTUATOR, "hand_x_servo");
  const Servo s{m->body_subtreemass[hand], -m->actuator_biasprm[mjNBIAS * servo + 2],
                m->actuator_gainprm[mjNGAIN * servo]};
  const double step = 0.05, T = sim_->period_s(), h = m->opt.timestep;
  const int n = static_cast<int>(std::lround(T / h));
  double x = 0, v = 0, worst_continuous = 0, worst_euler = 0;
  for (int i = 1; i <= 40; ++i) {
    const Vec3 target{step, 0.0, 1.5};
    ASSERT_TRUE(sim_->SetTarget(target.data()));
    ASSERT_TRUE(sim_->Step());
    for (int j = 1; j <= n; ++j) {  // v(n+1) = v + h a(x, v), x(n+1) = x + h v(n+1)
      const double u = i == 1 ? step * j / n : step;
      v += h * (s.stiffness * (u - x) - s.damping * v) / s.mass;
      x += h * v;
    }
    sim_->SamplePoint(point_);
    worst_continuous = std::max(worst_continuous, std::abs(point_[1] - step * s.RampStep(i * T, T)));
    worst_euler = std::max(worst_euler, std::abs(point_[1] - x));
    EXPECT_EQ(point_[0], 0.0) << "not holding once commanded";
  }
  RecordProperty("servo_error_vs_continuous_m", Text(worst_continuous));
  RecordProperty("servo_error_vs_euler_m", Text(worst_euler));
  EXPECT_LT(worst_euler, 1e-12) << "the same discrete servo";
  EXPECT_LT(worst_continuous, 0.08 * step) << "the 1 ms Euler step's error against the continuous servo";
  EXPECT_NEAR(point_[1], step, 1e-6) << "x carries no load: no steady error";
  EXPECT_NEAR(point_[4], 0.0, 1e-4);
  EXPECT_NEAR(point_[2], 0.0, 1e-12) << "y untouched";
}

TEST_F(YoyoSimTest, YoyoFallsWithTheClosedFormWhileTheHandIsStill) {
  const YoyoParams& y = sim_->yoyo();
  for (int i = 0; i < 20; ++i) ASSERT_TRUE(sim_->Step());  // the hand's 18 um sag settles
  sim_->SampleYoyo(yoyo_);
  const double t1 = sim_->time(), vz1 = yoyo_[4];
  for (int i = 0; i < 80; ++i) ASSERT_TRUE(sim_->Step());
  sim_->SampleYoyo(yoyo_);
  const double a = -(yoyo_[4] - vz1) / (sim_->time() - t1);
  RecordProperty("descent_relative_error", Text(a / (y.gravity * share_) - 1));
  EXPECT_NEAR(a, y.gravity * share_, 1e-7 * y.gravity * share_) << "a = g m r^2 / (m r^2 + J)";
  const double tension = y.mass * y.gravity * (1 - share_);  // T = m g J / (J + m r^2)
  EXPECT_NEAR(yoyo_[5], tension, 1e-4 * tension);
  EXPECT_NEAR(yoyo_[6], yoyo_[4] / y.axle_radius, 1e-12 * std::abs(yoyo_[6])) << "theta' = -d' / r while unwinding";
  sim_->SamplePoint(point_);
  EXPECT_NEAR(point_[3] - yoyo_[3], sim_->data()->qpos[drop_qpos_], 1e-12) << "the centre lies d below the hand";
}

// constant upward speed: no hand acceleration, so the descent in the hand's frame is
// the still hand's; the world velocity is the hand's minus d'
TEST_F(YoyoSimTest, HandMovingUpAtConstantSpeedLeavesTheRelativeDescent) {
  const double v = 0.5;
  Run(20, [&](double t) { return Vec3{0.0, 0.0, 1.5 + v * t}; });
  const double t1 = sim_->time(), d1 = Drop();
  Run(60, [&](double t) { return Vec3{0.0, 0.0, 1.5 + v * t}; });
  const double g = sim_->yoyo().gravity;
  EXPECT_NEAR((Drop() - d1) / (sim_->time() - t1), g * share_, 1e-6 * g * share_);
  sim_->SamplePoint(point_);
  sim_->SampleYoyo(yoyo_);
  EXPECT_NEAR(point_[6], v, 1e-6) << "the hand moves at the commanded speed";
  EXPECT_NEAR(yoyo_[4], point_[6] - Drop(), 1e-9) << "vz of the yo-yo = v_hand - d'";
}

// constant upward acceleration a_h: in the hand's frame the yo-yo falls as under g + a_h;
// measured as velocity changes over the same window, so that the servo's ripple cancels
TEST_F(YoyoSimTest, HandAcceleratingUpAddsItsAccelerationToGravity) {
  const double a_hand = 3.0;
  auto at = [&](double t) { return Vec3{0.0, 0.0, 1.5 + 0.5 * a_hand * t * t}; };
  Run(20, at);
  sim_->SamplePoint(point_);
  const double t1 = sim_->time(), d1 = Drop(), vh1 = point_[6];
  Run(30, at);
  sim_->SamplePoint(point_);
  const double dt = sim_->time() - t1;
  const double a_measured = (point_[6] - vh1) / dt;
  EXPECT_NEAR(a_measured, a_hand, 0.01 * a_hand) << "the hand accelerates as commanded";
  const double g = sim_->yoyo().gravity;
  const double expected = (g + a_measured) * share_;
  RecordProperty("g_plus_a_relative_error", Text((Drop() - d1) / dt / expected - 1));
  EXPECT_NEAR((Drop() - d1) / dt, expected, 1e-7 * expected) << "d'' = (g + a_hand) m r^2 / (m r^2 + J)";
  EXPECT_GT(expected, g * share_ * 1.25) << "and that is faster than under a still hand";
}

TEST_F(YoyoSimTest, HoldKeepsTheHandWhereItIs) {
  Run(10, [&](double t) { return Vec3{0.2 * t, 0.0, 1.5}; });
  sim_->Hold();
  sim_->SamplePoint(point_);
  EXPECT_EQ(point_[0], 1.0) << "holding";
  const double x = point_[1];
  for (int i = 0; i < 50; ++i) ASSERT_TRUE(sim_->Step());
  sim_->SamplePoint(point_);
  EXPECT_NEAR(point_[1], x, 1e-9);
  EXPECT_DOUBLE_EQ(sim_->target()[0], x);
}

TEST_F(YoyoSimTest, SameCommandsGiveTheSameStatesBitForBit) {
  auto at = [](double t) { return Vec3{0.05 * std::sin(3 * t), 0.0, 1.5 + 0.1 * std::sin(5 * t)}; };
  Run(150, at);
  sim_->SampleYoyo(yoyo_);
  double first[7];
  std::copy(yoyo_, yoyo_ + 7, first);
  first_sim_ = std::move(sim_);
  SetUp();
  Run(150, at);
  sim_->SampleYoyo(yoyo_);
  for (int i = 0; i < 7; ++i) EXPECT_EQ(yoyo_[i], first[i]) << "value " << i;
}

}  // namespace
}  // namespace vlab::yoyosim
