// Kinematic (resolved-rate) task-space controller for tip position and
// orientation.
//
// Ports: input the chain state q and a RobotModel already evaluated at that
// state (RobotModel::SetState), and a target pose with feed-forward twist;
// output a joint-velocity command qd_cmd, to be integrated or sent to a joint
// velocity / position servo at the caller's rate.
//
// Law (all task quantities in the world frame W):
//   e     = [p_d − p;  e_o],   e_o = rotation vector (angle·axis) of R_d·Rᵀ
//   ẋ_ref = [v_d + k_position·(p_d − p);  ω_d + k_orientation·e_o]
//   J⁺    = Jᵀ (J Jᵀ + λ² I₆)⁻¹                       (damped least squares)
//   q̇_0   = k_null·(q_rest − q) + joint-limit term     (secondary task)
//   q̇_cmd = J⁺ ẋ_ref + (I − J⁺J) q̇_0
//         = Jᵀ (J Jᵀ + λ² I)⁻¹ (ẋ_ref − J q̇_0) + q̇_0   (as evaluated: one 6×6 solve)
// then, if some |q̇_cmd,i| exceeds max_joint_speed, the whole vector is scaled
// down uniformly (direction kept).
//
// Orientation error: e_o is computed from the quaternion η + ε of R_d·Rᵀ with
// η ≥ 0 (the double cover resolved to the short way) as 2·atan2(|ε|, η)·ε/|ε|,
// so |e_o| ∈ [0, π] is exact for large errors (no small-angle approximation,
// no acos) and its direction is continuous up to 180°. With ω = k·e_o the error
// rotation keeps its axis and its angle decays as exp(−k t).
//
// Damping: λ² = damping² + (adaptive_damping_max² · (1 − (σ_min/ε)²) if
// σ_min < ε), σ_min the smallest singular value of J and ε =
// singular_value_threshold (Nakamura & Hanafusa 1986); adaptive damping is off
// by default. With λ > 0 the null-space projector is approximate: the posture
// term leaks into the task by O(λ²/σ²).
//
// Threading: one instance per control loop. Update() never allocates and never
// throws except for a size mismatch between q, the model and the controller
// (a programming error, caught on the first call).
#pragma once

#include <limits>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "control/robot_model.h"

namespace vlab::control {

/// Controller configuration; validated by TaskSpaceController::Create.
struct TaskSpaceConfig {
  /// Position error gain, 1/s (≥ 0).
  double k_position = 20.0;
  /// Orientation error gain, 1/s (≥ 0).
  double k_orientation = 20.0;
  /// Constant DLS damping λ (≥ 0); units of J's entries (m or 1 per joint unit).
  double damping = 1e-3;
  /// Extra damping reached at σ_min = 0 (≥ 0); 0 disables adaptive damping.
  double adaptive_damping_max = 0.0;
  /// σ_min below which adaptive damping is active (> 0 if adaptive).
  double singular_value_threshold = 0.05;
  /// Posture gain of the null-space term, 1/s (≥ 0).
  double k_null = 1.0;
  /// Rest posture (chain order). Empty: the centre of each joint's range, or 0
  /// for an unlimited joint.
  Eigen::VectorXd q_rest;
  /// Joint-limit avoidance gain, 1/s (≥ 0); 0 disables. Inside the margin band
  /// next to a limit, q̇_0 gets k_joint_limit·(distance into the band), pointing
  /// away from the limit (gradient of a quadratic penalty active near limits).
  double k_joint_limit = 0.0;
  /// Width of the band, as a fraction of the joint's range, in (0, 0.5].
  double joint_limit_margin = 0.1;
  /// Largest |q̇_cmd,i|, rad/s or m/s (> 0); +inf disables uniform scaling.
  double max_joint_speed = std::numeric_limits<double>::infinity();
};

/// Desired tip motion, world frame.
struct TaskSpaceTarget {
  Pose pose;                                      ///< desired p_W (m) and R_W
  Eigen::Vector3d v_W = Eigen::Vector3d::Zero();  ///< feed-forward linear velocity, m/s
  Eigen::Vector3d w_W = Eigen::Vector3d::Zero();  ///< feed-forward angular velocity, rad/s
};

/// Result of one update.
struct TaskSpaceOutput {
  Eigen::VectorXd qd_cmd;  ///< joint velocity command, rad/s or m/s, chain order
  Eigen::Matrix<double, 6, 1> error_W = Eigen::Matrix<double, 6, 1>::Zero();  ///< [p_d − p; e_o]
  double position_error_m = 0.0;                                              ///< |p_d − p|, m
  double orientation_error_rad = 0.0;                                         ///< |e_o| ∈ [0, π], rad
  double damping = 0.0;                                                       ///< λ used, after adaptation
  double speed_scale = 1.0;  ///< uniform factor applied for max_joint_speed, (0, 1]
  bool ok = true;            ///< false if an input was non-finite; qd_cmd is then zero
};

/// Orientation error e_o (rad, world frame): the rotation vector of R_d·Rᵀ,
/// angle in [0, π] (see the file comment). Rotating R about e_o by |e_o| gives R_d.
Eigen::Vector3d OrientationError(const Eigen::Matrix3d& R_d_W, const Eigen::Matrix3d& R_W);

/// Damped least-squares pseudo-inverse Jᵀ(JJᵀ + λ²I)⁻¹ of a 6×n matrix (a
/// reference implementation; allocates).
Eigen::MatrixXd DampedPseudoInverse(const Eigen::MatrixXd& J, double damping);

class TaskSpaceController {
 public:
  /// Validates `config` against `model` (dof, limits) and sizes all buffers.
  /// Throws std::invalid_argument naming the bad field (negative gain, q_rest
  /// size, non-finite value, ...).
  static std::unique_ptr<TaskSpaceController> Create(const TaskSpaceConfig& config, const RobotModel& model);

  /// One control step. `model` must be the chain given to Create, already set
  /// to the current state; `q` is that state's chain positions. Returns a
  /// reference to an internal output, valid until the next call. Never
  /// allocates; throws std::invalid_argument only on a size mismatch.
  const TaskSpaceOutput& Update(const RobotModel& model, const Eigen::VectorXd& q, const TaskSpaceTarget& target);

  /// Effective rest posture (chain order).
  const Eigen::VectorXd& q_rest() const { return q_rest_; }
  const TaskSpaceConfig& config() const { return config_; }

 private:
  TaskSpaceController() = default;
  void NullSpaceVelocity(const Eigen::VectorXd& q);

  TaskSpaceConfig config_;
  int nv_ = 0;
  Eigen::VectorXd q_rest_, lower_, upper_;
  // buffers sized at creation
  std::vector<mjtNum> jacp_, jacr_;
  Eigen::Matrix<double, 6, Eigen::Dynamic> J_;
  Eigen::VectorXd qd0_;
  TaskSpaceOutput out_;
};

}  // namespace vlab::control
