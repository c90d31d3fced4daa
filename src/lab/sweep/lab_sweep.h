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
// is pNN_sSEED (pNN: the override set's index), its folder OUT/ID. Values reach
// `vlab run --set` as one line of YAML each (lab_sweep_text.h); a key, name or
// path holding a control character is refused naming its file, line and key.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "lab/outputs/lab_run_record.h"

namespace vlab::lab {

struct SweepRun {
  std::string id;                 ///< "p02_s3"
  long long seed = -1;            ///< -1: the scenario's
  std::vector<std::string> sets;  ///< KEY=VALUE, the sweep's `set` first
  std::string label;              ///< the override set's own KEY=VALUE, for messages ("" when none)
  std::size_t set = 0;            ///< index of its override set (Sweep::records)
};

struct Sweep {
  std::string file;
  std::string name;
  std::string scenario;   ///< path of the scenario file (as the sweep names it, resolved)
  double duration_s = 0;  ///< 0: the scenario's
  std::vector<SweepRun> runs;
  /// per override set: the record of its runs with the scenario's seed (one
  /// text per set, not per run: a sweep may have 100000 seeds)
  std::vector<RunRecord> records;
};

/// Reads a sweep file strictly (InputError naming file, line and key); checks
/// every run's overrides against the scenario (LoadScenario) before any runs.
Sweep LoadSweep(const std::string& path);

/// The `vlab run` arguments of one run into out_dir/ID (without the program).
std::vector<std::string> RunArguments(const Sweep& sweep, const SweepRun& run, const std::string& out_dir);

/// Where a run folder stands against the run the sweep would make now.
struct RunState {
  bool current = false;  ///< finished (not interrupted) and its record is the run's
  bool stale = false;    ///< finished, but what it ran is not what the sweep runs now
  std::string result;    ///< summary.json's result ("" when there is none)
  std::string why;       ///< not current: "not run yet", "interrupted", or how it changed
};

/// What `run` will be: its set's record with its seed.
RunRecord RecordOfRun(const Sweep& sweep, const SweepRun& run);

/// Reads run_dir/summary.json (vlab writes output folders whole, lab_output.h)
/// and compares its record with RecordOfRun (RecordChange).
RunState CheckRun(const Sweep& sweep, const SweepRun& run, const std::string& run_dir);

}  // namespace vlab::lab
