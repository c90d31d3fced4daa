// The lab's devices beyond arms and wrenches (base, gripper, feet, imu, ...):
// one interface, so that the step loop, the log and the bridge treat them
// alike.
//
// Each control period: Command() with the newest accepted command (or Hold()
// when the watchdog fires), Actuate() between mj_step1 and mj_step2 of every
// physics step, Sample() once at the end of the period; State() and Row()
// then give what was sampled. A device reads mjData and writes only the
// controls of its own actuators.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "bridge/bridge_endpoint.h"
#include "bridge/bridge_protocol.h"
#include "lab/lab_scenario.h"

namespace vlab::lab {

class SimDevice {
 public:
  virtual ~SimDevice() = default;
  const std::string& name() const { return name_; }
  virtual bridge::DeviceKind kind() const = 0;

  /// After the lab's reset (mj_forward has run): restart from the state in `d`.
  virtual void Reset(const mjData& d) { (void)d; }
  /// Every physics step, between mj_step1 and mj_step2: write own controls.
  virtual void Actuate(mjData& d, double dt) {
    (void)d;
    (void)dt;
  }
  /// Start of a control period at time t, after the period's commands (and
  /// holds) were given: a device that commands another one (point: its arm)
  /// does it here.
  virtual void BeginPeriod(const mjData& d, double t) {
    (void)d;
    (void)t;
  }
  /// End of a control period at time t.
  virtual void Sample(const mjData& d, double t) = 0;

  /// The state payload of the last Sample() (status word first for commanded kinds).
  virtual void State(std::vector<double>* payload) const = 0;
  /// Log columns, prefixed "NAME.", and the values of the last Sample().
  virtual std::vector<std::string> Columns() const = 0;
  virtual int ColumnCount() const = 0;
  virtual void Row(double* out) const = 0;

  /// Commands: payload length (0: an output-only device), check, apply.
  virtual int command_length() const { return 0; }
  virtual bridge::CommandCheck CheckCommand(const std::vector<double>& payload) const {
    (void)payload;
    return bridge::CommandCheck::kAccept;
  }
  virtual void Command(const std::vector<double>& payload) { (void)payload; }
  /// The watchdog fired, or a hold was asked for: stop safely.
  virtual void Hold() {}
  virtual int watchdog_periods() const { return 0; }
  virtual double owner_timeout_s() const { return 1.0; }

  /// The kind's facts for the describe reply: a JSON object with "layout",
  /// "units" and the kind's own fields.
  virtual std::string DescribeFacts() const = 0;

 protected:
  explicit SimDevice(std::string name) : name_(std::move(name)) {}

 private:
  std::string name_;
};

class SimArm;

/// Makes a point device (kind point) that drives `arm` (the scenario's arm
/// device its `arm` key names; it must outlive the device) at the control
/// period. Throws InputError naming the device and the element it cannot bind.
std::unique_ptr<SimDevice> MakePointDevice(const mjModel* m, const DeviceConfig& config, SimArm* arm,
                                           double control_period_s);

/// Makes the device a scenario entry names (kinds base, gripper, feet, imu, gaze, pose, yoyo;
/// point: MakePointDevice).
/// Throws InputError naming the device and the MJCF element it cannot bind.
std::unique_ptr<SimDevice> MakeSimDevice(const mjModel* m, const DeviceConfig& config, std::uint64_t seed);

/// True for the kinds MakeSimDevice makes.
bool IsSimDeviceKind(const std::string& kind);

}  // namespace vlab::lab
