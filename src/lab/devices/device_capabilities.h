// What a device kind may have beyond the base (lab::Device): small interfaces
// a kind opts into, like MuJoCo's plugin capabilities (actuator, sensor,
// passive). A kind derives from the ones it has and offers them in its
// constructor (Device::capabilities_); the lab asks each device once, at load,
// and keeps a list per capability (Lab::Impl), so the step loop calls a hook
// only on the devices that have it.
//
//   CommandInput    a command input on the wire (arm, base, gripper, point,
//                   tool, sim): its role, length and check, Hold on the watchdog
//   StepHooks       work every physics step (arm, base, gripper: their servos;
//                   wrench: its sensor model)
//   RenderedOutput  output made from the state after the period's states went
//                   out (camera: frames rendered and delivered later)
//   LogReader       reads the lab's log rows (scene: its `signals`)
//   OwnTransport    its own socket instead of a bridge endpoint (camera)
//   CommandWriter   writes another device's command input (point, tool:
//                   lab/run/lab_command_writer.h)
// Two kinds are also addressed by type where other parts need them whole: the
// arm (a joint servo input the built-in controller, task programs and the
// task-space devices command in process) and the sim device (the run's own
// control). Nothing on the period path throws or allocates.
#pragma once

#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "bridge/bridge_endpoint.h"
#include "bridge/bridge_protocol.h"

namespace vlab::lab {

class CommandWriter;  // lab/run/lab_command_writer.h
class OwnTransport;   // lab/devices/device.h
class SimArm;         // lab/devices/device_arm.h
class SimControl;     // lab/devices/device_sim.h

/// How the lab treats a device's command input.
enum class CommandRole {
  kNone,             ///< output only
  kRun,              ///< the run's own control (sim): taken by the lab's loop, never waited for
  kWaited,           ///< lockstep waits for its owner's command once it has an owner
  kWaitedFromStart,  ///< ... and period 0 waits for an owner (arms: the controllers must be there)
  kDriven,           ///< commands taken, but another source holds its claim (an arm under a point device)
};

/// A command input served on the wire.
class CommandInput {
 public:
  virtual ~CommandInput() = default;
  /// Default: waited for once owned.
  virtual CommandRole command_role() const { return CommandRole::kWaited; }
  /// Payload length of a command (0: a typed command, TakeCommand's own: the arm's, the sim's).
  virtual int command_length() const { return 0; }
  /// Checks a command payload of command_length() finite values.
  virtual bridge::CommandCheck CheckCommand(const std::vector<double>& payload) const {
    (void)payload;
    return bridge::CommandCheck::kAccept;
  }
  /// Applies an accepted command payload.
  virtual void Command(const std::vector<double>& payload) { (void)payload; }
  /// Takes the endpoint's newest accepted command, if any, and applies it.
  /// True when there was one. Default: the payload to Command().
  virtual bool TakeCommand(bridge::DeviceEndpoint& endpoint, std::vector<double>* scratch);
  /// The watchdog fired, or a hold was asked for: stop safely.
  virtual void Hold() {}
  virtual int watchdog_periods() const { return 0; }
  virtual double owner_timeout_s() const { return 1.0; }
};

/// Work every physics step.
class StepHooks {
 public:
  virtual ~StepHooks() = default;
  /// Between mj_step1 and mj_step2: write own controls.
  virtual void Actuate(mjData& d, double dt) {
    (void)d;
    (void)dt;
  }
  /// After mj_step2.
  virtual void AfterStep(const mjData& d, double dt) {
    (void)d;
    (void)dt;
  }
};

/// Output made from the state at a period's end, besides its state datagram.
class RenderedOutput {
 public:
  virtual ~RenderedOutput() = default;
  /// Before the run, on the thread that runs the lab (a camera makes its renderer).
  virtual void BeforeRun(mjData* d) = 0;
  /// At every period end t (and t = 0), after the log row, before the states go out.
  virtual void Deliver(double t, mjData* d) = 0;
  /// After the states of a period end went out, the state still that of the period end.
  virtual void AfterPublish(mjData* d) = 0;
};

/// Reads the lab's log rows.
class LogReader {
 public:
  virtual ~LogReader() = default;
  /// The log's columns ("time" first), once the lab has them all; throws
  /// InputError naming a column it lacks.
  virtual void BindLog(const std::vector<std::string>& columns) = 0;
  /// Each log row as the lab writes it (columns as BindLog's), after Sample
  /// and before the period's states are published.
  virtual void LogRow(const double* row) = 0;
};

/// What a kind offers (null where it has none): set by the kind's constructor.
struct Capabilities {
  CommandInput* command_input = nullptr;
  StepHooks* step_hooks = nullptr;
  RenderedOutput* rendered_output = nullptr;
  LogReader* log_reader = nullptr;
  OwnTransport* own_transport = nullptr;
  CommandWriter* command_writer = nullptr;
  SimArm* arm = nullptr;
  SimControl* sim_control = nullptr;
};

}  // namespace vlab::lab
