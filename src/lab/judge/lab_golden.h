// Golden runs: a folder that holds a recorded log and how to reproduce and judge it.
//
//   GOLDEN/golden.yaml   what to run and the tolerances (written by a person)
//   GOLDEN/log.csv       the recorded log (written only by `vlab golden --update`)
//
// golden.yaml keys: `scenario` (path relative to the folder), optional `duration`
// (s; a golden may record a shortened run and says so here), `seed`, `set` (a list
// of KEY=VALUE scenario overrides), `every` (keep every N-th log row, default 1),
// `from`/`to` (compared window, s) and `tolerances`: a list of
// {columns: GLOB, abs: X, rel: Y} or {columns: GLOB, ignore: true}; first match
// wins, a column no entry matches must be equal.
#pragma once

#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "lab/judge/lab_compare.h"

namespace vlab::lab {

struct GoldenSpec {
  std::string dir;
  std::string scenario;           ///< resolved path of the scenario file
  double duration_s = 0.0;        ///< 0: the scenario's
  long long seed = -1;            ///< -1: the scenario's
  std::vector<std::string> sets;  ///< KEY=VALUE overrides
  int every = 1;                  ///< log rows kept: 0, every, 2 every, ...
  CompareOptions compare;         ///< tolerances and window
  std::string log() const { return dir + "/log.csv"; }
};

/// Reads DIR/golden.yaml strictly (InputError naming file, line and key).
GoldenSpec LoadGolden(const std::string& dir);

/// Reads a `tolerances` list ({columns: GLOB, abs: X, rel: Y} or {columns: GLOB,
/// ignore: true}) of `file` at key path `path`; InputError naming file, line and key.
std::vector<ColumnTolerance> ReadTolerances(const std::string& file, const YAML::Node& list, const std::string& path);

/// Writes every `every`-th data row of the CSV `from` (the header and row 0
/// always) to `to`, byte for byte, through a temporary file renamed into place.
/// Throws std::runtime_error naming the file on an I/O error.
void WriteDecimatedLog(const std::string& from, const std::string& to, int every);

}  // namespace vlab::lab
