// A scenario's device entry: the keys every device has (name, kind, port) and
// the kind's own parameters, read by the kind's reader (device_kinds.h) next
// to its class.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>

#include "bridge/bridge_protocol.h"

namespace vlab::lab {

class MapReader;

/// Base of every kind's parameter struct (ArmParams, GripperParams, ...).
struct DeviceParams {
  virtual ~DeviceParams() = default;
};

/// The command input of a commanded kind (arm, base, gripper, point): read by
/// one shared reader (ReadCommandInput), the same keys for every kind.
struct CommandInputConfig {
  int watchdog_periods = 3;      ///< hold after this many periods without a command (0: off)
  double owner_timeout_s = 1.0;  ///< a silent owner gives the command input up after this
};

/// Reads `watchdog_periods` and `owner_timeout` into `input` (its values are
/// the defaults). Throws InputError naming the file, line and key.
void ReadCommandInput(MapReader& r, CommandInputConfig* input);

/// DeviceConfig::port of `port: auto`: served on a free port the kernel
/// chooses when the device is bound (its ServedDevice says which).
constexpr int kAutoPort = -1;

struct DeviceConfig {
  std::string name;
  bridge::DeviceKind kind = bridge::DeviceKind::kArm;
  std::string where;  ///< "FILE:LINE" for messages about binding
  int port = 0;       ///< UDP port under `vlab serve` (0: not served; kAutoPort: any free port)
  /// The kind's own parameters (null: the kind's defaults).
  std::shared_ptr<const DeviceParams> params;

  /// The parameters as the kind's struct: the defaults when none were given.
  /// Throws std::logic_error when they are another kind's.
  template <class Params>
  const Params& ParamsAs() const {
    static const Params kDefaults{};
    if (!params) return kDefaults;
    const auto* p = dynamic_cast<const Params*>(params.get());
    if (!p) throw std::logic_error("device '" + name + "': parameters of another kind");
    return *p;
  }
  /// The parameters as the kind's struct, to change (tests, tools that build a
  /// scenario in code). Copy on write: parameters shared with another config
  /// are copied first; none give the defaults. Throws std::logic_error when
  /// they are another kind's. (Readers make their structs non-const.)
  template <class Params>
  Params& EditParams() {
    const Params& current = ParamsAs<Params>();
    if (!params || params.use_count() > 1) {
      auto copy = std::make_shared<Params>(current);
      Params& ref = *copy;
      params = std::move(copy);
      return ref;
    }
    return const_cast<Params&>(current);
  }
};

}  // namespace vlab::lab
