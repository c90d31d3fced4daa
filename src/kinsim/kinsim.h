// Kinematic arm simulator: an arm device that integrates commanded joint
// velocities without dynamics. A second, independent implementation of the arm
// device kind (the first is the lab's MuJoCo arm), used where only the robot's
// kinematics matter, like the external kinematic simulator of the original lab.
//
// Ports
//   input   arm command (mode hold | position | velocity | torque, one value
//           per joint), applied from the next Step on (Command)
//   output  arm state: q (rad), qd = the velocity actually applied in the last
//           step (rad/s), tau = 0 (N m: there are no dynamics), status bits
//           (Sample)
//   rate    driven by its owner: one Step(dt) per control period
// Behaviour
//   - holds the initial position until the first command arrives;
//   - hold: q stays where it is, qd = 0;
//   - velocity: q += v dt, each joint clamped at its position limits
//     (kStatusAtLimit while a joint is at or beyond a limit);
//   - position: a rate-limited kinematic servo: each joint moves toward its
//     target by at most velocity_max dt per step and lands on it exactly;
//   - torque: refused (no dynamics to apply it to), see Command.
// No sockets here: the wire (ownership, seq, watchdog, limit checks) is the
// bridge's DeviceEndpoint, run by kinsim_server. Step, Command, Hold and
// Sample never throw and never allocate once Sample has sized its message.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "bridge/bridge_protocol.h"

namespace vlab::kinsim {

/// Arm command modes: the wire values of the arm command's mode field.
enum class ArmMode : int { kHold = 0, kPosition = 1, kVelocity = 2, kTorque = 3 };

/// A kinematic arm: joint names and limits, nothing about masses or motors.
struct KinArmConfig {
  std::string name = "pa10";         ///< device name (describe, messages)
  std::vector<std::string> joints;   ///< joint names, in wire order
  std::vector<double> position_min;  ///< rad, one per joint, finite
  std::vector<double> position_max;  ///< rad, one per joint, finite, > position_min
  std::vector<double> velocity_max;  ///< rad/s, |qd| bound, one per joint, finite, > 0
  std::vector<double> initial;       ///< rad, one per joint, within the position limits
};

class KinArm {
 public:
  /// Validates the config; throws vlab::InputError naming the arm and the field
  /// (and the joint) that cannot be used.
  static std::unique_ptr<KinArm> Create(const KinArmConfig& config);

  /// Takes a command; it applies from the next Step on. A command is refused
  /// (returns false, sets kStatusRefused until the next applied command, and
  /// the previous command stays in force) when its size is wrong, a value is
  /// not finite or beyond a limit (the DeviceEndpoint refuses those first; the
  /// arm checks again so that it is safe on its own), or its mode is torque:
  /// a kinematic simulator has no dynamics to turn a torque into motion.
  bool Command(const bridge::ArmCommandMsg& command);
  /// Puts the arm on hold at its current position (watchdog).
  void Hold();
  /// Advances the arm by dt seconds (dt > 0; otherwise nothing happens).
  void Step(double dt);

  /// Status bits of the arm itself: kStatusHolding (hold mode: before the first
  /// command, hold command or Hold), kStatusRefused (the last command was
  /// refused), kStatusAtLimit (a joint at or beyond a position limit).
  std::uint32_t status() const;
  /// Fills q, qd, tau (= 0) and status; allocates only on the first call.
  void Sample(bridge::ArmStateMsg* state) const;

  int dof() const { return static_cast<int>(q_.size()); }
  ArmMode mode() const { return mode_; }
  const std::vector<double>& q() const { return q_; }
  const std::vector<double>& qd() const { return qd_; }
  const KinArmConfig& config() const { return config_; }
  /// Commands refused by Command: all of them, and those refused for their torque mode.
  long refused() const { return refused_; }
  long refused_torque() const { return refused_torque_; }

 private:
  explicit KinArm(const KinArmConfig& config);
  bool Valid(const bridge::ArmCommandMsg& command) const;

  KinArmConfig config_;
  ArmMode mode_ = ArmMode::kHold;
  std::vector<double> q_, qd_, value_;  // value_: target (rad) or velocity (rad/s) in force
  bool last_refused_ = false;
  long refused_ = 0;
  long refused_torque_ = 0;
};

}  // namespace vlab::kinsim
