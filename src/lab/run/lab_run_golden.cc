// Golden checks of a run (CheckConfig::golden): after the run, its log.csv is compared
// with the golden log within the tolerances; the report goes beside it as
// golden_NAME.txt, and the check's value is the worst divergence in multiples of its
// tolerance.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "lab/judge/lab_compare.h"
#include "lab/judge/lab_golden.h"
#include "lab/outputs/lab_log.h"
#include "lab/run/lab_run_session.h"

namespace vlab::lab {

namespace {

namespace fs = std::filesystem;

// The options of a golden check: its own tolerances, then a golden folder's.
CompareOptions GoldenOptions(const CheckConfig& c, std::string* golden_log) {
  CompareOptions o;
  o.tolerances = c.tolerances;
  o.from_s = c.from_s;
  o.to_s = c.to_s;
  *golden_log = c.golden;
  if (fs::is_directory(c.golden)) {
    *golden_log = c.golden + "/log.csv";
    if (fs::is_regular_file(c.golden + "/golden.yaml")) {
      const GoldenSpec spec = LoadGolden(c.golden);
      o.tolerances.insert(o.tolerances.end(), spec.compare.tolerances.begin(), spec.compare.tolerances.end());
    }
  }
  return o;
}

}  // namespace

void RunSession::EvaluateGoldenChecks() {
  const double end_s = result_.sim_time_s;
  for (const CheckConfig& c : s_.scenario.checks) {
    if (c.golden.empty()) continue;
    CheckResult r;
    r.config = c;
    r.pass = true;
    if (c.from_s > end_s) {  // a shortened or interrupted run: as a signal check's window
      r.skipped = true;
      r.value = std::nan("");
      result_.checks.push_back(r);
      continue;
    }
    std::string golden_log;
    CompareOptions o = GoldenOptions(c, &golden_log);
    o.to_s = std::min(o.to_s, end_s);  // what the run reached
    CompareReport report = CompareLogs(ReadCsvTable(out_->File("log.csv")), ReadCsvTable(golden_log), o);
    report.run_file = "this run's log.csv";
    r.samples = report.golden_rows;
    r.value = 0.0;
    for (const ColumnReport& col : report.columns) {
      if (col.missing) r.value = INFINITY;
      if (col.out > 0) r.value = std::max(r.value, col.worst.excess);
    }
    if (!report.coverage_failure.empty()) r.value = INFINITY;
    r.pass = report.pass();
    std::ofstream text(out_->File("golden_" + c.name + ".txt"));
    text << FormatCompareReport(report, true);
    if (!r.pass && !result_.interrupted_by) {
      if (result_.failure.empty()) {
        result_.failure = "check '" + c.name + "' failed: log.csv diverges from the golden " + golden_log + " (" +
                          std::to_string(report.failing()) + " columns; see golden_" + c.name + ".txt)";
      }
      result_.exit_code = 1;
    }
    result_.checks.push_back(r);
  }
}

}  // namespace vlab::lab
