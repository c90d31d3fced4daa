// The arm key tests' loader: a scenario whose one arm entry (joints a, b) carries the
// given key lines, read by LoadScenario (the keys are checked there, no scene is loaded).
#pragma once

#include <string>

#include "core/core_errors.h"
#include "lab/scenario/lab_scenario.h"
#include "test_util.h"

namespace vlab::lab {

/// Loads a scenario whose arm entry carries `keys` (YAML lines indented by four spaces);
/// returns the InputError's text, "" if there is none.
inline std::string ArmKeysError(const std::string& keys) {
  testing::TempDir dir;
  testing::WriteFile(dir / "s.yaml",
                     "scene: scene.xml\nduration: 1\ndevices:\n  - name: arm\n    kind: arm\n"
                     "    joints: [a, b]\n" +
                         keys);
  try {
    LoadScenario(dir / "s.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace vlab::lab
