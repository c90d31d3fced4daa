// Joint-space PD control with gravity compensation.
//
//   τ = kp ∘ (q_des − q) + kd ∘ (qd_des − qd) + g(q)
//
// with ∘ the element-wise product. With constant q_des, qd_des = 0 and positive
// gains, q_des is a globally asymptotically stable equilibrium of the rigid
// chain (Takegaki & Arimoto 1981) when g is the exact gravity vector
// (RobotModel::Gravity()).
#pragma once

#include <Eigen/Core>

namespace vlab::control {

/// Diagonal joint gains, one entry per joint.
struct JointPdGains {
  Eigen::VectorXd kp;  ///< stiffness, N·m/rad (hinge) or N/m (slide)
  Eigen::VectorXd kd;  ///< damping, N·m·s/rad (hinge) or N·s/m (slide)
};

/// Joint torques (N·m or N) of the PD law above. All vectors are in chain order
/// and must have the same size as q; otherwise throws std::invalid_argument
/// naming the mismatched argument and both sizes. Allocates the result only.
Eigen::VectorXd JointPdGravityTorque(const JointPdGains& gains, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                     const Eigen::VectorXd& q_des, const Eigen::VectorXd& qd_des,
                                     const Eigen::VectorXd& g);

/// The same, written into `tau` (resized to the joint count; no allocation
/// when it already has that size): for control loops.
void JointPdGravityTorque(const JointPdGains& gains, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                          const Eigen::VectorXd& q_des, const Eigen::VectorXd& qd_des, const Eigen::VectorXd& g,
                          Eigen::VectorXd* tau);

}  // namespace vlab::control
