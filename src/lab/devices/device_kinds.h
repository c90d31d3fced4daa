// The kinds table: every device kind a scenario can name, with its reader and
// its factory. One row per kind (device_kinds.cc), no registration by static
// initialisation: the table is the whole list.
//
// A kind's row names its bridge::DeviceKind (the wire's kind code and name),
// the reader of its own YAML keys and the factory of its device class; both
// live in the kind's file pair under src/lab/devices/.
#pragma once

#include <memory>
#include <string>

#include <yaml-cpp/yaml.h>

#include "lab/devices/device.h"

namespace vlab::lab {

/// Reads a kind's own keys of a device entry (the shared keys name, kind and
/// port are read already). Throws InputError naming file, line and key.
using ReadParamsFn = std::shared_ptr<const DeviceParams> (*)(MapReader& r);
/// Makes a kind's device. Throws InputError naming the device and the MJCF
/// element it cannot bind.
using MakeDeviceFn = std::unique_ptr<Device> (*)(const DeviceContext& context, const DeviceConfig& config);

struct DeviceKindSpec {
  bridge::DeviceKind kind;
  ReadParamsFn read;
  MakeDeviceFn make;
};

/// The row of a kind; nullptr for a kind the lab does not simulate.
const DeviceKindSpec* FindDeviceKind(bridge::DeviceKind kind);
/// The kind of a scenario's `kind` name; nullptr when unknown.
const DeviceKindSpec* FindDeviceKind(const std::string& name);
/// The kinds' names in table order, comma separated (for messages).
std::string KnownDeviceKinds();

/// Reads one entry of a scenario's `devices` list. Throws InputError.
DeviceConfig ReadDevice(const std::string& file, const YAML::Node& node, const std::string& path);

/// Makes the device a scenario entry names. Throws InputError.
std::unique_ptr<Device> MakeDevice(const DeviceContext& context, const DeviceConfig& config);

}  // namespace vlab::lab
