// A whole-body joint servo for the HOAP-3 model in double support (test helper).
//
// Ports
//   input   q_ref: one position per actuated joint, rad, in actuator order
//   output  mjData::ctrl (joint torques, N m, clipped to the motor ranges)
//   rate    every physics step (call between mj_step1 and mj_step2)
// Law: tau = tau_g + kp (q_ref - q) - kd qd, where tau_g is the joint torque that holds
// the robot still with both feet on the floor: the static generalized force qfrc_bias
// minus J_c' f, with f the minimum-norm pair of foot wrenches (at the two sole sites)
// that balances the floating base, J_c,base' f = qfrc_bias,base. The position servo of
// the real HOAP-3 is stiff; this one is a PD with that feed-forward.
// Also reads the eight FSR touch sensors: their sum, the centre of pressure and its
// margin inside the support polygon (the convex hull of the FSR pads).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>
#include <Eigen/Core>

namespace vlab::models::testing {

/// What the feet measure, world frame.
struct FootReading {
  double force_sum_N = 0;                           ///< sum of the 8 FSRs
  Eigen::Vector2d cop_W = Eigen::Vector2d::Zero();  ///< centre of pressure (x, y), m
  double margin_m = 0;                              ///< CoP distance inside the support polygon
};

class Hoap3Balance {
 public:
  /// Binds to the HOAP-3 of a scene (motors, sole sites, FSR sensors); fails the
  /// calling test (returns nullptr) when an element is missing.
  static std::unique_ptr<Hoap3Balance> Create(const mjModel* model);

  int dof() const { return static_cast<int>(actuators_.size()); }
  /// Index of a joint (= its actuator) in q_ref, or -1.
  int Index(const std::string& joint) const;
  /// Current joint positions in q_ref order.
  Eigen::VectorXd Positions(const mjData& data) const;
  /// Sets ctrl for the next step. Requires mj_step1 (positions, velocities, bias).
  void Actuate(const Eigen::VectorXd& q_ref, mjData& data);
  /// FSR sum, CoP and support margin. Requires sensors (after mj_step2 or mj_forward).
  FootReading ReadFeet(const mjData& data) const;

  /// Joint stiffness, N m/rad, and damping, N m s/rad (motor joints; servos x 0.1).
  static constexpr double kStiffness = 40.0, kDamping = 0.8;

 private:
  Hoap3Balance() = default;

  const mjModel* model_ = nullptr;
  std::vector<int> actuators_, qpos_adr_, dof_adr_;
  Eigen::VectorXd kp_, kd_, lower_, upper_;
  int right_sole_ = -1, left_sole_ = -1;
  std::vector<int> fsr_sensors_, fsr_sites_;
  // work arrays, sized once
  Eigen::MatrixXd jac_feet_;  // 12 x nv: right then left, position rows then rotation rows
  std::vector<mjtNum> jacp_, jacr_;
};

}  // namespace vlab::models::testing
