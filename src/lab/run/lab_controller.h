// Built-in controllers: in-process controllers that talk to an arm device
// through the same messages an external controller gets over the wire.
//
// Ports
//   input   bridge::ArmState of the arm it commands (newest sample)
//   output  bridge::ArmCommand for that arm, once per control period
//   log     its own columns (controller.*), e.g. tracking errors
// Types (scenario key controller.type):
//   none        sends nothing: the arm holds its initial position
//   joint_pd    joint-space PD with gravity compensation (torque mode) along a
//               joint-space path with quintic or trapezoidal timing
//   task_space  kinematic resolved-rate control of the tip pose (velocity mode)
//               along a Cartesian path (straight lines, SLERP orientation)
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "bridge/bridge_messages.h"
#include "lab/scenario/lab_scenario.h"

namespace vlab::lab {

class Controller {
 public:
  virtual ~Controller() = default;
  /// Names of the log columns this controller writes.
  virtual std::vector<std::string> Columns() const = 0;
  /// One control period at time_s: reads the arm state, writes the command
  /// and Columns().size() log values into `columns`.
  virtual void Update(double time_s, const bridge::ArmState& state, bridge::ArmCommand* command, double* columns) = 0;
};

/// Creates the controller a scenario names. `model` is read-only (the
/// controller keeps its own scratch data for robot-model quantities);
/// `joint_names` are the arm device's joints in device order; `initial` is the
/// arm's first sample. Throws InputError naming the scenario line and the
/// offending element.
std::unique_ptr<Controller> MakeController(const mjModel* model, const ControllerConfig& config,
                                           const std::vector<std::string>& joint_names,
                                           const bridge::ArmState& initial);

}  // namespace vlab::lab
