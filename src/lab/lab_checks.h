// Checks: pass/fail rules over logged signals, evaluated while the run goes.
//
// Each check reduces one signal over a time window [from, to] (max, min, mean,
// rms, final or max_abs) and compares the result with its bounds. A check whose
// window holds no sample fails with value NaN.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "lab/lab_scenario.h"

namespace vlab::lab {

struct CheckResult {
  CheckConfig config;
  double value = 0.0;  ///< the reduced signal
  long samples = 0;    ///< samples inside the window
  bool pass = false;
};

class CheckSet {
 public:
  /// Binds every check to its signal column; throws InputError naming the
  /// check's file position and the unknown signal.
  CheckSet(const std::vector<CheckConfig>& checks, const std::vector<std::string>& columns);
  /// Feeds one row of the log (columns as given at construction) at time t.
  void Add(double time_s, const double* row);
  /// Final verdicts.
  std::vector<CheckResult> Results() const;

 private:
  struct Accumulator {
    int column = 0;
    double max = -std::numeric_limits<double>::infinity();
    double min = std::numeric_limits<double>::infinity();
    double max_abs = 0.0, sum = 0.0, sum_sq = 0.0, last = 0.0;
    long count = 0;
  };
  std::vector<CheckConfig> checks_;
  std::vector<Accumulator> acc_;
};

}  // namespace vlab::lab
