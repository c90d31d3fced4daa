// Device messages: what a controller reads from and writes to a device.
//
// These structs are the in-process form of the device layouts. The in-process
// transport (fast clock) passes them directly between the lab and a built-in
// controller; a wire transport encodes exactly these fields. A controller sees
// only these messages, never MuJoCo.
#pragma once

#include <cstdint>

#include <Eigen/Core>

#include "bridge/bridge_protocol.h"

namespace vlab::bridge {

/// Command mode of an arm device.
enum class ArmMode : int {
  kHold = 0,      ///< hold the position the arm had when the hold began
  kPosition = 1,  ///< value = joint positions, rad
  kVelocity = 2,  ///< value = joint velocities, rad/s
  kTorque = 3,    ///< value = joint torques, N·m (no gravity compensation added)
};

/// Status bits of an arm device: the wire's bits (bridge_protocol.h), one set.
enum ArmStatus : std::uint32_t {
  kArmHolding = kStatusHolding,            ///< no command yet, watchdog hold, or hold mode
  kArmCommandRefused = kStatusRefused,     ///< the last command was refused (NaN, limits, size)
  kArmTorqueSaturated = kStatusSaturated,  ///< a joint torque hit its actuator limit this period
  kArmAtJointLimit = kStatusAtLimit,       ///< a joint is at or beyond its position limit
};

/// Output of an arm device, sampled at the end of a control period.
struct ArmState {
  double time_s = 0.0;
  Eigen::VectorXd q;    ///< joint positions, rad
  Eigen::VectorXd qd;   ///< joint velocities, rad/s
  Eigen::VectorXd tau;  ///< applied joint torques, N·m
  std::uint32_t status = kArmHolding;
};

/// Input of an arm device.
struct ArmCommand {
  ArmMode mode = ArmMode::kHold;
  Eigen::VectorXd value;  ///< one value per joint, units by mode
};

/// Output of a wrench (force/torque sensor) device.
struct WrenchState {
  double time_s = 0.0;
  Eigen::Matrix<double, 6, 1> wrench =
      Eigen::Matrix<double, 6, 1>::Zero();  ///< Fx Fy Fz (N), Mx My Mz (N·m), sensor frame
  int filter = 0;                           ///< JR3 filter index the values come from (0 = unfiltered)
  bool saturated = false;                   ///< any axis beyond the ADC range during the period
};

}  // namespace vlab::bridge
