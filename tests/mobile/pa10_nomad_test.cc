// The PA10 on the Nomad XR4000 (scenes/pa10_nomad.xml).
//
// Holding: the base drives 1 m (quintic profile, odometry feedback on its velocity servo)
// while the arm holds its joint pose under joint PD + bias compensation from src/control
// (RobotModel, JointPdGravityTorque); the tool pose relative to the arm's base must stay
// within 1 mm / 1 mrad. The residual swing is the base's acceleration acting through the
// arm-base inertia coupling: feeding M[arm, base] a_base forward must remove it (a check of
// the coupling). Holonomic with a payload: a pure sideways drive moves the base sideways;
// the arm's mass ahead of the yaw axis makes the yaw servo work, and the heading stays
// within bounds.
// Reach (the pa10_nomad_reach scenario): the base drives 2.25 m to the table holding the
// arm, parks without touching the table, then the arm brings the tool tip to the target
// on the table under the task-space controller (src/control).
#include <algorithm>
#include <cmath>
#include <iostream>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <Eigen/Core>

#include "control/task_space.h"
#include "control/time_scaling.h"
#include "control/trajectory.h"
#include "mobile/mobile_scene.h"

namespace vlab::testing {
namespace {

constexpr int kBaseDofs = 3, kArmDofs = 7;
constexpr double kOdometryGain = 5.0;  // 1/s, base position feedback on the velocity command

struct HoldResult {
  double max_position_error_m = 0;  // tool site in the arm's base frame vs its start
  double max_orientation_error_rad = 0;
  double max_yaw_rad = 0;        // base heading
  double max_cross_track_m = 0;  // base motion across the commanded direction
  Eigen::Vector3d base_end = Eigen::Vector3d::Zero();
  int contacts = 0;  // largest contact count seen
};

class MobilePa10NomadTest : public vlab::test::MujocoTest {
 protected:
  void SetUp() override {
    m_ = LoadModel("scenes/pa10_nomad.xml");
    d_ = MakeData(m_);
    mj_resetDataKeyframe(m_, d_, RequireId(m_, mjOBJ_KEY, "ready"));
    mj_forward(m_, d_);
    for (const char* name : {"base_x", "base_y", "base_yaw"}) act_.push_back(RequireId(m_, mjOBJ_ACTUATOR, name));
    arm_base_ = RequireId(m_, mjOBJ_BODY, "pa10_base");
    tool_ = RequireId(m_, mjOBJ_SITE, "tool");
    target_ = RequireId(m_, mjOBJ_SITE, "target");
    full_m_.resize(m_->nv * m_->nv);
  }

  // tool pose in the arm's base frame
  Eigen::Vector3d ToolInBase() const {
    return Mat3(d_->xmat + 9 * arm_base_).transpose() *
           (Vec3(d_->site_xpos + 3 * tool_) - Vec3(d_->xpos + 3 * arm_base_));
  }
  Eigen::Matrix3d ToolRotInBase() const {
    return Mat3(d_->xmat + 9 * arm_base_).transpose() * Mat3(d_->site_xmat + 9 * tool_);
  }

  // the arm torque that carries the base's acceleration: M[arm, base] a_base, with the mass
  // matrix and base acceleration of the last step (what an IMU on the base would give)
  void BaseAccelerationFeedforward(ArmServo* servo) {
    mj_fullM(m_, full_m_.data(), d_->qM);
    Eigen::VectorXd& ff = servo->extra_feedforward();
    for (int i = 0; i < kArmDofs; ++i) {
      ff[i] = 0;
      for (int j = 0; j < kBaseDofs; ++j) ff[i] += full_m_[(kBaseDofs + i) * m_->nv + j] * d_->qacc[j];
    }
  }

  // base velocity command: planned velocity + odometry feedback, world frame
  void DriveBase(const Eigen::Vector3d& pose_d, const Eigen::Vector3d& vel_d) {
    for (int i = 0; i < kBaseDofs; ++i) d_->ctrl[act_[i]] = vel_d[i] + kOdometryGain * (pose_d[i] - d_->qpos[i]);
  }

  // Drives the base by `move` (x, y, yaw) over `seconds` (quintic), then 1 s still, the arm
  // holding its start pose with a `bandwidth_hz` servo.
  HoldResult DriveHolding(const Eigen::Vector3d& move, double seconds, double bandwidth_hz, bool feedforward,
                          bool heading_feedback = true) {
    ArmServo servo(m_, *d_, "pa10_base", "tool", bandwidth_hz, 1.0);
    const Eigen::VectorXd q_hold = servo.model().ChainPositions(*d_);
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(kArmDofs);
    const Eigen::Vector3d start(d_->qpos[0], d_->qpos[1], d_->qpos[2]);
    const Eigen::Vector3d p0 = ToolInBase();
    const Eigen::Matrix3d R0 = ToolRotInBase();
    const control::TimeScaling quintic;
    const Eigen::Vector3d unit =
        move.head<2>().norm() > 0 ? Eigen::Vector3d(move.x(), move.y(), 0).normalized() : Eigen::Vector3d::Zero();
    HoldResult r;
    const int steps = static_cast<int>(std::lround((seconds + 1.0) / m_->opt.timestep));
    for (int k = 0; k < steps; ++k) {
      const control::ScalingSample s = control::EvaluateTimeScaling(quintic, seconds, k * m_->opt.timestep);
      Eigen::Vector3d pose_d = start + s.s * move, vel_d = s.sd * move;
      if (!heading_feedback) {
        pose_d[2] = d_->qpos[2];
        vel_d[2] = 0;
      }
      DriveBase(pose_d, vel_d);
      if (feedforward) BaseAccelerationFeedforward(&servo);
      servo.Command(d_, q_hold, zero, Eigen::VectorXd());
      mj_step(m_, d_);
      r.max_position_error_m = std::max(r.max_position_error_m, (ToolInBase() - p0).norm());
      r.max_orientation_error_rad = std::max(r.max_orientation_error_rad, AngleBetween(ToolRotInBase(), R0));
      r.max_yaw_rad = std::max(r.max_yaw_rad, std::abs(d_->qpos[2] - start[2]));
      const Eigen::Vector3d travelled(d_->qpos[0] - start[0], d_->qpos[1] - start[1], 0);
      r.max_cross_track_m = std::max(r.max_cross_track_m, (travelled - travelled.dot(unit) * unit).norm());
      r.contacts = std::max(r.contacts, d_->ncon);
    }
    r.base_end = Eigen::Vector3d(d_->qpos[0], d_->qpos[1], d_->qpos[2]);
    return r;
  }

  const mjModel* m_ = nullptr;
  mjData* d_ = nullptr;
  std::vector<int> act_;
  int arm_base_ = -1, tool_ = -1, target_ = -1;
  std::vector<mjtNum> full_m_;
};

TEST_F(MobilePa10NomadTest, ArmHoldsToolPoseWhileTheBaseDrivesOneMetre) {
  const HoldResult r = DriveHolding(Eigen::Vector3d(1.0, 0, 0), 3.0, 10.0, false);
  std::cout << "base drives 1 m in 3 s, arm joint PD 10 Hz + bias: tool moved " << r.max_position_error_m * 1e3
            << " mm / " << r.max_orientation_error_rad * 1e3 << " mrad in the arm's base frame; base ends at "
            << r.base_end.transpose() << "\n";
  EXPECT_LT(r.max_position_error_m, 1e-3);
  EXPECT_LT(r.max_orientation_error_rad, 1e-3);
  EXPECT_NEAR(r.base_end.x(), 1.0, 1e-3);
  EXPECT_LT(r.max_cross_track_m, 1e-6);
  EXPECT_EQ(r.contacts, 0);
}

TEST_F(MobilePa10NomadTest, BaseAccelerationFeedforwardCancelsTheCoupling) {
  // what is left of the swing is the base's acceleration acting through M[arm, base]:
  // feeding M[arm, base] a_base forward removes nearly all of it
  const HoldResult plain = DriveHolding(Eigen::Vector3d(1.0, 0, 0), 3.0, 10.0, false);
  mj_resetDataKeyframe(m_, d_, RequireId(m_, mjOBJ_KEY, "ready"));
  mj_forward(m_, d_);
  const HoldResult fed = DriveHolding(Eigen::Vector3d(1.0, 0, 0), 3.0, 10.0, true);
  std::cout << "with M[arm, base] a_base fed forward: tool moved " << fed.max_position_error_m * 1e3 << " mm / "
            << fed.max_orientation_error_rad * 1e3 << " mrad (without: " << plain.max_position_error_m * 1e3
            << " mm)\n";
  EXPECT_LT(fed.max_position_error_m, 0.05 * plain.max_position_error_m);
  EXPECT_LT(fed.max_orientation_error_rad, 0.05 * plain.max_orientation_error_rad);
}

TEST_F(MobilePa10NomadTest, SidewaysDriveWithTheArmStaysOnTrack) {
  // heading left to the base's velocity servo alone: the arm's mass ahead of the yaw axis
  // turns the base while it accelerates sideways, by a bounded amount
  const HoldResult free_heading = DriveHolding(Eigen::Vector3d(0, 1.0, 0), 3.0, 10.0, true, false);
  mj_resetDataKeyframe(m_, d_, RequireId(m_, mjOBJ_KEY, "ready"));
  mj_forward(m_, d_);
  // with odometry feedback on the heading as well
  const HoldResult held = DriveHolding(Eigen::Vector3d(0, 1.0, 0), 3.0, 10.0, true, true);
  std::cout << "pure vy 1 m: heading drift " << free_heading.max_yaw_rad * 1e3 << " mrad (velocity servo only), "
            << held.max_yaw_rad * 1e3 << " mrad (odometry heading feedback); cross-track "
            << held.max_cross_track_m * 1e3 << " mm\n";
  EXPECT_LT(free_heading.max_yaw_rad, 0.02);
  EXPECT_GT(free_heading.max_yaw_rad, 1e-4);  // the coupling exists
  EXPECT_LT(held.max_yaw_rad, 0.005);
  EXPECT_LT(held.max_cross_track_m, 1e-3);
  EXPECT_NEAR(held.base_end.y(), 1.0, 1e-3);
  EXPECT_LT(held.max_position_error_m, 1e-3);
}

// The pa10_nomad_reach scenario: drive 2.25 m to the table (5 s, quintic) with the arm held in
// its ready pose, park 5 cm short of the table edge, then bring the tool tip 5 mm above the
// target, pointing down, along a straight line (3 s, quintic) under the task-space
// controller, whose joint velocity the joint servo integrates and tracks.
TEST_F(MobilePa10NomadTest, ReachScenarioDrivesToTheTableThenReachesTheTarget) {
  const double park_x = 2.25, hover = 0.005;
  const HoldResult drive = DriveHolding(Eigen::Vector3d(park_x, 0, 0), 5.0, 10.0, false);
  std::cout << "drive to the table: base at " << drive.base_end.transpose() << ", tool held to "
            << drive.max_position_error_m * 1e3 << " mm / " << drive.max_orientation_error_rad * 1e3 << " mrad\n";
  EXPECT_NEAR(drive.base_end.x(), park_x, 1e-3);
  EXPECT_LT(drive.max_position_error_m, 1e-3);
  EXPECT_EQ(drive.contacts, 0);

  ArmServo servo(m_, *d_, "pa10_base", "tool", 10.0, 1.0);
  control::RobotModel& arm = servo.model();
  arm.SetState(*d_);
  control::CartesianTrajectoryConfig path;
  control::Pose goal;
  goal.p_W = Vec3(d_->site_xpos + 3 * target_) + Eigen::Vector3d(0, 0, hover);
  goal.R_W = ToolDown();
  path.waypoints = {arm.TipPose(), goal, goal};
  path.segments = {{3.0, {}}, {1.0, {}}};
  auto trajectory = control::CartesianTrajectory::Create(path);
  auto task = control::TaskSpaceController::Create(control::TaskSpaceConfig{}, arm);
  Eigen::VectorXd q_ref = arm.ChainPositions(*d_);
  const Eigen::Vector3d park(d_->qpos[0], d_->qpos[1], d_->qpos[2]);
  double max_tracking = 0;
  int contacts = 0;
  const int steps = static_cast<int>(std::lround(trajectory->duration_s() / m_->opt.timestep));
  for (int k = 0; k <= steps; ++k) {
    const control::CartesianSample s = trajectory->Evaluate(k * m_->opt.timestep);
    control::TaskSpaceTarget target;
    target.pose = s.pose;
    target.v_W = s.v_W;
    target.w_W = s.w_W;
    DriveBase(park, Eigen::Vector3d::Zero());
    arm.SetState(*d_);
    const control::TaskSpaceOutput& out = task->Update(arm, arm.ChainPositions(*d_), target);
    q_ref += out.qd_cmd * m_->opt.timestep;
    servo.Command(d_, q_ref, out.qd_cmd, Eigen::VectorXd());
    mj_step(m_, d_);
    max_tracking = std::max(max_tracking, out.position_error_m);
    contacts = std::max(contacts, d_->ncon);
  }
  mj_forward(m_, d_);
  const Eigen::Vector3d tip = Vec3(d_->site_xpos + 3 * tool_);
  const double angle = AngleBetween(Mat3(d_->site_xmat + 9 * tool_), ToolDown());
  std::cout << "reach: tool tip " << (tip - goal.p_W).norm() * 1e3 << " mm from 5 mm above the target, " << angle * 1e3
            << " mrad from pointing down; largest tracking error " << max_tracking * 1e3 << " mm; base moved "
            << (Eigen::Vector3d(d_->qpos[0], d_->qpos[1], 0) - Eigen::Vector3d(park.x(), park.y(), 0)).norm() * 1e3
            << " mm while the arm reached\n";
  EXPECT_LT((tip - goal.p_W).norm(), 1e-3);
  EXPECT_LT(angle, 1e-3);
  EXPECT_EQ(contacts, 0) << "the arm or the base touched the table";
}

}  // namespace
}  // namespace vlab::testing
