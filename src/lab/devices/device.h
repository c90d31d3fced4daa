// The lab's device seam: one interface for every simulated device, so that
// the step loop, the log and the bridge treat them alike. The kinds (the rows
// of device_kinds.cc): arm, wrench, sim, camera, base, gripper, feet, imu,
// gaze, pose, point, yoyo, counter, scene, word, tool. A kind is one file pair
// under src/lab/devices/ and one row of the kinds table.
//
// Order of calls
//   creation  (run/lab_runner.cc) the kind's factory with the DeviceContext; then
//             Bind() once every device exists (a device that drives another
//             finds it); the claims of the command sources (command_writer())
//   reset     (run/lab_runner_impl.cc) SetInitialState() before the first
//             mj_forward; Start() after it; after a second mj_forward, Reset()
//   period    (run/lab_run_session.cc) the command sources write, in order: the
//             wire (CommandInput::TakeCommand()/Hold() of the served devices),
//             the built-in controller or the task programs, then the devices
//             that drive another (CommandWriter::Write); every physics step
//             StepHooks::Actuate() between mj_step1 and mj_step2 and AfterStep()
//             after mj_step2; Sample() at the period's end; Row() for the log
//             (LogReader::LogRow() after it); RenderedOutput::Deliver() before
//             the period's states go out, AfterPublish() after
// The base holds what every kind has (reset, sampling, log columns, the
// wire's state and describe reply); the rest is a capability a kind opts into
// (device_capabilities.h).
// A device reads mjData and writes only the controls of its own actuators.
// Nothing on the period path throws or allocates.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "bridge/bridge_describe.h"
#include "bridge/bridge_endpoint.h"
#include "bridge/bridge_protocol.h"
#include "lab/devices/device_capabilities.h"
#include "lab/devices/device_config.h"

namespace vlab::lab {

/// What every factory gets, the same way for every kind.
struct DeviceContext {
  const mjModel* model = nullptr;
  double control_period_s = 0.002;
  std::uint64_t seed = 1;  ///< the device's own seed (scenario seed mixed with the device name)
  std::string scene;       ///< the scene's MJCF path, for messages and for reloading it (cameras)
};

/// Frames of a device that streams them (a camera).
struct FrameCounters {
  long sent = 0;     ///< frames sent to at least one subscriber
  long late = 0;     ///< sent after their stamp + latency (realtime: the worker was late)
  long dropped = 0;  ///< not rendered: the ring of frames in flight was full
};

/// A device that serves itself on its own socket (a camera's chunked frames).
class OwnTransport {
 public:
  virtual ~OwnTransport() = default;
  /// Binds (address, port) and makes the describe reply; throws InputError
  /// naming the device when the port cannot be bound.
  virtual void Serve(const std::string& address, int port, const std::string& server, const std::string& clock) = 0;
  virtual bool served() const = 0;
  /// Closes its socket (a run without serving).
  virtual void Unserve() = 0;
  /// Its socket, and a non-blocking pass over what arrived on it.
  virtual int fd() const = 0;
  virtual void PollRequests() = 0;
  virtual int port() const = 0;
  virtual std::string address() const = 0;
  virtual std::string describe_json() const = 0;
  virtual bridge::EndpointCounters counters() const = 0;
  /// A streaming device's frames (a camera's): sent, late, dropped; zeros for others.
  virtual FrameCounters frames() const { return {}; }
};

class Device {
 public:
  virtual ~Device() = default;
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;

  const std::string& name() const { return name_; }
  bridge::DeviceKind kind() const { return kind_; }
  /// "FILE:LINE" of its scenario entry.
  const std::string& where() const { return where_; }

  // ---- creation and reset
  /// Once every device of the scenario exists. Throws InputError.
  virtual void Bind(const std::vector<Device*>& devices) { (void)devices; }
  /// Before the first mj_forward of a reset: initial joint positions.
  virtual void SetInitialState(mjData& d) const { (void)d; }
  /// After mj_forward: start servos, write the controls of the first instant.
  virtual void Start(mjData& d) { (void)d; }
  /// After the second mj_forward: restart from the state in `d`.
  virtual void Reset(const mjData& d) { (void)d; }

  // ---- the control period
  /// End of a period at time t.
  virtual void Sample(const mjData& d, double t) {
    (void)d;
    (void)t;
  }

  // ---- the log
  /// Log columns, prefixed "NAME.".
  virtual std::vector<std::string> Columns() const { return {}; }
  virtual int ColumnCount() const { return 0; }
  /// ColumnCount() values of the last Sample().
  virtual void Row(const mjData& d, double* out) const {
    (void)d;
    (void)out;
  }
  /// Log order: columns go by rank, then scenario order (arms 0, wrenches 1,
  /// point devices 3, the others 2: the order of every log vlab has written).
  virtual int log_rank() const { return 2; }

  // ---- the wire
  /// False when the last Sample() made no state to publish (a decimated
  /// stream between its frames): the bridge then sends nothing this period.
  virtual bool PublishDue() const { return true; }
  /// The state payload of the last Sample() (status word first for commanded kinds).
  virtual void State(std::vector<double>* payload) const { payload->clear(); }
  /// The state datagram of period `seq` at time t. `endpoint_bits`: the status
  /// bits of its endpoint (refused, watchdog). Default: header + State().
  virtual void EncodeState(double seq, double t, std::uint32_t endpoint_bits, std::vector<double>* scratch,
                           std::vector<unsigned char>* out) const;
  /// The endpoint's rules for this device (kind; its command input's length
  /// and check, watchdog, owner timeout). `control_hz` converts seconds to periods.
  virtual void ConfigureEndpoint(double control_hz, bridge::EndpointConfig* config) const;
  /// The describe reply, from the facts every device shares.
  virtual std::string DescribeJson(const bridge::DeviceDescription& common) const;
  /// The kind's facts for the default describe reply: a JSON object with
  /// "layout", "units" and the kind's own fields.
  virtual std::string DescribeFacts() const { return "{}"; }

  // ---- capabilities: what the kind has beyond this base (device_capabilities.h), null
  // where it has none; the lab asks once, at load, and keeps a list per capability
  CommandInput* command_input() const { return capabilities_.command_input; }
  StepHooks* step_hooks() const { return capabilities_.step_hooks; }
  RenderedOutput* rendered_output() const { return capabilities_.rendered_output; }
  LogReader* log_reader() const { return capabilities_.log_reader; }
  /// A device with its own transport (cameras), or null.
  OwnTransport* own_transport() const { return capabilities_.own_transport; }
  /// A device that writes another device's command input (point, tool), or null.
  CommandWriter* command_writer() const { return capabilities_.command_writer; }
  /// A joint servo input that other sources command in process (an arm), or null.
  SimArm* arm() const { return capabilities_.arm; }
  /// The run's own control (the sim device), or null.
  SimControl* sim_control() const { return capabilities_.sim_control; }
  /// The role of its command input (kNone without one).
  CommandRole command_role() const {
    return capabilities_.command_input ? capabilities_.command_input->command_role() : CommandRole::kNone;
  }

 protected:
  explicit Device(const DeviceConfig& config) : name_(config.name), kind_(config.kind), where_(config.where) {}
  /// "FILE:LINE: device 'NAME'", the start of every message about it.
  std::string who() const { return where_ + ": device '" + name_ + "'"; }
  /// What the kind offers: its constructor sets the interfaces it implements.
  Capabilities capabilities_;

 private:
  std::string name_;
  bridge::DeviceKind kind_;
  std::string where_;
};

}  // namespace vlab::lab
