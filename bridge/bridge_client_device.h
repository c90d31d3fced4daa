// A client for any float64 device kind by its layout (base, gripper, feet,
// imu, markers, point, yoyo, ...): states as value arrays, commands as value
// arrays, with the lengths taken from the device's describe reply. The typed
// handles (Arm, Wrench, Sim) stay the convenient way for their kinds.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "bridge/bridge_client.h"

namespace vlab::bridge {

class Device : public DeviceClient {
 public:
  struct State {
    std::int64_t seq = 0;        ///< control period k
    double time = 0;             ///< simulated time of the sample, s
    std::vector<double> values;  ///< payload, in the order of layout.state
  };

  /// Connects to the device of `kind` at address:port (throws as
  /// Arm::Connect). The state and command lengths come from the describe
  /// reply's layout: "name" counts 1, "name[n]" counts n.
  static Device Connect(DeviceKind kind, const std::string& address, int port, double timeout_s = 1.0,
                        const std::string& bind_address = "0.0.0.0");

  int state_length() const { return state_length_; }
  int command_length() const { return command_length_; }
  /// Names of the state / command values, one per value ("q[7]" gives q[0]..q[6]).
  const std::vector<std::string>& state_names() const { return state_names_; }
  const std::vector<std::string>& command_names() const { return command_names_; }
  /// Index of a state value by name; -1 if the layout has none.
  int StateIndex(const std::string& name) const;

  State Read(double timeout_s);
  State ReadLatest(double timeout_s);
  /// Sends a command answering state `seq`. Throws std::invalid_argument when
  /// the device takes no commands, the length is wrong or a value is not
  /// finite. Never blocks; false if not sent.
  bool Write(const std::vector<double>& values, std::int64_t seq);

 private:
  Device(DeviceKind kind, const std::string& address, int port, double timeout_s, const std::string& bind_address);
  DecodeError ParseState(const Header& header, const std::vector<double>& payload) override;
  State Copy(const Header& header) const;

  int state_length_ = 0;
  int command_length_ = 0;
  std::vector<std::string> state_names_, command_names_;
  std::vector<double> values_;
};

}  // namespace vlab::bridge
