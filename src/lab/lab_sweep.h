// Sweep files: one scenario run over seeds and a grid or list of overrides.
//
//   name: pa10_gains                      # output folder sweeps/NAME (default: file stem)
//   scenario: ../scenes/pa10_reach.yaml   # relative to the sweep file
//   duration: 3                           # optional: every run's --duration, s
//   seeds: [1, 2, 3]                      # or {from: 1, count: 3}; default: the scenario's
//   set: [devices.jr3.filter=2]           # optional: overrides of every run
//   grid:                                 # every combination (the last key varies fastest)
//     controller.gains.position: [10, 20, 30]
//   list:                                 # or: explicit override sets, one per entry
//     - {controller.gains.position: 10, devices.jr3.filter: 3}
//
// Runs are ordered override set by override set, seeds within each; a run's id
// is pNN_sSEED (pNN: the override set's index), its folder OUT/ID.
#pragma once

#include <string>
#include <vector>

namespace vlab::lab {

struct SweepRun {
  std::string id;                  ///< "p02_s3"
  long long seed = -1;             ///< -1: the scenario's
  std::vector<std::string> sets;   ///< KEY=VALUE, the sweep's `set` first
};

struct Sweep {
  std::string file;
  std::string name;
  std::string scenario;  ///< path of the scenario file (as the sweep names it, resolved)
  double duration_s = 0; ///< 0: the scenario's
  std::vector<SweepRun> runs;
};

/// Reads a sweep file strictly (InputError naming file, line and key); checks
/// every run's overrides against the scenario (LoadScenario) before any runs.
Sweep LoadSweep(const std::string& path);

/// The `vlab run` arguments of one run into out_dir/ID (without the program).
std::vector<std::string> RunArguments(const Sweep& sweep, const SweepRun& run, const std::string& out_dir);

/// A command line word quoted for POSIX shells when it needs it.
std::string ShellQuote(const std::string& word);

/// True when out_dir/ID holds a finished run: summary.json whose result is not
/// "interrupted" (vlab writes output folders whole, lab_output.h).
bool RunComplete(const std::string& run_dir);

}  // namespace vlab::lab
