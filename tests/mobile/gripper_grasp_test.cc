// Grasping by contact with friction (mjcf/gripper on the PA10, scenes/pa10_gripper.xml).
//
// The arm, under joint PD + gravity compensation (src/control) along a quintic joint path,
// closes the gripper on a 5 cm beech cube on the table, lifts it 0.15 m and carries it 0.3 m
// sideways; the cube must not slip in the fingers by 2 mm or more and must never drop, in
// position mode and in force mode. Coulomb's limit decides: a grip below m g / (2 mu) lets
// the cube slide out, one above it holds. The same motion with the gripper left open leaves
// the cube where it was (the control case). The weld mount stays rigid and the JR3 reads the
// weight of everything beyond it.
#include <iostream>
#include <string>

#include <gtest/gtest.h>

#include "mobile/gripper_fixture.h"

namespace vlab::testing {
namespace {

// min_pad_force: the grip force the pads must keep feeling all the way, N
void ExpectCarried(const CarryResult& r, const std::string& what, double min_pad_force) {
  std::cout << what << ": slip " << r.slip_m * 1e3 << " mm / " << r.slip_rad * 1e3 << " mrad, pad force min "
            << r.min_touch_n << " N, cube lifted " << r.max_lift_m * 1e3 << " mm, end cube-TCP "
            << (r.cube_end - r.tcp_end).norm() * 1e3 << " mm, mount error " << r.mount_error_m * 1e3 << " mm / "
            << r.mount_error_rad * 1e3 << " mrad, JR3 |F| " << r.jr3_force_end.norm() << " N\n";
  EXPECT_LT(r.slip_m, 0.002);
  EXPECT_GT(r.min_touch_n, min_pad_force) << "the cube left a pad";
  // lifted and carried: it ends 0.15 m up and 0.3 m to the side, between the pads
  const Eigen::Vector3d goal = kCubeStart + Eigen::Vector3d(0, 0.30, 0.15);
  EXPECT_LT((r.cube_end - goal).norm(), 0.003);
  EXPECT_LT((r.cube_end - r.tcp_end).norm(), 0.002);
  // the weld mount is rigid, and the JR3 carries the sensor's tool half, the tool, the gripper and the cube
  EXPECT_LT(r.mount_error_m, 1e-4);
  EXPECT_LT(r.mount_error_rad, 1e-3);
  const double beyond_jr3 = 0.085 + 0.3416 + 1.4 + kCubeMass;
  EXPECT_NEAR(r.jr3_force_end.norm(), beyond_jr3 * 9.81, 0.01 * beyond_jr3 * 9.81);
}

TEST_F(MobileGripperTest, PositionModeGraspLiftsAndCarriesTheCubeWithoutSlip) {
  const CarryResult r = PickAndCarry(GripMode::kPosition, kCubeEdge - 0.008);
  ExpectCarried(r, "position-mode carry", 50.0);
  EXPECT_NEAR(r.grip_force_end, r.touch_left_end, 0.05 * r.grip_force_end);
}

TEST_F(MobileGripperTest, ForceModeGraspLiftsAndCarriesTheCubeWithoutSlip) {
  const CarryResult r = PickAndCarry(GripMode::kForce, 40.0);
  ExpectCarried(r, "force-mode carry", 0.95 * 40.0);
  EXPECT_NEAR(r.touch_left_end, 40.0, 2.0);
}

// Coulomb friction decides: two pads with friction mu hold a cube of weight m g when the grip
// force F satisfies 2 mu F >= m g, i.e. F >= 0.44 N here (pad-cube friction 1.0, the pads'
// value by their contact priority).
TEST_F(MobileGripperTest, GripBelowTheFrictionLimitLetsTheCubeSlipOut) {
  const double limit = kCubeMass * 9.81 / (2 * 1.0);
  const CarryResult r = PickAndCarry(GripMode::kForce, 0.6 * limit);
  std::cout << "grip " << 0.6 * limit << " N (friction limit " << limit << " N): cube ends "
            << (r.cube_end - r.tcp_end).norm() * 1e3 << " mm from the TCP, " << (r.cube_end.z() - kCubeStart.z()) * 1e3
            << " mm above its start\n";
  EXPECT_GT((r.cube_end - r.tcp_end).norm(), 0.1);
  EXPECT_LT(r.cube_end.z() - kCubeStart.z(), 0.01);
}

TEST_F(MobileGripperTest, GripAboveTheFrictionLimitHolds) {
  const double limit = kCubeMass * 9.81 / (2 * 1.0);
  const CarryResult r = PickAndCarry(GripMode::kForce, 2.5 * limit);
  ExpectCarried(r, "grip " + std::to_string(2.5 * limit) + " N carry", 0.95 * 2.5 * limit);
}

TEST_F(MobileGripperTest, OpenGripperLeavesTheCubeOnTheTable) {
  const Eigen::Vector3d start = BodyPos(cube_);
  const CarryResult r = PickAndCarry(GripMode::kOpenOnly, 0);
  std::cout << "open gripper: cube moved " << (r.cube_end - start).norm() * 1e3 << " mm, rose " << r.max_lift_m * 1e3
            << " mm, largest pad force " << r.max_touch_n << " N\n";
  EXPECT_LT((r.cube_end - start).norm(), 0.001);
  EXPECT_LT(r.max_lift_m, 0.001);
  EXPECT_LT(r.max_touch_n, 0.01);
  // and the gripper did go there and come away
  EXPECT_GT((r.tcp_end - r.cube_end).norm(), 0.3);
}

}  // namespace
}  // namespace vlab::testing
