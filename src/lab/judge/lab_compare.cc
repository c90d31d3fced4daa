#include "lab/judge/lab_compare.h"

#include <fnmatch.h>

#include <cmath>
#include <sstream>

#include "core/core_errors.h"
#include "lab/outputs/lab_log.h"

namespace vlab::lab {

namespace {

const ColumnTolerance& ToleranceOf(const std::string& column, const CompareOptions& options) {
  static const ColumnTolerance kExact{"(none: exact)", 0.0, 0.0, false};
  for (const ColumnTolerance& t : options.tolerances) {
    if (fnmatch(t.pattern.c_str(), column.c_str(), 0) == 0) return t;
  }
  return kExact;
}

// |run - golden| against the tolerance: the excess ratio, 0 when within.
double Excess(double run, double golden, const ColumnTolerance& t) {
  if (std::isnan(run) || std::isnan(golden)) return std::isnan(run) && std::isnan(golden) ? 0.0 : INFINITY;
  if (run == golden) return 0.0;  // also equal infinities
  const double diff = std::fabs(run - golden);
  const double allowed = t.abs + t.rel * std::fabs(golden);
  if (diff <= allowed) return 0.0;
  return allowed > 0 ? diff / allowed : INFINITY;
}

std::string Tol(const ColumnTolerance& t) {
  if (t.abs == 0 && t.rel == 0) return "exact";
  std::string s;
  if (t.abs > 0) s += "abs " + FormatDouble(t.abs);
  if (t.rel > 0) s += std::string(s.empty() ? "" : " + ") + "rel " + FormatDouble(t.rel);
  return s;
}

std::string Point(const Divergence& d) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "t = %s s: run %s, golden %s (|d| %.3g", FormatDouble(d.time_s).c_str(),
                FormatDouble(d.run).c_str(), FormatDouble(d.golden).c_str(), std::fabs(d.run - d.golden));
  std::string s = buf;
  if (std::isfinite(d.excess)) {
    std::snprintf(buf, sizeof buf, ", %.3gx the tolerance)", d.excess);
    s += buf;
  } else {
    s += ")";
  }
  return s;
}

}  // namespace

bool CompareReport::pass() const { return coverage_failure.empty() && failing() == 0 && golden_rows > 0; }

long CompareReport::failing() const {
  long n = 0;
  for (const ColumnReport& c : columns) n += c.pass() ? 0 : 1;
  return n;
}

CompareReport CompareLogs(const CsvTable& run, const CsvTable& golden, const CompareOptions& options) {
  CompareReport report;
  report.run_file = run.file;
  report.golden_file = golden.file;
  const int rt = run.Column(options.time_column), gt = golden.Column(options.time_column);
  if (rt < 0) throw InputError(run.file + ": no '" + options.time_column + "' column");
  if (gt < 0) throw InputError(golden.file + ": no '" + options.time_column + "' column");

  // the window: the golden's rows inside [from, to]; the run must span them
  std::vector<std::size_t> golden_rows;
  for (std::size_t i = 0; i < golden.rows.size(); ++i) {
    const double t = golden.rows[i][gt];
    if (t >= options.from_s && t <= options.to_s) golden_rows.push_back(i);
  }
  report.golden_rows = static_cast<long>(golden_rows.size());
  if (golden_rows.empty()) {
    report.coverage_failure = "the golden has no rows in the compared window";
    return report;
  }
  report.from_s = golden.rows[golden_rows.front()][gt];
  report.to_s = golden.rows[golden_rows.back()][gt];
  const double run_first = run.rows.empty() ? NAN : run.rows.front()[rt];
  const double run_last = run.rows.empty() ? NAN : run.rows.back()[rt];
  if (run.rows.empty() || run_first > report.from_s || run_last < report.to_s) {
    report.coverage_failure = "the run's log covers t = " + FormatDouble(run_first) + " .. " + FormatDouble(run_last) +
                              " s, the golden's window is " + FormatDouble(report.from_s) + " .. " +
                              FormatDouble(report.to_s) + " s";
    return report;
  }

  // columns: golden's, with their run column (or missing)
  std::vector<int> run_index;
  for (std::size_t c = 0; c < golden.columns.size(); ++c) {
    if (static_cast<int>(c) == gt) continue;
    const ColumnTolerance& tol = ToleranceOf(golden.columns[c], options);
    if (tol.ignore) {
      report.ignored.push_back(golden.columns[c]);
      continue;
    }
    ColumnReport col;
    col.column = golden.columns[c];
    col.tolerance = tol;
    const int r = run.Column(col.column);
    col.missing = r < 0;
    report.columns.push_back(col);
    run_index.push_back(r);
  }
  for (const std::string& name : run.columns) {
    if (golden.Column(name) < 0) report.run_only.push_back(name);
  }
  std::vector<int> golden_index;
  for (const ColumnReport& col : report.columns) golden_index.push_back(golden.Column(col.column));

  // walk the golden's rows and the run's in time order
  std::size_t k = 0;  // run row with time <= t
  for (std::size_t gi : golden_rows) {
    const std::vector<double>& g = golden.rows[gi];
    const double t = g[gt];
    while (k + 1 < run.rows.size() && run.rows[k + 1][rt] <= t) ++k;
    const std::vector<double>& a = run.rows[k];
    const bool exact = a[rt] == t || k + 1 >= run.rows.size();
    const std::vector<double>& b = exact ? a : run.rows[k + 1];
    const double w = exact ? 0.0 : (t - a[rt]) / (b[rt] - a[rt]);
    for (std::size_t c = 0; c < report.columns.size(); ++c) {
      ColumnReport& col = report.columns[c];
      if (col.missing) continue;
      const int r = run_index[c];
      const double value = exact ? a[r] : a[r] + w * (b[r] - a[r]);
      const double expected = g[golden_index[c]];
      ++col.compared;
      const double diff = std::fabs(value - expected);
      if (std::isnan(value) != std::isnan(expected)) {
        col.max_abs_diff = INFINITY;
      } else if (diff > col.max_abs_diff) {
        col.max_abs_diff = diff;
      }
      const double excess = Excess(value, expected, col.tolerance);
      if (excess == 0.0) continue;
      const Divergence d{t, value, expected, excess};
      if (col.out == 0) col.first = d;
      if (col.out == 0 || excess > col.worst.excess ||
          (excess == col.worst.excess && diff > std::fabs(col.worst.run - col.worst.golden))) {
        col.worst = d;
      }
      ++col.out;
    }
  }
  return report;
}

std::string FormatCompareReport(const CompareReport& r, bool all) {
  std::ostringstream s;
  s << "compare " << r.run_file << " with golden " << r.golden_file << "\n";
  if (!r.coverage_failure.empty()) {
    s << "  FAIL: " << r.coverage_failure << "\n";
  } else {
    s << "  " << r.golden_rows << " golden rows over t = " << FormatDouble(r.from_s) << " .. " << FormatDouble(r.to_s)
      << " s, " << r.columns.size() << " columns compared";
    if (!r.ignored.empty()) s << ", " << r.ignored.size() << " ignored";
    if (!r.run_only.empty()) s << ", " << r.run_only.size() << " only in the run (not compared)";
    s << "\n";
    for (const ColumnReport& c : r.columns) {
      if (c.missing) {
        s << "  FAIL " << c.column << ": not in the run's log\n";
      } else if (!c.pass()) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%.3g", c.max_abs_diff);
        s << "  FAIL " << c.column << " (" << Tol(c.tolerance) << "): " << c.out << " of " << c.compared
          << " rows out, max |d| " << buf << "\n"
          << "       first " << Point(c.first) << "\n"
          << "       worst " << Point(c.worst) << "\n";
      } else if (all) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%.3g", c.max_abs_diff);
        s << "  pass " << c.column << " (" << Tol(c.tolerance) << "): max |d| " << buf << "\n";
      }
    }
  }
  if (r.pass()) {
    s << "result: pass (" << r.columns.size() << " columns within tolerance)\n";
  } else if (!r.coverage_failure.empty()) {
    s << "result: FAIL (the run does not cover the golden)\n";
  } else {
    s << "result: FAIL (" << r.failing() << " of " << r.columns.size() << " columns diverge)\n";
  }
  return s.str();
}

}  // namespace vlab::lab
