// What the task-space devices (kinds point and tool: device_point.cc,
// device_tool.cc) share: a device that holds an arm device's claim and drives
// it through an ArmChain every control period, toward commands of its own.
#pragma once

#include <initializer_list>
#include <string>
#include <vector>

#include "bridge/bridge_layouts.h"
#include "control/task_space.h"
#include "lab/devices/device.h"
#include "lab/devices/device_arm_chain.h"

namespace vlab::lab {

/// A task-space device over an ArmChain (Params: its ArmChainParams). It binds
/// and claims its arm, holds it before the first command, on the watchdog and
/// after a reset, and in every period that it does not hold gives the arm the
/// target that Advance returns (resolved rate, control/task_space.h).
/// A subclass gives the command (length, checks, Command), what a reset or a
/// resume from a hold starts from, the set-point's step and the samples.
/// Throws InputError from the constructor (MakeArmChain) and Bind (BindArmChain)
/// naming the device and what it cannot bind; never throws in a period.
template <class Params>
class TaskSpaceDevice : public Device, public CommandInput, public CommandWriter {
 public:
  /// `kind_word`: how the arm's claim names this device ("point" gives "point device 'NAME'").
  TaskSpaceDevice(const DeviceContext& context, const DeviceConfig& c, const char* kind_word)
      : Device(c), model_(context.model), config_(c.ParamsAs<Params>()), period_s_(context.control_period_s),
        chain_(MakeArmChain(model_, config_, who())), kind_word_(kind_word) {
    capabilities_.command_input = this;
    capabilities_.command_writer = this;
  }

  // its arm: an arm device of the scenario, driven by this device alone
  void Bind(const std::vector<Device*>& devices) override { BindArmChain(chain_, config_, devices, who()); }
  std::vector<Claim> Claims() const override {
    return {{config_.arm, std::string(kind_word_) + " device '" + name() + "'", where()}};
  }
  int log_rank() const override { return 3; }  // after the other devices, as in every log written so far

  void Reset(const mjData& d) override {
    ReadArmChain(chain_, d);
    Start(chain_.model->TipPose());
    ResetArmChain(chain_, config_);  // the null-space term keeps the start posture; hold
    Sample(d, d.time);
  }

  void Hold() override { chain_.holding = true; }
  int watchdog_periods() const override { return config_.input.watchdog_periods; }
  double owner_timeout_s() const override { return config_.input.owner_timeout_s; }

  // the arm's command of the period, toward the newest command (a command source: lab_command_writer.h)
  bool Write(const CommandPeriod& period, std::string*) override {
    bool resumed = false;
    if (!BeginArmChainPeriod(chain_, *period.data, &resumed)) return true;  // holding
    if (resumed) Resume(chain_.model->TipPose());                           // from a hold: start where the site is
    DriveArm(chain_, Advance());
    return true;
  }

 protected:
  /// At a reset: the set-point and command start at the site's pose `tip` (world frame).
  virtual void Start(const control::Pose& tip) = 0;
  /// After a hold: the set-point starts again at the site's pose `tip`.
  virtual void Resume(const control::Pose& tip) = 0;
  /// Moves the set-point one period toward the newest command (rate limits)
  /// and returns the arm's target for the period (set-point before the move,
  /// feed-forward velocity = the move / period).
  virtual control::TaskSpaceTarget Advance() = 0;

  /// For Command, once it has taken a command: the device leaves its hold (CommandArmChain).
  void Commanded() { CommandArmChain(chain_); }
  /// The log column names NAME.c of `columns`, in order.
  std::vector<std::string> NamedColumns(std::initializer_list<const char*> columns) const {
    std::vector<std::string> out;
    for (const char* c : columns) out.push_back(name() + "." + c);
    return out;
  }
  /// The status value of a state: kStatusHolding while the arm is held, else 0.
  double StatusValue() const { return chain_.holding ? static_cast<double>(bridge::kStatusHolding) : 0.0; }

  const mjModel* model_;
  Params config_;
  double period_s_;
  ArmChain chain_;  // the chain, its arm (bound by Bind) and its controller (made by Reset)

 private:
  const char* kind_word_;
};

}  // namespace vlab::lab
