#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include <unistd.h>

#include "bridge/bridge_signals.h"
#include "cli/cli_commands.h"
#include "core/core_clock.h"
#include "core/core_errors.h"
#include "lab/outputs/lab_log.h"
#include "lab/run/lab_runner.h"
#include "lab/scenario/lab_overrides.h"
#include "lab/scenario/lab_scenario.h"

namespace vlab::cli {

namespace {

std::string Bound(const lab::CheckConfig& c) {
  std::string text;
  if (std::isfinite(c.min)) text += ">= " + lab::FormatDouble(c.min);
  if (std::isfinite(c.max)) text += std::string(text.empty() ? "" : ", ") + "<= " + lab::FormatDouble(c.max);
  return text;
}

}  // namespace

ProgressBar::ProgressBar(bool enabled) : enabled_(enabled && ::isatty(2)), start_s_(WallNow()) {}

void ProgressBar::Update(double fraction) {
  if (!enabled_ || WallNow() - start_s_ < 1.0) return;
  constexpr int kWidth = 40;
  const int filled = static_cast<int>(fraction * kWidth);
  std::string bar(filled, '#');
  bar.append(kWidth - filled, '.');
  std::fprintf(stderr, "\r[%s] %3d%%", bar.c_str(), static_cast<int>(fraction * 100));
  std::fflush(stderr);
  drawn_ = true;
}

void ProgressBar::Finish() {
  if (drawn_) std::fprintf(stderr, "\r%*s\r", 48, "");
  drawn_ = false;
}

const char* Verdict(const lab::RunResult& result) {
  return result.interrupted_by ? "INTERRUPTED" : result.exit_code == 0 ? "pass" : "FAIL";
}

void PrintPlots(const lab::Scenario& scenario, const std::string& out_dir, const lab::RunResult& result) {
  for (const lab::PlotConfig& plot : scenario.outputs.plots) {
    const std::string file = out_dir + "/" + plot.file;
    if (std::filesystem::exists(file)) std::printf("plot: %s\n", file.c_str());
  }
  for (const std::string& why : result.plots_skipped) std::printf("plot skipped: %s\n", why.c_str());
}

void PrintRealtime(const std::string& line) {
  std::fprintf(stderr, "vlab: %s\n", line.c_str());
  std::fflush(stderr);
}

int WithErrorReport(const std::function<int()>& body) {
  try {
    return body();
  } catch (const vlab::InputError& e) {
    std::fprintf(stderr, "vlab: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vlab: error: %s\n", e.what());
    return 1;
  }
}

int RunCommand(const RunArgs& args) {
  return WithErrorReport([&args] {
    // SIGINT, SIGTERM: the run stops at the next period and writes what ran (exit 1); installed
    // before loading, so that one during loading stops the run at t = 0 instead of being lost
    InstallStopSignals();
    std::vector<std::string> sets;
    if (!args.overrides_file.empty()) sets = lab::ReadOverridesFile(args.overrides_file);
    sets.insert(sets.end(), args.sets.begin(), args.sets.end());
    lab::Scenario scenario = lab::LoadScenario(lab::ResolveScenarioPath(args.scenario), sets);
    if (args.duration_s > 0) scenario.duration_s = args.duration_s;
    if (args.seed >= 0) scenario.seed = static_cast<std::uint64_t>(args.seed);
    std::unique_ptr<lab::Lab> lab = lab::Lab::Create(scenario);
    if (args.list_signals) {
      for (const auto& c : lab->Columns()) std::cout << c << "\n";
      return 0;
    }
    const std::string out_dir = args.out_dir.empty() ? "out/" + scenario.name : args.out_dir;
    ProgressBar bar(!args.quiet);
    lab::RunOptions options;
    options.out_dir = out_dir;
    options.interrupt = &g_stop_requested;
    options.progress = [&bar](double f) { bar.Update(f); };
    if (args.rt_priority >= 0) options.realtime_priority = args.rt_priority;
    if (!args.quiet) options.on_realtime = PrintRealtime;
    options.quiet = args.quiet;
    const lab::RunResult r = lab->Run(options);
    bar.Finish();

    if (!args.quiet) {
      for (const auto& c : r.checks) {
        std::printf("  %s  %-28s %s(%s) = %s  (%s)\n",
                    c.skipped ? "skip"
                    : c.pass  ? "pass"
                              : "FAIL",
                    c.config.name.c_str(), lab::ReduceName(c.config.reduce), c.config.signal.c_str(),
                    lab::FormatDouble(c.value).c_str(), Bound(c.config).c_str());
      }
    }
    const double rtf = r.loop_wall_s > 0 ? r.sim_time_s / r.loop_wall_s : 0.0;
    std::printf("%s: %s, %.2f s simulated in %.2f s (%.0fx real time); output in %s/\n", scenario.name.c_str(),
                Verdict(r), r.sim_time_s, r.loop_wall_s, rtf, r.out_dir.c_str());
    PrintPlots(scenario, r.out_dir, r);
    if (!r.out_note.empty()) std::fprintf(stderr, "vlab: %s\n", r.out_note.c_str());
    if (r.exit_code != 0) std::fprintf(stderr, "vlab: %s\n", r.failure.c_str());
    return r.exit_code;
  });
}

}  // namespace vlab::cli
