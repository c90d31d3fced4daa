// vlab compare RUN GOLDEN: two runs' logs, column by column, within tolerances.
// vlab golden GOLDEN...: run a golden's scenario and compare; --update rewrites it.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>

#include "bridge/bridge_signals.h"
#include "cli/cli_commands.h"
#include "core/core_errors.h"
#include "lab/judge/lab_compare.h"
#include "lab/judge/lab_golden.h"
#include "lab/outputs/lab_log.h"
#include "lab/outputs/lab_output.h"
#include "lab/run/lab_runner.h"
#include "lab/scenario/lab_scenario.h"

namespace vlab::cli {

namespace {

namespace fs = std::filesystem;

struct CompareArgs {
  std::string run, golden;
  std::vector<std::string> tolerances;  // GLOB=ABS[,REL]
  std::vector<std::string> ignore;      // GLOB
  double from_s = -INFINITY, to_s = INFINITY;
  bool all = false;
};

// A log file, or the log.csv of a run or golden folder.
std::string LogOf(const std::string& path) { return fs::is_directory(path) ? path + "/log.csv" : path; }

double ParseNumber(const std::string& text, const std::string& what) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !(v >= 0) || !std::isfinite(v)) {
    throw InputError(what + ": expected a number >= 0, got '" + text + "'");
  }
  return v;
}

lab::ColumnTolerance ParseTolerance(const std::string& text) {
  const std::size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0) throw InputError("--tol '" + text + "': expected GLOB=ABS or GLOB=ABS,REL");
  lab::ColumnTolerance t;
  t.pattern = text.substr(0, eq);
  const std::string values = text.substr(eq + 1);
  const std::size_t comma = values.find(',');
  t.abs = ParseNumber(values.substr(0, comma), "--tol " + text + ": ABS");
  if (comma != std::string::npos) t.rel = ParseNumber(values.substr(comma + 1), "--tol " + text + ": REL");
  return t;
}

int Compare(const CompareArgs& a) {
  lab::CompareOptions options;
  for (const std::string& t : a.tolerances) options.tolerances.push_back(ParseTolerance(t));
  for (const std::string& g : a.ignore) options.tolerances.push_back({g, 0.0, 0.0, true});
  options.from_s = a.from_s;
  options.to_s = a.to_s;
  // a golden folder brings its own tolerances and window, after the command line's
  if (fs::is_regular_file(a.golden + "/golden.yaml")) {
    const lab::GoldenSpec spec = lab::LoadGolden(a.golden);
    for (const auto& t : spec.compare.tolerances) options.tolerances.push_back(t);
    if (!std::isfinite(a.from_s)) options.from_s = spec.compare.from_s;
    if (!std::isfinite(a.to_s)) options.to_s = spec.compare.to_s;
  }
  const lab::CsvTable run = lab::ReadCsvTable(LogOf(a.run));
  const lab::CsvTable golden = lab::ReadCsvTable(LogOf(a.golden));
  const lab::CompareReport report = lab::CompareLogs(run, golden, options);
  std::fputs(lab::FormatCompareReport(report, a.all).c_str(), stdout);
  return report.pass() ? 0 : 1;
}

struct GoldenArgs {
  std::vector<std::string> dirs;
  bool update = false;
  bool all = false;
  std::string keep;  // write the runs here (DIR/NAME) instead of a temporary folder
};

// Runs the golden's scenario into out_dir; returns the run's exit code.
int RunGolden(const lab::GoldenSpec& g, const std::string& out_dir) {
  lab::Scenario scenario = lab::LoadScenario(g.scenario, g.sets);
  if (g.duration_s > 0) scenario.duration_s = g.duration_s;
  if (g.seed >= 0) scenario.seed = static_cast<std::uint64_t>(g.seed);
  std::unique_ptr<lab::Lab> lab = lab::Lab::Create(scenario);
  lab::RunOptions options;
  options.out_dir = out_dir;
  options.interrupt = &g_stop_requested;
  const lab::RunResult r = lab->Run(options);
  std::printf("%s: run %s, %.2f s simulated in %.2f s\n", g.dir.c_str(), Verdict(r), r.sim_time_s, r.loop_wall_s);
  if (r.exit_code != 0) std::fprintf(stderr, "vlab: %s: %s\n", g.dir.c_str(), r.failure.c_str());
  return r.exit_code;
}

int OneGolden(const GoldenArgs& a, const std::string& dir, const std::string& work) {
  const lab::GoldenSpec g = lab::LoadGolden(dir);
  const std::string out = work + "/" + fs::path(dir).lexically_normal().filename().string();
  const int code = RunGolden(g, out);
  if (code != 0) {
    std::printf("%s: the run did not pass; %s\n", dir.c_str(), a.update ? "golden not updated" : "not compared");
    return 1;
  }
  // the run's log, thinned as the golden keeps it, so both hold the same rows
  const std::string thinned = out + "/golden_log.csv";
  lab::WriteDecimatedLog(out + "/log.csv", thinned, g.every);
  lab::AddToOutputList(out, "golden_log.csv");  // vlab's too: a later --keep run into DIR replaces it
  if (!a.update) {
    if (!fs::is_regular_file(g.log()))
      throw InputError(g.log() + ": no golden log yet (write it: vlab golden --update " + dir + ")");
    lab::CompareReport report = lab::CompareLogs(lab::ReadCsvTable(thinned), lab::ReadCsvTable(g.log()), g.compare);
    report.run_file = "a new run of " + g.scenario;
    std::fputs(lab::FormatCompareReport(report, a.all).c_str(), stdout);
    return report.pass() ? 0 : 1;
  }
  // --update: say what changed against the old golden (exact comparison), then replace it
  if (fs::is_regular_file(g.log())) {
    lab::CompareOptions exact = g.compare;
    exact.tolerances.clear();
    for (const auto& t : g.compare.tolerances) {
      if (t.ignore) exact.tolerances.push_back(t);
    }
    lab::CompareReport change = lab::CompareLogs(lab::ReadCsvTable(thinned), lab::ReadCsvTable(g.log()), exact);
    change.run_file = "a new run of " + g.scenario;
    const lab::CompareReport within =
        lab::CompareLogs(lab::ReadCsvTable(thinned), lab::ReadCsvTable(g.log()), g.compare);
    std::printf("changes against the old golden (exact comparison; %s the golden's tolerances):\n",
                within.pass() ? "all within" : "NOT within");
    std::fputs(lab::FormatCompareReport(change, a.all).c_str(), stdout);
  } else {
    std::printf("%s: new golden\n", dir.c_str());
  }
  lab::WriteDecimatedLog(out + "/log.csv", g.log(), g.every);
  std::printf("%s: written (every %d-th row of the run's log)\n", g.log().c_str(), g.every);
  return 0;
}

int Golden(const GoldenArgs& a) {
  InstallStopSignals();
  std::string work = a.keep;
  bool temporary = false;
  if (work.empty()) {
    std::string pattern = (fs::temp_directory_path() / "vlab-golden-XXXXXX").string();
    if (!::mkdtemp(pattern.data()))
      throw std::runtime_error("cannot create a temporary folder in " + fs::temp_directory_path().string());
    work = pattern;
    temporary = true;
  }
  int worst = 0;
  try {
    for (const std::string& dir : a.dirs) worst = std::max(worst, OneGolden(a, dir, work));
  } catch (...) {
    if (temporary) fs::remove_all(work);
    throw;
  }
  if (temporary) fs::remove_all(work);
  return worst;
}

}  // namespace

Subcommand AddCompareCommand(CLI::App& app) {
  auto args = std::make_shared<CompareArgs>();
  CLI::App* cmd = app.add_subcommand(
      "compare",
      "Compare a run's log with a golden log column by column within tolerances; print the first and the "
      "worst divergence of each diverging column; exit 0 all within, 1 not");
  cmd->add_option("run", args->run, "The run: its output folder or a log CSV")->required();
  cmd->add_option(
         "golden", args->golden,
         "The golden: a golden folder (its golden.yaml's tolerances apply after --tol), a run folder or a log CSV")
      ->required();
  cmd->add_option("--tol", args->tolerances,
                  "GLOB=ABS[,REL]: columns matching GLOB may differ by ABS + REL*|golden| (first match wins; a column "
                  "no pattern matches must be equal); repeatable")
      ->allow_extra_args(false);
  cmd->add_option("--ignore", args->ignore, "GLOB: columns not compared; repeatable")->allow_extra_args(false);
  cmd->add_option("--from", args->from_s, "Compare golden rows from this time, s");
  cmd->add_option("--to", args->to_s, "Compare golden rows up to this time, s");
  cmd->add_flag("--all", args->all, "One line per compared column (its largest difference), not only failing ones");
  return {cmd, [args] { return WithErrorReport([&] { return Compare(*args); }); }};
}

Subcommand AddGoldenCommand(CLI::App& app) {
  auto args = std::make_shared<GoldenArgs>();
  CLI::App* cmd = app.add_subcommand(
      "golden",
      "Run each golden's scenario (GOLDEN/golden.yaml) and compare its log with GOLDEN/log.csv; with "
      "--update, print what changed and rewrite GOLDEN/log.csv instead");
  cmd->add_option("golden", args->dirs, "Golden folders (e.g. tests/goldens/pa10_reach)")->required();
  cmd->add_flag("--update", args->update, "Regenerate: rewrite GOLDEN/log.csv from a new run, printing what changed");
  cmd->add_flag("--all", args->all, "One line per compared column, not only failing ones");
  cmd->add_option("--keep", args->keep, "Keep the runs in DIR/NAME (default: a temporary folder, removed)");
  return {cmd, [args] { return WithErrorReport([&] { return Golden(*args); }); }};
}

}  // namespace vlab::cli
