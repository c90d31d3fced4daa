// vlab collect DIR: one CSV row per run of a sweep folder, a summary line, and
// optionally a plot of a check against a swept parameter.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>

#include "cli/cli_commands.h"
#include "core/core_errors.h"
#include "lab/sweep/lab_collect.h"

namespace vlab::cli {

namespace {

struct CollectArgs {
  std::string dir;
  std::string csv;  // "" = stdout
  bool no_timings = false;
  std::string plot, x, y;
};

int Collect(const CollectArgs& a) {
  if (!a.plot.empty() && (a.x.empty() || a.y.empty())) throw InputError("--plot needs --x KEY and --y CHECK");
  const lab::CollectedTable t = lab::CollectRuns(a.dir, !a.no_timings);
  const std::string csv = lab::CollectedCsv(t);
  if (a.csv.empty()) {
    std::fputs(csv.c_str(), stdout);
  } else {
    const std::string tmp = a.csv + ".partial";
    {
      std::ofstream out(tmp);
      if (!out) throw InputError(a.csv + ": cannot write");
      out << csv;
    }
    std::filesystem::rename(tmp, a.csv);
  }
  if (!a.plot.empty()) lab::PlotCollected(t, a.x, a.y, a.plot);
  const std::string table = a.csv.empty() ? "" : "; table in " + a.csv;
  const std::string plot = a.plot.empty() ? "" : "; plot in " + a.plot;
  std::fprintf(stderr, "collect %s: %zu runs: %d pass, %d failed, %d interrupted%s%s\n", a.dir.c_str(), t.rows.size(),
               t.pass, t.failed, t.interrupted, table.c_str(), plot.c_str());
  return 0;
}

}  // namespace

Subcommand AddCollectCommand(CLI::App& app) {
  auto args = std::make_shared<CollectArgs>();
  CLI::App* cmd = app.add_subcommand(
      "collect",
      "One CSV row per run of a sweep folder (id, seed, overrides, verdict, each check's value and "
      "verdict, timings) and a summary line; optionally a plot of a check against a swept parameter");
  cmd->add_option("dir", args->dir, "Sweep folder (DIR/ID/summary.json)")->required();
  cmd->add_option("-o,--csv", args->csv, "Write the table to this file (default: stdout)");
  cmd->add_flag("--no-timings", args->no_timings, "Leave out the timing columns (tables of two engines then compare)");
  cmd->add_option("--plot", args->plot, "Draw a check against a parameter into this PNG");
  cmd->add_option("--x", args->x, "--plot: the override KEY (as in --set) or seed on the horizontal axis");
  cmd->add_option("--y", args->y, "--plot: the check name whose value is drawn");
  return {cmd, [args] { return WithErrorReport([&] { return Collect(*args); }); }};
}

}  // namespace vlab::cli
