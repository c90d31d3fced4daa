#include "lab/lab_checks.h"

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
      throw InputError(checks_[i].where + ": check '" + checks_[i].name + "': unknown signal '" +
                       checks_[i].signal + "' (see the log columns: vlab run --list-signals)");
    }
    acc_[i].column = static_cast<int>(it - columns.begin());
  }
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
    ++a.count;
  }
}

std::vector<CheckResult> CheckSet::Results() const {
  std::vector<CheckResult> results;
  for (std::size_t i = 0; i < checks_.size(); ++i) {
    const CheckConfig& c = checks_[i];
    const Accumulator& a = acc_[i];
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
      }
    }
    r.pass = std::isfinite(r.value) && r.value >= c.min && r.value <= c.max;
    results.push_back(r);
  }
  return results;
}

}  // namespace vlab::lab
