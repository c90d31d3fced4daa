// The built-in controller as a command source (lab_command_writer.h): each
// period it reads its arm's last sample and commands the arm, or replays the
// commands of a recording (RunOptions::replay) instead.
//
// Ports
//   input   the arm's state of the last Sample (bridge::ArmState)
//   output  the arm's command of the period, and the controller's log columns
//   claims  controller.arm
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "bridge/bridge_messages.h"
#include "lab/devices/device_arm.h"
#include "lab/run/lab_command_writer.h"
#include "lab/run/lab_controller.h"

namespace vlab::lab {

class ControllerWriter final : public CommandWriter {
 public:
  /// The scenario's built-in controller on `arm` (which must outlive it).
  /// Throws InputError as MakeController.
  ControllerWriter(const mjModel* model, const ControllerConfig& config, SimArm& arm);

  /// The built-in controller's claim on controller.arm (checked before it is made).
  static Claim ClaimOf(const ControllerConfig& config);
  /// The controller's log columns.
  std::vector<std::string> Columns() const { return controller_->Columns(); }

  // CommandWriter
  std::vector<Claim> Claims() const override;
  /// Row 0: the controller's view of the initial state (no command sent).
  bool Restart(const CommandPeriod& period, std::string* failure) override;
  /// Period k > 0 computes (or replays) the command; every period sends it.
  bool Write(const CommandPeriod& period, std::string* failure) override;

 private:
  // one controller period: computed (and recorded), or replayed from a recording
  void Update(const CommandPeriod& period);

  SimArm& arm_;
  std::string where_;
  std::unique_ptr<Controller> controller_;
  std::size_t columns_ = 0;     // log columns the controller writes
  std::size_t replay_at_ = 0;   // the next value of a recording replayed
  bridge::ArmCommand command_;  // the command of the period
};

}  // namespace vlab::lab
