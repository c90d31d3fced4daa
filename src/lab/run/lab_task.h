// The `task` controller: robot programs in the task language (src/task/)
// run in the lab's process, one period at a time, on the devices' own state
// and command payloads (the bytes they would send and take over UDP).
//
// Ports
//   input   every device's state payload (Device::State) at the period start
//   output  position commands of the programs' arms and the commands the
//           scripts send to other devices (Device::CheckCommand, Command),
//           applied before the period's physics
//   log     task.ROBOT.line, task.ROBOT.tool.x|y|z (task_runtime.h)
// A script error stops the run with exit 1, the log kept up to the period
// before; a syntax error is an InputError when the lab is created.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "lab/devices/device.h"
#include "lab/run/lab_command_writer.h"
#include "lab/scenario/lab_scenario.h"

namespace vlab::lab {

/// The task programs, one command source (lab_command_writer.h) that claims
/// each program's robot arm.
class TaskController final : public CommandWriter {
 public:
  /// Binds the programs to `devices` (which must outlive it); loads the
  /// scripts. Throws InputError naming the program entry, or the script's
  /// file:line of a syntax error.
  static std::unique_ptr<TaskController> Create(const mjModel* model, const Scenario& scenario,
                                                const std::vector<Device*>& devices);
  ~TaskController() override;

  /// The claims of a scenario's programs: each program's robot arm, claimed
  /// by "task program 'SCRIPT'" at its entry (the lab checks them before the
  /// programs are loaded).
  static std::vector<Claim> ClaimsOf(const Scenario& scenario);

  /// Starts the programs again from their first line (a fresh runtime, the
  /// scripts loaded again): each run of a lab starts its programs anew.
  void Restart();

  std::vector<std::string> Columns() const;

  // CommandWriter
  /// ClaimsOf(the scenario it was made from).
  std::vector<Claim> Claims() const override;
  /// Row 0: the programs start anew (Restart()) and run their period 0.
  bool Restart(const CommandPeriod& period, std::string* failure) override;
  /// One period at period.t_s: resumes the programs, commands the devices,
  /// writes the log columns. False when a program failed: *failure says where.
  bool Write(const CommandPeriod& period, std::string* failure) override;
  /// Called while a script waits in wall time (markers:next() holding a
  /// period, markers() connecting): the run serves its devices meanwhile
  /// (LabBridge::Poll), so that the vision program can read the lab's camera.
  void SetIdle(std::function<void()> idle);

 private:
  struct Impl;
  // one period of the programs
  bool Step(const CommandPeriod& period, std::string* failure);
  explicit TaskController(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace vlab::lab
