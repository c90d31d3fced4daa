// The runtime's view of a device: a name, a kind and float64 payloads, the
// same bytes whether the device is in the lab's process or across UDP.
#pragma once

#include <string>
#include <vector>

#include "bridge/bridge_protocol.h"

namespace vlab::task {

class Channel {
 public:
  virtual ~Channel() = default;
  virtual const std::string& name() const = 0;
  virtual bridge::DeviceKind kind() const = 0;
  /// One name per state / command value, in payload order ("status",
  /// "q[0]", ..., "grasped"): a describe reply's layout, groups expanded.
  virtual const std::vector<std::string>& state_names() const = 0;
  virtual const std::vector<std::string>& command_names() const = 0;
  /// An arm's joint names in device order (its describe reply); empty for
  /// other kinds.
  virtual std::vector<std::string> joint_names() const { return {}; }
  /// The newest state payload; false when the device has sent none yet.
  virtual bool Read(std::vector<double>* values) = 0;
  /// Sends a command payload (command_names().size() values). False with a
  /// reason when the device refuses it (in process: its own command check).
  virtual bool Write(const std::vector<double>& values, std::string* why) = 0;
};

/// The devices a runtime may use, by name; a robot program's arm among them.
class Devices {
 public:
  virtual ~Devices() = default;
  /// The channel of the device `name`, or nullptr when there is none.
  virtual Channel* Find(const std::string& name) = 0;
  /// Names of every device, for messages.
  virtual std::vector<std::string> Names() const = 0;
};

/// Index of `name` in `names`, or -1.
int IndexOf(const std::vector<std::string>& names, const std::string& name);

}  // namespace vlab::task
