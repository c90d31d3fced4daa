// Checks: pass/fail rules over logged signals, evaluated while the run goes.
//
// Each check reduces one signal over a time window [from, to] (max, min, mean,
// rms, final or max_abs, or per sub-window: min_of_window_max, max_of_window_min)
// and compares the result with its bounds. A check whose window holds no sample
// (or no whole sub-window) fails with value NaN, unless the window starts after
// the run's end (a run shortened with --duration, or interrupted): then it is
// skipped, not failed, and says so.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "lab/scenario/lab_scenario.h"

namespace vlab::lab {

struct CheckResult {
  CheckConfig config;
  double value = 0.0;  ///< the reduced signal
  long samples = 0;    ///< samples inside the window
  bool pass = false;
  bool skipped = false;  ///< its window starts after the run's end: not evaluated (pass stays true)
};

class CheckSet {
 public:
  /// Binds every check to its signal column; throws InputError naming the
  /// check's file position and the unknown signal.
  CheckSet(const std::vector<CheckConfig>& checks, const std::vector<std::string>& columns);
  /// Feeds one row of the log (columns as given at construction) at time t.
  void Add(double time_s, const double* row);
  /// Final verdicts of a run that ended at end_s (simulated time).
  std::vector<CheckResult> Results(double end_s = std::numeric_limits<double>::infinity()) const;

 private:
  struct Accumulator {
    int column = 0;
    double max = -std::numeric_limits<double>::infinity();
    double min = std::numeric_limits<double>::infinity();
    double max_abs = 0.0, sum = 0.0, sum_sq = 0.0, last = 0.0, last_t = 0.0;
    long count = 0;
    // sub-windows: the one being filled, its extreme, and the reduction over the whole ones
    long window = -1;
    double window_extreme = 0.0;
    double windowed = std::numeric_limits<double>::quiet_NaN();
    long whole_windows = 0;
  };
  /// Folds the sub-window being filled into the windowed reduction.
  static void CloseWindow(Reduce reduce, Accumulator& a);
  std::vector<CheckConfig> checks_;
  std::vector<Accumulator> acc_;
};

}  // namespace vlab::lab
