// Fixture of the gripper tests (mobile_gripper_test): scenes/pa10_gripper.xml with the arm
// above the 5 cm cube, the joint poses of a pick-and-carry path (solved by inverse
// kinematics), the arm servo with the welded gripper's gravity fed forward, the gripper
// driver's command modes, and one pick-and-carry run with its measurements.
#pragma once

#include <algorithm>
#include <cmath>
#include <iostream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "control/trajectory.h"
#include "mobile/mobile_scene.h"

namespace vlab::testing {

inline constexpr double kCubeEdge = 0.05;                     // m
inline constexpr double kCubeMass = 0.09;                     // kg, beech 720 kg/m^3 (mjcf/gripper/README.md)
inline constexpr double kTcpFromMount = 0.133;                // m, gripper_tcp along the gripper's z
inline constexpr double kServoKp = 10000;                     // N/m, gripper_actuators.xml
inline constexpr double kMaxForce = 200;                      // N, drive limit
inline constexpr double kJawDamping = 4800;                   // N s/m per jaw, gripper_defaults.xml
inline constexpr double kOpen = 0.068;                        // m, full opening
inline const Eigen::Vector3d kCubeStart(0.60, -0.15, 0.425);  // m, cube centre on the table

enum class GripMode { kOpenOnly, kPosition, kForce };

// What one pick-and-carry run measured.
struct CarryResult {
  double slip_m = 0;         // largest cube displacement in either finger's frame after the grasp
  double slip_rad = 0;       // largest cube rotation relative to the left finger after the grasp
  double min_touch_n = 1e9;  // smallest pad force after the grasp
  double max_touch_n = 0;    // largest pad force during the whole run
  double max_lift_m = 0;     // highest the cube rose above its start
  double mount_error_m = 0;  // largest gripper-frame offset from the tool site
  double mount_error_rad = 0;
  Eigen::Vector3d cube_end = Eigen::Vector3d::Zero();
  Eigen::Vector3d tcp_end = Eigen::Vector3d::Zero();
  double touch_left_end = 0, touch_right_end = 0, grip_force_end = 0;
  Eigen::Vector3d jr3_force_end = Eigen::Vector3d::Zero();
};

class MobileGripperTest : public vlab::test::MujocoTest {
 protected:
  void SetUp() override {
    m_ = LoadModel("scenes/pa10_gripper.xml");
    d_ = MakeData(m_);
    act_servo_ = RequireId(m_, mjOBJ_ACTUATOR, "gripper");
    act_force_ = RequireId(m_, mjOBJ_ACTUATOR, "gripper_force");
    touch_left_ = m_->sensor_adr[RequireId(m_, mjOBJ_SENSOR, "gripper_touch_left")];
    touch_right_ = m_->sensor_adr[RequireId(m_, mjOBJ_SENSOR, "gripper_touch_right")];
    opening_ = m_->sensor_adr[RequireId(m_, mjOBJ_SENSOR, "gripper_opening")];
    opening_vel_ = m_->sensor_adr[RequireId(m_, mjOBJ_SENSOR, "gripper_opening_vel")];
    servo_force_ = m_->sensor_adr[RequireId(m_, mjOBJ_SENSOR, "gripper_servo_force")];
    jr3_force_ = m_->sensor_adr[RequireId(m_, mjOBJ_SENSOR, "jr3_force")];
    q_left_ = m_->jnt_qposadr[RequireId(m_, mjOBJ_JOINT, "gripper_left")];
    q_right_ = m_->jnt_qposadr[RequireId(m_, mjOBJ_JOINT, "gripper_right")];
    cube_ = RequireId(m_, mjOBJ_BODY, "cube");
    gripper_ = RequireId(m_, mjOBJ_BODY, "gripper");
    tool_body_ = RequireId(m_, mjOBJ_BODY, "tool_body");
    finger_left_ = RequireId(m_, mjOBJ_BODY, "gripper_finger_left");
    finger_right_ = RequireId(m_, mjOBJ_BODY, "gripper_finger_right");
    tool_site_ = RequireId(m_, mjOBJ_SITE, "tool");
    tcp_site_ = RequireId(m_, mjOBJ_SITE, "gripper_tcp");
    payload_mass_ = SubtreeMass(m_, gripper_);
    jacp_.resize(3 * m_->nv);

    // joint poses: TCP 0.10 m above the cube centre, at it, lifted 0.15 m, carried 0.3 m in +y
    mj_resetData(m_, d_);
    servo_ = std::make_unique<ArmServo>(m_, *d_, "world", "tool", 10.0, 1.0);
    Eigen::VectorXd seed(7);
    seed << 0, 0.523599, 0, 1.047198, 0, 1.570796, 0;  // the PA10 "ready" pose
    auto solve = [&](const Eigen::Vector3d& tcp) {
      control::Pose pose;
      pose.R_W = ToolDown();
      pose.p_W = tcp + Eigen::Vector3d(0, 0, kTcpFromMount);  // the gripper's z points down
      seed = SolvePose(servo_->model(), seed, pose);
      return seed;
    };
    q_above_ = solve(kCubeStart + Eigen::Vector3d(0, 0, 0.10));
    q_grasp_ = solve(kCubeStart);
    q_lift_ = solve(kCubeStart + Eigen::Vector3d(0, 0, 0.15));
    q_carry_ = solve(kCubeStart + Eigen::Vector3d(0, 0.30, 0.15));
    // start at rest above the cube, gripper open
    for (int i = 0; i < 7; ++i) d_->qpos[i] = q_above_[i];
    d_->qpos[q_left_] = d_->qpos[q_right_] = kOpen / 2;
    d_->ctrl[act_servo_] = kOpen;
    PlaceWeldedBodies(m_, d_);
    servo_ = std::make_unique<ArmServo>(m_, *d_, "world", "tool", 10.0, 1.0);
  }

  // the gravity torque of the welded gripper, which the arm chain's model does not contain:
  // tau = J_p' m g at the gripper's COM, as a point of tool_body
  void UpdatePayloadFeedforward() {
    mj_jac(m_, d_, jacp_.data(), nullptr, d_->subtree_com + 3 * gripper_, tool_body_);
    Eigen::VectorXd& ff = servo_->extra_feedforward();
    for (int i = 0; i < 7; ++i) ff[i] = jacp_[2 * m_->nv + i] * payload_mass_ * 9.81;
  }

  // one physics step with the arm servo tracking (q, qd, qdd)
  void Step(const control::JointSample& s) {
    UpdatePayloadFeedforward();
    servo_->Command(d_, s.q, s.qd, s.qdd);
    mj_step(m_, d_);
  }

  void HoldArm(double seconds) {
    control::JointSample hold{q_above_, Eigen::VectorXd::Zero(7), Eigen::VectorXd::Zero(7), true};
    for (long i = 0; i < std::lround(seconds / m_->opt.timestep); ++i) Step(hold);
  }

  // The gripper driver's command modes, as a device runs them before every step:
  //   open      the servo's set-point is the full opening;
  //   position  the servo's set-point is `value` (m);
  //   force     the servo closes at full speed until both pads touch (> 0.5 N), then it is
  //             held neutral (set-point = current opening) and the force drive closes with
  //             `value` (N): the drive's force-speed line would make a weak force close slowly.
  void Drive(GripMode mode, double value) {
    d_->ctrl[act_force_] = 0;
    if (mode == GripMode::kOpenOnly) {
      d_->ctrl[act_servo_] = kOpen;
      force_engaged_ = false;
    } else if (mode == GripMode::kPosition) {
      d_->ctrl[act_servo_] = value;
    } else {
      force_engaged_ = force_engaged_ || std::min(d_->sensordata[touch_left_], d_->sensordata[touch_right_]) > 0.5;
      d_->ctrl[act_servo_] = force_engaged_ ? OpeningNow() : 0.0;
      d_->ctrl[act_force_] = force_engaged_ ? -value : 0.0;
    }
  }

  double Opening() const { return d_->sensordata[opening_]; }
  // the opening of the current state (the sensor holds the last forward pass's value)
  double OpeningNow() const { return d_->qpos[q_left_] + d_->qpos[q_right_]; }
  Eigen::Vector3d BodyPos(int b) const { return Vec3(d_->xpos + 3 * b); }
  Eigen::Matrix3d BodyRot(int b) const { return Mat3(d_->xmat + 9 * b); }

  CarryResult PickAndCarry(GripMode mode, double grip);

  const mjModel* m_ = nullptr;
  mjData* d_ = nullptr;
  std::unique_ptr<ArmServo> servo_;
  int act_servo_ = -1, act_force_ = -1;
  int touch_left_ = 0, touch_right_ = 0, opening_ = 0, opening_vel_ = 0, servo_force_ = 0, jr3_force_ = 0;
  int q_left_ = 0, q_right_ = 0;
  int cube_ = -1, gripper_ = -1, tool_body_ = -1, finger_left_ = -1, finger_right_ = -1;
  int tool_site_ = -1, tcp_site_ = -1;
  double payload_mass_ = 0;
  bool force_engaged_ = false;
  std::vector<mjtNum> jacp_;
  Eigen::VectorXd q_above_, q_grasp_, q_lift_, q_carry_;
};

// Descend 1.5 s, close (0.7 s), lift 0.15 m (1.5 s), carry 0.3 m sideways (2.0 s), hold 0.5 s.
// grip: the opening set-point (m) in position mode, the closing force (N) in force mode.
inline CarryResult MobileGripperTest::PickAndCarry(GripMode mode, double grip) {
  control::JointTrajectoryConfig path;
  path.waypoints = {q_above_, q_above_, q_grasp_, q_grasp_, q_lift_, q_carry_, q_carry_};
  for (double duration : {0.3, 1.5, 0.7, 1.5, 2.0, 0.5}) path.segments.push_back({duration, {}});
  auto trajectory = control::JointTrajectory::Create(path);
  const double t_close = 1.8, t_grasped = 2.5;

  CarryResult r;
  control::JointSample s;
  Eigen::Vector3d ref_left = Eigen::Vector3d::Zero(), ref_right = Eigen::Vector3d::Zero();
  Eigen::Matrix3d ref_rot = Eigen::Matrix3d::Identity();
  const int steps = static_cast<int>(std::lround(trajectory->duration_s() / m_->opt.timestep));
  for (int k = 0; k <= steps; ++k) {
    const double t = k * m_->opt.timestep;
    trajectory->Evaluate(t, &s);
    Drive(mode == GripMode::kOpenOnly || t < t_close ? GripMode::kOpenOnly : mode, grip);
    Step(s);

    // measurements
    const Eigen::Vector3d cube = BodyPos(cube_);
    const double touch = std::min(d_->sensordata[touch_left_], d_->sensordata[touch_right_]);
    r.max_touch_n = std::max({r.max_touch_n, d_->sensordata[touch_left_], d_->sensordata[touch_right_]});
    r.max_lift_m = std::max(r.max_lift_m, cube.z() - kCubeStart.z());
    const Eigen::Vector3d mount_offset = BodyPos(gripper_) - Vec3(d_->site_xpos + 3 * tool_site_);
    r.mount_error_m = std::max(r.mount_error_m, mount_offset.norm());
    r.mount_error_rad =
        std::max(r.mount_error_rad, AngleBetween(BodyRot(gripper_), Mat3(d_->site_xmat + 9 * tool_site_)));
    const Eigen::Vector3d in_left = BodyRot(finger_left_).transpose() * (cube - BodyPos(finger_left_));
    const Eigen::Vector3d in_right = BodyRot(finger_right_).transpose() * (cube - BodyPos(finger_right_));
    const Eigen::Matrix3d rot_in_left = BodyRot(finger_left_).transpose() * BodyRot(cube_);
    if (t < t_grasped) {
      ref_left = in_left;
      ref_right = in_right;
      ref_rot = rot_in_left;
    } else {
      r.slip_m = std::max({r.slip_m, (in_left - ref_left).norm(), (in_right - ref_right).norm()});
      r.slip_rad = std::max(r.slip_rad, AngleBetween(rot_in_left, ref_rot));
      r.min_touch_n = std::min(r.min_touch_n, touch);
    }
  }
  r.cube_end = BodyPos(cube_);
  r.tcp_end = Vec3(d_->site_xpos + 3 * tcp_site_);
  r.touch_left_end = d_->sensordata[touch_left_];
  r.touch_right_end = d_->sensordata[touch_right_];
  r.grip_force_end = -(d_->actuator_force[act_servo_] + d_->actuator_force[act_force_]);
  r.jr3_force_end = Vec3(d_->sensordata + jr3_force_);
  return r;
}

}  // namespace vlab::testing
