// The parallel gripper's drive and force sensing (mjcf/gripper, scenes/pa10_gripper.xml).
//
// Drive: free closing runs at the force-speed line's speed 2 F_max / c; the opening servo
// settles on its set-point with both jaws symmetric. Force sensing: the pad touch sensors
// read the grip force the drive applies (kp (opening - set-point) in position mode, the
// commanded force in force mode).
#include <algorithm>
#include <cmath>
#include <iostream>

#include <gtest/gtest.h>

#include "mobile/gripper_fixture.h"

namespace vlab::testing {
namespace {

TEST_F(MobileGripperTest, FreeClosingRunsAtTheDriveSpeed) {
  HoldArm(0.2);
  d_->ctrl[act_servo_] = 0;
  double peak_rate = 0, max_asymmetry = 0;
  for (int i = 0; i < 2500; ++i) {
    HoldArm(0.001);
    peak_rate = std::max(peak_rate, -d_->sensordata[opening_vel_]);
    max_asymmetry = std::max(max_asymmetry, std::abs(d_->qpos[q_left_] - d_->qpos[q_right_]));
  }
  // saturated drive against the jaw damping: each jaw moves at F_max / c, the opening at twice that
  const double expected = 2 * kMaxForce / kJawDamping;
  std::cout << "free closing: peak opening rate " << peak_rate * 1e3 << " mm/s (expected " << expected * 1e3
            << "), final opening " << Opening() * 1e3 << " mm, jaw asymmetry " << max_asymmetry * 1e3 << " mm\n";
  EXPECT_NEAR(peak_rate, expected, 0.01 * expected);
  EXPECT_LT(Opening(), 5e-5);
  EXPECT_LT(max_asymmetry, 1e-6);
}

TEST_F(MobileGripperTest, OpeningServoSettlesOnItsSetPoint) {
  HoldArm(0.2);
  d_->ctrl[act_servo_] = 0.03;
  HoldArm(2.5);
  std::cout << "opening servo: set-point 30 mm, reached " << Opening() * 1e3 << " mm\n";
  EXPECT_NEAR(Opening(), 0.03, 1e-4);
  EXPECT_NEAR(d_->qpos[q_left_], d_->qpos[q_right_], 5e-5);
}

TEST_F(MobileGripperTest, PadsReadTheGripForceInPositionMode) {
  // close on the cube standing on the table, without lifting it
  const double set_point = kCubeEdge - 0.008;
  control::JointTrajectoryConfig path;
  path.waypoints = {q_above_, q_grasp_, q_grasp_};
  path.segments = {{1.5, {}}, {1.0, {}}};
  auto trajectory = control::JointTrajectory::Create(path);
  control::JointSample s;
  for (int k = 0; k <= 2500; ++k) {
    trajectory->Evaluate(k * 0.001, &s);
    d_->ctrl[act_servo_] = k < 1600 ? kOpen : set_point;
    Step(s);
  }
  const double grip = kServoKp * (Opening() - set_point);  // the servo's force law
  const double left = d_->sensordata[touch_left_], right = d_->sensordata[touch_right_];
  std::cout << "position-mode grip: servo law " << grip << " N, servo sensor " << -d_->sensordata[servo_force_]
            << " N, pads " << left << " / " << right << " N, opening " << Opening() * 1e3 << " mm\n";
  EXPECT_NEAR(-d_->sensordata[servo_force_], grip, 1e-6 * grip);
  EXPECT_GT(grip, 70.0);
  EXPECT_NEAR(left, grip, 0.03 * grip);
  EXPECT_NEAR(right, grip, 0.03 * grip);
  // the pads squeeze the wood by less than 1 mm each
  EXPECT_GT(Opening(), kCubeEdge - 0.002);
}

TEST_F(MobileGripperTest, PadsReadTheCommandedForceInForceMode) {
  control::JointTrajectoryConfig path;
  path.waypoints = {q_above_, q_grasp_, q_grasp_};
  path.segments = {{1.5, {}}, {1.0, {}}};
  auto trajectory = control::JointTrajectory::Create(path);
  control::JointSample s;
  const double force = 40;
  for (int k = 0; k <= 2500; ++k) {
    trajectory->Evaluate(k * 0.001, &s);
    Drive(k < 1600 ? GripMode::kOpenOnly : GripMode::kForce, force);
    Step(s);
  }
  const double left = d_->sensordata[touch_left_], right = d_->sensordata[touch_right_];
  std::cout << "force-mode grip: commanded " << force << " N, pads " << left << " / " << right << " N\n";
  EXPECT_NEAR(left, force, 0.03 * force);
  EXPECT_NEAR(right, force, 0.03 * force);
}

}  // namespace
}  // namespace vlab::testing
