// vlab excite's internals (cli_excite.cc: the command; cli_excite_files.cc: the files it
// writes): not a public header.
#pragma once

#include <string>

#include "control/dynamics_regressor.h"
#include "control/excitation_optimizer.h"
#include "lab/outputs/lab_output.h"
#include "lab/scenario/lab_scenario.h"

namespace vlab::cli::excite {

/// Degrees to radians.
inline constexpr double kDeg = 3.14159265358979323846 / 180;

struct ExciteArgs {
  std::string scenario, arm, tip, base, out_dir;
  int harmonics = 5;
  double period_s = 10;
  int cycles = 3;
  long long seed = -1;  // < 0: the scenario's
  int evaluations = 1600;
  double clearance_m = 0.01;
  bool quiet = false;
};

/// Writes excite.lua, excite.yaml and excite.json into `out`'s staging folder (see
/// cli_excite.cc); `tip` and `base` the task's chain. Throws std::runtime_error on a write error.
void WriteOutputs(const ExciteArgs& a, const lab::Scenario& s, const lab::DeviceConfig& arm, const std::string& tip,
                  const std::string& base, const control::DynamicsRegressor& r, const control::JointLimits& limits,
                  const control::ExcitationConfig& c, const control::ExcitationResult& res, lab::OutputDir& out);

}  // namespace vlab::cli::excite
