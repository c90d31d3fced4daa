// Gaze control of the 7-DOF humanoid head model (test helper).
//
// GazeSolver: given the neck angles, finds the common eye tilt and the two eye pans
// that point both cameras' optical axes (camera -z) at a world point, by Gauss-Newton on
// the model's own kinematics (finite-difference Jacobian). Nothing about the head's
// geometry is assumed, so the solver checks that the model can look at the point.
// HeadServo: joint PD with gravity feed-forward through the head's torque motors,
// gains from each joint's inertia at the start pose (kp = H_ii w^2, kd = 2 H_ii w).
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>
#include <Eigen/Core>

namespace vlab::models::testing {

/// The head device's joints, in device order.
inline constexpr std::array<const char*, 7> kHeadJoints = {"neck_pitch", "neck_roll",    "neck_yaw",     "head_tilt",
                                                           "eye_tilt",   "left_eye_pan", "right_eye_pan"};

/// Angle between a camera's optical axis and the direction to target_W, rad.
double GazeError(const mjModel* m, const mjData* d, int camera, const Eigen::Vector3d& target_W);

class GazeSolver {
 public:
  explicit GazeSolver(const mjModel* m);
  ~GazeSolver();
  GazeSolver(const GazeSolver&) = delete;
  GazeSolver& operator=(const GazeSolver&) = delete;

  /// q: the 7 head joint angles (neck fixed, eyes = initial guess). Returns the angles
  /// with the eye joints solved (within their limits) and sets *error_rad to the larger
  /// of the two eyes' remaining gaze errors.
  Eigen::VectorXd Solve(const Eigen::VectorXd& q, const Eigen::Vector3d& target_W, double* error_rad);

 private:
  Eigen::VectorXd Residual(const Eigen::Vector3d& target_W);
  void SetHead(const Eigen::VectorXd& q);

  const mjModel* model_;
  mjData* scratch_;
  std::vector<int> qpos_adr_;
  std::vector<double> lower_, upper_;
  int left_camera_, right_camera_;
};

class HeadServo {
 public:
  /// Binds to the head joints and their motors; gains at the current state of data.
  HeadServo(const mjModel* m, const mjData& data, double bandwidth_hz);
  int dof() const { return static_cast<int>(qpos_adr_.size()); }
  Eigen::VectorXd Positions(const mjData& data) const;
  /// ctrl for the next step (call between mj_step1 and mj_step2).
  void Actuate(const Eigen::VectorXd& q_ref, const Eigen::VectorXd& qd_ref, mjData& data) const;

 private:
  const mjModel* model_;
  std::vector<int> qpos_adr_, dof_adr_, actuators_;
  Eigen::VectorXd kp_, kd_;
};

}  // namespace vlab::models::testing
