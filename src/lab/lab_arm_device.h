// Simulated arm device: a joint servo interface over MuJoCo motors.
//
// Ports
//   input   ArmCommand (mode hold | position | velocity | torque, one value per
//           joint), taken at the start of a control period
//   output  ArmState (q, qd, applied tau, status bits), sampled at the end of
//           every control period
//   rate    the servo runs at every physics step (model timestep); commands and
//           outputs at the control rate
// Behaviour, like a real servo drive:
//   - holds the initial position until the first command arrives;
//   - position and velocity modes run a PD servo per joint with bias (gravity
//     and Coriolis) feed-forward from the model: tau = kp (q_ref - q) +
//     kd (qd_ref - qd) + h(q, qd); velocity mode integrates q_ref from the
//     commanded velocity, position mode feeds forward the command's rate;
//   - gains follow from the requested bandwidth and damping ratio and each
//     joint's inertia H_ii at the initial pose: kp = H_ii w^2, kd = 2 zeta H_ii w;
//   - the servo reference stays within 0.2 rad of the measured position (a
//     following-error window: a joint blocked by contact does not wind up);
//   - torque mode applies the commanded torque as is;
//   - every torque is clipped to the motor's range (status bit when it is);
//   - a command with the wrong size, a non-finite value, a position outside the
//     joint range, a velocity beyond max_velocity or a torque outside the motor
//     range is refused and counted; the arm keeps its previous command.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <mujoco/mujoco.h>

#include "bridge/bridge_messages.h"
#include "lab/lab_scenario.h"

namespace vlab::lab {

class SimArm {
 public:
  /// Binds the device to the model's joints and motors. Throws InputError
  /// naming the device, its scenario line and the missing or unsuitable element.
  static std::unique_ptr<SimArm> Create(const mjModel* model, const DeviceConfig& config);

  const std::string& name() const { return name_; }
  int dof() const { return static_cast<int>(qpos_adr_.size()); }
  const std::vector<std::string>& joint_names() const { return joint_names_; }
  const Eigen::VectorXd& lower_limits() const { return lower_; }
  const Eigen::VectorXd& upper_limits() const { return upper_; }
  /// Motor torque ranges, N m (−inf / +inf where unlimited).
  const Eigen::VectorXd& torque_min() const { return tau_min_; }
  const Eigen::VectorXd& torque_max() const { return tau_max_; }
  /// |qd| limits of velocity commands, rad/s (empty: none).
  const Eigen::VectorXd& max_velocity() const { return max_velocity_; }
  int watchdog_periods() const { return watchdog_periods_; }
  double owner_timeout_s() const { return owner_timeout_s_; }

  /// Writes the initial joint positions into qpos (if configured).
  void SetInitialPositions(mjData& data) const;
  /// Computes the servo gains at the current state and starts holding it.
  /// Requires mj_forward to have run on `data`. control_period_s is the time
  /// between commands (position mode differentiates successive commands).
  void Start(const mjData& data, double control_period_s);

  /// Takes a command. Returns false (and counts it) when refused.
  bool Command(const bridge::ArmCommand& command);
  /// Sets the motor controls for the next physics step; call between
  /// mj_step1 and mj_step2. dt = model timestep.
  void Actuate(mjData& data, double dt);
  /// Samples the device output.
  void Sample(const mjData& data, double time_s, bridge::ArmState* state) const;

  /// Log columns: NAME.q.JOINT, NAME.qd.JOINT, NAME.tau.JOINT, NAME.limit_violation,
  /// and NAME.following_error (largest |q_ref - q| of the servo, rad) when configured.
  std::vector<std::string> Columns() const;
  int ColumnCount() const { return 3 * dof() + 1 + (log_following_error_ ? 1 : 0); }
  /// Writes ColumnCount() values for the current state.
  void Row(const mjData& data, double* out) const;

  long refused_commands() const { return refused_; }
  const Eigen::VectorXd& kp() const { return kp_; }
  const Eigen::VectorXd& kd() const { return kd_; }

 private:
  SimArm() = default;

  const mjModel* model_ = nullptr;
  std::string name_;
  std::vector<std::string> joint_names_;
  std::vector<int> qpos_adr_, dof_adr_, actuator_ids_;
  Eigen::VectorXd lower_, upper_, tau_min_, tau_max_, initial_, max_velocity_;
  int watchdog_periods_ = 3;
  double owner_timeout_s_ = 1.0;
  bool has_initial_ = false;
  bool log_following_error_ = false;
  double bandwidth_hz_ = 10.0, damping_ratio_ = 1.0;
  Eigen::VectorXd kp_, kd_;
  // servo state
  bridge::ArmMode mode_ = bridge::ArmMode::kHold;
  Eigen::VectorXd value_, q_ref_, qd_ref_, last_position_command_, tau_;
  bool have_position_command_ = false;
  bool saturated_ = false;
  double command_period_s_ = 0.0;
  long refused_ = 0;
  bool last_refused_ = false;
};

}  // namespace vlab::lab
