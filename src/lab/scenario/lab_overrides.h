// Scenario overrides: `vlab run … --set KEY=VALUE`.
//
// KEY is a dotted path into the scenario document: map keys by name, list items
// by their `name` (devices.jr3.filter, checks.final_position_error.max) or by
// index (controller.waypoints.0.duration). VALUE is read as YAML (2, true,
// [0.1, 0.2], {bandwidth_hz: 8}, a string) and replaces what the file has at
// KEY, or adds KEY to a mapping; the scenario is then parsed as usual, so an
// override gets the same strict typing, range checks and unknown-key errors as
// the file. An error on an overridden value names the --set that gave it.
#pragma once

#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace vlab::lab {

/// One `--set KEY=VALUE`.
struct Override {
  std::string key;    ///< dotted path as given
  std::string value;  ///< YAML text as given
};

/// Splits "KEY=VALUE" (the first '='). Throws InputError naming the argument when
/// there is no '=' or KEY is empty or has an empty segment ("a..b").
Override ParseOverride(const std::string& text);

/// Reads an overrides file (`vlab run --overrides FILE`, written by vlab identify): one
/// KEY=VALUE a line, as --set takes it; blank lines and lines starting with '#' are skipped.
/// Returns the lines in order. Throws InputError naming the file (and "FILE:LINE" for a
/// line ParseOverride refuses).
std::vector<std::string> ReadOverridesFile(const std::string& path);

/// Applies `overrides` in order to the document `root` of scenario `file`.
/// Returns, for each override, the key path the scenario parser uses in its
/// messages ("devices[1].filter"). Throws InputError naming the --set when a
/// list has no item of that name or index, a path runs through a scalar, or the
/// value is not valid YAML.
std::vector<std::string> ApplyOverrides(const std::string& file, YAML::Node root,
                                        const std::vector<Override>& overrides);

}  // namespace vlab::lab
