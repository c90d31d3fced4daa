// Collecting a sweep: one table row per run folder (its summary.json).
//
// Columns: id (the folder's name), scenario, seed, duration_s, result, exit_code, one
// `set:KEY` column per override key any run has, for each check `NAME` (its
// value) and `NAME.verdict` (pass, fail, skip), then the timings (sim_time_s,
// loop_wall_s, total_wall_s, steps_per_s) unless left out. Rows sorted by id;
// numbers in the shortest decimal that reads back the same (the table of two
// identical sweeps is the same bytes, timings left out).
#pragma once

#include <string>
#include <vector>

namespace vlab::lab {

struct CollectedTable {
  std::vector<std::string> columns;
  std::vector<std::vector<std::string>> rows;  ///< "" where a run lacks the column
  int pass = 0, failed = 0, interrupted = 0;
  /// Index of a column, -1 when absent.
  int Column(const std::string& name) const;
};

/// Reads every DIR/*/summary.json (folders without one are not runs: left out;
/// a summary.json that is not JSON: InputError naming it). InputError when DIR
/// holds no run at all.
CollectedTable CollectRuns(const std::string& dir, bool timings);

/// The table as CSV (fields with ',' or '"' quoted).
std::string CollectedCsv(const CollectedTable& table);

/// Draws check `check`'s value against override `key` (or "seed"), one line per
/// seed (per override set when key is "seed"), into the PNG `png`. InputError
/// when the key or check is not a column or the key's values are not numbers.
void PlotCollected(const CollectedTable& table, const std::string& key, const std::string& check,
                   const std::string& png);

}  // namespace vlab::lab
