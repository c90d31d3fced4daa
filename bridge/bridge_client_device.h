// A client for any float64 device kind by its layout (base, gripper, feet,
// imu, point, yoyo, gaze, pose, ...): states as value arrays, commands as
// value arrays, with the lengths taken from the device's describe reply. The
// typed handles (Arm, Wrench, Sim; CameraClient, MarkersClient for the kinds
// that are not float64 arrays) stay the convenient way for their kinds.
//
// Values by name: a kind with a fixed layout (bridge_layouts.h) has
// compile-time indices, and Connect checks that the device's describe layout
// is the table's, so
//   constexpr int kGrasped = StateIndex(DeviceKind::kGripper, "grasped");
//   gripper.Read(1.0).values[kGrasped]
// reads the right value; Field(state, "grasped") does the same by a run-time
// lookup, and works for every layout (sensor names, "q[2]").
#pragma once

#include <cstdint>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

#include "bridge/bridge_client.h"

namespace vlab::bridge {

/// A device of any float64 kind, its layout from its describe reply.
/// A describe reply's layout (its "state" or "command" list) as one name per
/// value: "q[7]" -> "q[0]" .. "q[6]", "x" -> "x". Throws ProtocolError naming
/// `label` for a layout that is not a list of names or a bad count.
std::vector<std::string> ExpandLayoutFields(const nlohmann::json& fields, const std::string& label);

class Device : public DeviceClient {
 public:
  /// One state, sampled by the device at the end of control period `seq`.
  struct State {
    std::int64_t seq = 0;        ///< control period k
    double time = 0;             ///< simulated time of the sample, s
    std::vector<double> values;  ///< payload, in the order of layout.state
  };

  /// One command value by field name, for WriteFields.
  struct FieldValue {
    std::string_view name;
    double value = 0;
  };

  /// Connects to the device of `kind` at address:port (throws as
  /// Arm::Connect). The state and command lengths come from the describe
  /// reply's layout: "name" counts 1, "name[n]" counts n. For a kind with a
  /// fixed layout, a describe layout other than the table's is a
  /// ProtocolError. Throws std::invalid_argument for camera and markers, which
  /// are not float64 kinds.
  static Device Connect(DeviceKind kind, const std::string& address, int port, double timeout_s = 1.0,
                        const std::string& bind_address = "0.0.0.0");

  int state_length() const { return state_length_; }
  int command_length() const { return command_length_; }
  /// Names of the state / command values, one per value ("q[7]" gives q[0]..q[6]).
  const std::vector<std::string>& state_names() const { return state_names_; }
  const std::vector<std::string>& command_names() const { return command_names_; }
  /// Index of a state value by name; -1 if the layout has none.
  int StateIndex(std::string_view name) const;
  /// Index of a command value by name; -1 if the layout has none.
  int CommandIndex(std::string_view name) const;
  /// The value of the state field `name` in `state`. Throws
  /// std::invalid_argument naming the device and the field when the layout
  /// has no such field or `state` holds no state of this device.
  double Field(const State& state, std::string_view name) const;

  State Read(double timeout_s);
  State ReadLatest(double timeout_s);
  /// Sends a command answering state `seq`. Throws std::invalid_argument when
  /// the device takes no commands, the length is wrong or a value is not
  /// finite. Never blocks; false if not sent.
  bool Write(const std::vector<double>& values, std::int64_t seq);
  /// Sends a command given by field names, in any order: every command field
  /// exactly once, e.g. {{"x", 0.1}, {"y", 0}, {"z", 1.5}}. Throws
  /// std::invalid_argument naming the device and the field for an unknown,
  /// missing or repeated field or a non-finite value, and as Write. No
  /// allocation; never blocks; false if not sent.
  bool WriteFields(std::initializer_list<FieldValue> values, std::int64_t seq);

 private:
  Device(DeviceKind kind, const std::string& address, int port, double timeout_s, const std::string& bind_address);
  DecodeError ParseState(const Header& header, const std::vector<double>& payload) override;
  State Copy(const Header& header) const;

  int state_length_ = 0;
  int command_length_ = 0;
  std::vector<std::string> state_names_, command_names_;
  std::vector<double> values_;
  std::vector<double> command_;  ///< WriteFields' command, sized at connect
  std::vector<char> given_;      ///< which command fields WriteFields was given
};

}  // namespace vlab::bridge
