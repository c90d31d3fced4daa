// Reading one `devices:` entry of a scenario file (docs/scenarios.md, one section
// per kind): the part of LoadScenario that knows every device kind's keys.
#pragma once

#include <string>

#include <yaml-cpp/yaml.h>

#include "lab/lab_scenario.h"

namespace vlab::lab {

/// The device at `node` of `file` (`path` names it in messages, e.g. "devices[2]").
/// Throws InputError naming the file, line and key: an unknown kind or key, a
/// value of the wrong type or out of range.
DeviceConfig ReadDevice(const std::string& file, const YAML::Node& node, const std::string& path);

}  // namespace vlab::lab
