// KinArm (src/kinsim/kinsim.cc) and ArmFromScene (kinsim_scene.cc), no sockets:
// every expectation is a closed form of the kinematic integration.
#include "kinsim/kinsim.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "core/core_errors.h"
#include "kinsim/kinsim_scene.h"

namespace vlab::kinsim {
namespace {

using bridge::ArmCommandMsg;
using bridge::ArmStateMsg;

constexpr double kDt = 0.002;

// three joints: limits ±1, ±2, ±3 rad; velocity limits 1, 2, 0.5 rad/s
KinArmConfig ThreeJoints() {
  KinArmConfig c;
  c.name = "test_arm";
  c.joints = {"a", "b", "c"};
  c.position_min = {-1, -2, -3};
  c.position_max = {1, 2, 3};
  c.velocity_max = {1, 2, 0.5};
  c.initial = {0, 0.5, -1};
  return c;
}

ArmCommandMsg Cmd(ArmMode mode, std::vector<double> value) {
  ArmCommandMsg c;
  c.mode = static_cast<int>(mode);
  c.value = std::move(value);
  return c;
}

void StepN(KinArm& arm, int n, double dt = kDt) {
  for (int i = 0; i < n; ++i) arm.Step(dt);
}

TEST(KinArmTest, HoldsTheInitialPoseUntilTheFirstCommand) {
  auto arm = KinArm::Create(ThreeJoints());
  EXPECT_EQ(arm->mode(), ArmMode::kHold);
  EXPECT_TRUE(arm->status() & bridge::kStatusHolding);
  StepN(*arm, 100);
  EXPECT_EQ(arm->q(), (std::vector<double>{0, 0.5, -1}));
  EXPECT_EQ(arm->qd(), (std::vector<double>{0, 0, 0}));
}

TEST(KinArmTest, VelocityIntegratesExactly) {
  auto arm = KinArm::Create(ThreeJoints());
  const std::vector<double> v = {0.5, -0.25, 0.1};
  ASSERT_TRUE(arm->Command(Cmd(ArmMode::kVelocity, v)));
  const int steps = 400;  // 0.8 s, no joint reaches a limit
  StepN(*arm, steps);
  const double t = steps * kDt;
  const std::vector<double> q0 = ThreeJoints().initial;
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(arm->q()[i], q0[i] + v[i] * t, 1e-12) << "joint " << i;
    EXPECT_EQ(arm->qd()[i], v[i]) << "joint " << i;  // the applied velocity is the command, bit for bit
  }
  EXPECT_EQ(arm->status(), 0u);  // moving, nothing refused, no joint at a limit

  ArmStateMsg s;
  arm->Sample(&s);
  EXPECT_EQ(s.q, arm->q());
  EXPECT_EQ(s.qd, v);
  EXPECT_EQ(s.tau, (std::vector<double>{0, 0, 0}));  // no dynamics: tau reported as 0
}

TEST(KinArmTest, VelocityClampsAtTheLimitsWithTheAtLimitBit) {
  auto arm = KinArm::Create(ThreeJoints());
  // joint a: 0 -> +1 rad at 1 rad/s reaches its limit after 1 s; joint c: -1 -> -3 at 0.5 rad/s after 4 s
  ASSERT_TRUE(arm->Command(Cmd(ArmMode::kVelocity, {1.0, 0.0, -0.5})));
  StepN(*arm, 400);  // 0.8 s
  EXPECT_FALSE(arm->status() & bridge::kStatusAtLimit);
  StepN(*arm, 200);  // 1.2 s: joint a clamped
  EXPECT_EQ(arm->q()[0], 1.0);
  EXPECT_EQ(arm->qd()[0], 0.0);  // the velocity actually applied
  EXPECT_EQ(arm->qd()[2], -0.5);
  EXPECT_TRUE(arm->status() & bridge::kStatusAtLimit);
  StepN(*arm, 2000);  // 5.2 s: joint c clamped at its lower limit too
  EXPECT_EQ(arm->q()[0], 1.0);
  EXPECT_EQ(arm->q()[2], -3.0);
  EXPECT_EQ(arm->qd()[2], 0.0);
  EXPECT_EQ(arm->q()[1], 0.5);

  // the step that reaches the limit applies only the distance that was left
  auto arm2 = KinArm::Create(ThreeJoints());
  ASSERT_TRUE(arm2->Command(Cmd(ArmMode::kVelocity, {1.0, 0, 0})));
  arm2->Step(0.9);
  arm2->Step(0.2);
  EXPECT_EQ(arm2->q()[0], 1.0);
  EXPECT_NEAR(arm2->qd()[0], 0.1 / 0.2, 1e-12);

  // leaving the limit clears the bit
  ASSERT_TRUE(arm->Command(Cmd(ArmMode::kVelocity, {-1.0, 0, 0.5})));
  arm->Step(kDt);
  EXPECT_EQ(arm->q()[0], 1.0 - kDt);
  EXPECT_FALSE(arm->status() & bridge::kStatusAtLimit);
}

TEST(KinArmTest, PositionIsRateLimitedAndConvergesExactly) {
  auto arm = KinArm::Create(ThreeJoints());
  const std::vector<double> q0 = ThreeJoints().initial;
  const std::vector<double> target = {0.7, -1.5, 0.3};  // distances 0.7, 2.0, 1.3 rad
  ASSERT_TRUE(arm->Command(Cmd(ArmMode::kPosition, target)));
  const std::vector<double> vmax = ThreeJoints().velocity_max;
  const double times[3] = {0.7 / 1.0, 2.0 / 2.0, 1.3 / 0.5};  // each joint's travel time at its limit
  for (int k = 1; k <= 2000; ++k) {
    const std::vector<double> before = arm->q();
    arm->Step(kDt);
    const double t = k * kDt;
    for (int i = 0; i < 3; ++i) {
      // never faster than the velocity limit; at the limit until the target is reached
      EXPECT_LE(std::abs(arm->q()[i] - before[i]), vmax[i] * kDt * (1 + 1e-12));
      if (t < times[i] - kDt) {
        EXPECT_NEAR(std::abs(arm->qd()[i]), vmax[i], 1e-9) << "joint " << i << " at " << t;
        EXPECT_NEAR(arm->q()[i], q0[i] + std::copysign(vmax[i] * t, target[i] - q0[i]), 1e-9);
      }
    }
  }
  // 4 s later every joint sits exactly on its target
  EXPECT_EQ(arm->q(), target);
  EXPECT_EQ(arm->qd(), (std::vector<double>{0, 0, 0}));
  EXPECT_EQ(arm->status(), 0u);
}

TEST(KinArmTest, TorqueIsRefusedAndThePreviousCommandStays) {
  auto arm = KinArm::Create(ThreeJoints());
  ASSERT_TRUE(arm->Command(Cmd(ArmMode::kVelocity, {0.2, 0, 0})));
  StepN(*arm, 10);
  EXPECT_FALSE(arm->Command(Cmd(ArmMode::kTorque, {1, 2, 3})));
  EXPECT_EQ(arm->refused(), 1);
  EXPECT_EQ(arm->refused_torque(), 1);
  EXPECT_TRUE(arm->status() & bridge::kStatusRefused);
  EXPECT_EQ(arm->mode(), ArmMode::kVelocity);
  const double q = arm->q()[0];
  arm->Step(kDt);
  EXPECT_EQ(arm->q()[0], q + 0.2 * kDt);  // still the velocity command
  ArmStateMsg s;
  arm->Sample(&s);
  EXPECT_EQ(s.tau, (std::vector<double>{0, 0, 0}));
  // the next applied command clears the refused bit
  ASSERT_TRUE(arm->Command(Cmd(ArmMode::kHold, {0, 0, 0})));
  EXPECT_FALSE(arm->status() & bridge::kStatusRefused);
}

TEST(KinArmTest, InvalidCommandsAreRefusedToo) {
  auto arm = KinArm::Create(ThreeJoints());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(arm->Command(Cmd(ArmMode::kVelocity, {nan, 0, 0})));
  EXPECT_FALSE(arm->Command(Cmd(ArmMode::kVelocity, {1.5, 0, 0})));  // beyond 1 rad/s
  EXPECT_FALSE(arm->Command(Cmd(ArmMode::kPosition, {0, 2.5, 0})));  // beyond 2 rad
  EXPECT_FALSE(arm->Command(Cmd(ArmMode::kVelocity, {0, 0})));       // wrong size
  EXPECT_EQ(arm->refused(), 4);
  EXPECT_EQ(arm->refused_torque(), 0);
  EXPECT_EQ(arm->mode(), ArmMode::kHold);
  EXPECT_EQ(arm->status(), bridge::kStatusHolding | bridge::kStatusRefused);
}

TEST(KinArmTest, HoldStopsWhereTheArmIs) {
  auto arm = KinArm::Create(ThreeJoints());
  ASSERT_TRUE(arm->Command(Cmd(ArmMode::kVelocity, {0.5, 0.5, 0.5})));
  StepN(*arm, 50);
  ASSERT_TRUE(arm->Command(Cmd(ArmMode::kHold, {9, 9, 9})));  // hold ignores its values
  const std::vector<double> q = arm->q();
  StepN(*arm, 50);
  EXPECT_EQ(arm->q(), q);
  EXPECT_EQ(arm->qd(), (std::vector<double>{0, 0, 0}));
  EXPECT_TRUE(arm->status() & bridge::kStatusHolding);

  // Hold() (the watchdog) does the same to a moving arm
  ASSERT_TRUE(arm->Command(Cmd(ArmMode::kVelocity, {-0.5, 0, 0})));
  StepN(*arm, 5);
  arm->Hold();
  const std::vector<double> q2 = arm->q();
  StepN(*arm, 5);
  EXPECT_EQ(arm->q(), q2);
  EXPECT_TRUE(arm->status() & bridge::kStatusHolding);
}

TEST(KinArmTest, CreateNamesTheBadField) {
  auto expect_error = [](KinArmConfig c, const std::string& part) {
    try {
      KinArm::Create(c);
      ADD_FAILURE() << "no error, expected '" << part << "'";
    } catch (const vlab::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  };
  KinArmConfig c = ThreeJoints();
  c.initial = {0, 0};
  expect_error(c, "arm 'test_arm': initial has 2 values for 3 joints");
  c = ThreeJoints();
  c.initial[2] = 3.5;
  expect_error(c, "joint 'c': initial position 3.5 rad is outside [-3, 3]");
  c = ThreeJoints();
  c.velocity_max[1] = 0;
  expect_error(c, "joint 'b': velocity limit 0 rad/s is not > 0");
  c = ThreeJoints();
  c.position_max[0] = -2;
  expect_error(c, "joint 'a': position limits");
  c = ThreeJoints();
  c.joints[2] = "a";
  expect_error(c, "joint 'a' is listed twice");
  c = ThreeJoints();
  c.joints.clear();
  expect_error(c, "no joints");
}

TEST(KinsimSceneTest, ReadsThePa10JointsAndRanges) {
  const std::string scene = VLAB_SOURCE_DIR "/scenes/pa10.xml";
  const KinArmConfig c = ArmFromScene("pa10", scene, Pa10Joints(), {kPa10VelocityMax}, Pa10ReadyPose());
  ASSERT_EQ(c.joints.size(), 7u);
  // mjcf/pa10/pa10.xml ranges, degrees: S1 ±177, S2 ±94, S3 ±174, E1 ±137, E2 ±255, W1 ±165, W2 ±255
  const double degrees[7] = {177, 94, 174, 137, 255, 165, 255};
  for (int i = 0; i < 7; ++i) {
    EXPECT_NEAR(c.position_max[i], degrees[i] * M_PI / 180, 1e-9) << c.joints[i];
    EXPECT_NEAR(c.position_min[i], -degrees[i] * M_PI / 180, 1e-9) << c.joints[i];
    EXPECT_EQ(c.velocity_max[i], M_PI);
  }
  EXPECT_NO_THROW(KinArm::Create(c));

  try {
    ArmFromScene("pa10", scene, {"S1", "elbow"}, {1.0}, {0, 0});
    ADD_FAILURE() << "no error for an unknown joint";
  } catch (const vlab::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no joint 'elbow'"), std::string::npos) << e.what();
  }
  try {
    ArmFromScene("pa10", "no/such/scene.xml", Pa10Joints(), {1.0}, Pa10ReadyPose());
    ADD_FAILURE() << "no error for a missing scene";
  } catch (const vlab::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("scene 'no/such/scene.xml'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace vlab::kinsim
