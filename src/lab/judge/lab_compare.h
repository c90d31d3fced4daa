// Comparing a run's log with a golden log, column by column, within tolerances.
//
// Rows are aligned by time, not by index: every golden row whose time lies in the
// compared window is compared with the run's values at that time, interpolated
// linearly between the run's two neighbouring rows (exact when the run has a row
// at that time, as when the golden keeps every N-th row of a log with the same
// period). A column passes when every compared row has
//   |run - golden| <= abs + rel * |golden|
// with the tolerance of the first pattern that matches the column's name
// (shell globs: "pa10.q.*"); a column no pattern matches must match exactly.
// A NaN equals only a NaN. A golden column the run lacks fails; a run column
// the golden lacks is listed and not compared. A run that does not cover the
// golden's time window fails.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "scene/scene_csv.h"

namespace vlab::lab {

/// A CSV log read back (scene/scene_csv.h, shared with the view).
using scene::CsvTable;
using scene::ReadCsvTable;

/// The tolerance of the columns whose names match `pattern` (fnmatch glob).
struct ColumnTolerance {
  std::string pattern;
  double abs = 0.0;     ///< in the column's unit
  double rel = 0.0;     ///< of |golden|
  bool ignore = false;  ///< not compared at all
};

struct CompareOptions {
  std::vector<ColumnTolerance> tolerances;  ///< first match wins
  std::string time_column = "time";
  double from_s = -std::numeric_limits<double>::infinity();  ///< compared window
  double to_s = std::numeric_limits<double>::infinity();
};

/// One sample where a column leaves its tolerance.
struct Divergence {
  double time_s = 0.0;
  double run = 0.0;
  double golden = 0.0;
  double excess = 0.0;  ///< |run - golden| / allowed (inf when allowed is 0)
};

struct ColumnReport {
  std::string column;
  ColumnTolerance tolerance;
  bool missing = false;  ///< in the golden, not in the run
  long compared = 0;     ///< rows compared
  long out = 0;          ///< rows out of tolerance
  double max_abs_diff = 0.0;
  Divergence first, worst;  ///< valid when out > 0
  bool pass() const { return !missing && out == 0; }
};

struct CompareReport {
  std::string run_file, golden_file;
  long golden_rows = 0;               ///< golden rows in the window
  double from_s = 0.0, to_s = 0.0;    ///< window actually compared
  std::string coverage_failure;       ///< "" or why the run does not cover the golden
  std::vector<ColumnReport> columns;  ///< golden columns, time excepted, ignored ones excepted
  std::vector<std::string> ignored;   ///< golden columns ignored by a tolerance
  std::vector<std::string> run_only;  ///< run columns the golden lacks
  bool pass() const;
  long failing() const;
};

/// Compares `run` with `golden`. Throws InputError when a log lacks the time column.
CompareReport CompareLogs(const CsvTable& run, const CsvTable& golden, const CompareOptions& options);

/// The report as text: one line per failing column (first and worst divergence),
/// with `all` one line per compared column; then the verdict line.
std::string FormatCompareReport(const CompareReport& report, bool all);

}  // namespace vlab::lab
