#include "lab/judge/lab_checks.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/core_errors.h"

namespace vlab::lab {

CheckSet::CheckSet(const std::vector<CheckConfig>& checks, const std::vector<std::string>& columns)
    : checks_(checks), acc_(checks.size()) {
  for (std::size_t i = 0; i < checks_.size(); ++i) {
    const auto it = std::find(columns.begin(), columns.end(), checks_[i].signal);
    if (it == columns.end()) {
      throw InputError(checks_[i].where + ": check '" + checks_[i].name + "': unknown signal '" + checks_[i].signal +
                       "' (see the log columns: vlab run --list-signals)");
    }
    acc_[i].column = static_cast<int>(it - columns.begin());
  }
}

namespace {

bool TakesLargest(Reduce r) { return r == Reduce::kMinOfWindowMax; }

// a NaN anywhere stays NaN: std::max / std::min would silently drop it
double Larger(double a, double b) { return (std::isnan(a) || std::isnan(b)) ? std::nan("") : std::max(a, b); }
double Smaller(double a, double b) { return (std::isnan(a) || std::isnan(b)) ? std::nan("") : std::min(a, b); }

}  // namespace

void CheckSet::CloseWindow(Reduce reduce, Accumulator& a) {
  if (a.window < 0) return;
  // min of the maxima, or max of the minima
  const bool first = a.whole_windows == 0;
  if (TakesLargest(reduce)) {
    a.windowed = first ? a.window_extreme : Smaller(a.windowed, a.window_extreme);
  } else {
    a.windowed = first ? a.window_extreme : Larger(a.windowed, a.window_extreme);
  }
  ++a.whole_windows;
}

void CheckSet::Add(double t, const double* row) {
  for (std::size_t i = 0; i < checks_.size(); ++i) {
    if (t < checks_[i].from_s || t > checks_[i].to_s) continue;
    Accumulator& a = acc_[i];
    const double v = row[a.column];
    // NaN must fail max/min checks: std::max would silently drop it
    a.max = (std::isnan(v) || std::isnan(a.max)) ? std::numeric_limits<double>::quiet_NaN() : std::max(a.max, v);
    a.min = (std::isnan(v) || std::isnan(a.min)) ? std::numeric_limits<double>::quiet_NaN() : std::min(a.min, v);
    a.max_abs = (std::isnan(v) || std::isnan(a.max_abs)) ? std::numeric_limits<double>::quiet_NaN()
                                                         : std::max(a.max_abs, std::abs(v));
    a.sum += v;
    a.sum_sq += v * v;
    a.last = v;
    a.last_t = t;
    ++a.count;
    if (checks_[i].window_s > 0.0) {
      // sub-window k holds [from + k w, from + (k + 1) w); a sample in a later one closes it whole
      const long k = static_cast<long>(std::floor((t - checks_[i].from_s) / checks_[i].window_s));
      if (k != a.window) {
        CloseWindow(checks_[i].reduce, a);
        // a whole sub-window without a sample (window shorter than the log's period) has no extreme
        if (k > a.window + 1) a.windowed = std::nan(""), ++a.whole_windows;
        a.window = k;
        a.window_extreme = v;
      } else {
        a.window_extreme = TakesLargest(checks_[i].reduce) ? Larger(a.window_extreme, v) : Smaller(a.window_extreme, v);
      }
    }
  }
}

std::vector<CheckResult> CheckSet::Results(double end_s) const {
  std::vector<CheckResult> results;
  for (std::size_t i = 0; i < checks_.size(); ++i) {
    const CheckConfig& c = checks_[i];
    Accumulator a = acc_[i];
    CheckResult r;
    r.config = c;
    r.samples = a.count;
    if (a.count == 0) {
      r.value = std::numeric_limits<double>::quiet_NaN();
    } else {
      switch (c.reduce) {
        case Reduce::kMax:
          r.value = a.max;
          break;
        case Reduce::kMin:
          r.value = a.min;
          break;
        case Reduce::kMean:
          r.value = a.sum / a.count;
          break;
        case Reduce::kRms:
          r.value = std::sqrt(a.sum_sq / a.count);
          break;
        case Reduce::kFinal:
          r.value = a.last;
          break;
        case Reduce::kMaxAbs:
          r.value = a.max_abs;
          break;
        case Reduce::kRange:
          r.value = a.max - a.min;  // NaN when either is
          break;
        case Reduce::kMinOfWindowMax:
        case Reduce::kMaxOfWindowMin: {
          // the last sub-window counts only when whole: it ends by `to` and by the last sample
          const double end_s = c.from_s + static_cast<double>(a.window + 1) * c.window_s;
          if (end_s <= std::min(c.to_s, a.last_t) + 1e-9 * c.window_s) {
            CloseWindow(c.reduce, a);
          }
          r.value = a.whole_windows > 0 ? a.windowed : std::numeric_limits<double>::quiet_NaN();
          break;
        }
      }
    }
    r.pass = std::isfinite(r.value) && r.value >= c.min && r.value <= c.max;
    if (a.count == 0 && c.from_s > end_s) {  // a shortened run never reached the window
      r.skipped = true;
      r.pass = true;
    }
    results.push_back(r);
  }
  return results;
}

}  // namespace vlab::lab
