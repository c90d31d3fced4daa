// vlab bench task: the cost of the task-language runtime in the lab's period.
//
// Two scenarios with the same scene, devices, path and duration, timed in the
// same process, best of --repeat each, alternating:
//   a. scenes/pa10_reach       the built-in task_space controller
//   b. scenes/pa10_reach_task  the same square as a task script
//                              (scenes/tasks/reach_square.lua): Lua resumes,
//                              the motion planner's IK, the in-process channels
// Prints the mean period time of each (loop wall time / periods) and the
// ratio b/a (goal <= 1.2), after the CPUs the process may use. Both runs
// write log.csv (into a temporary folder), as `vlab run` does.
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <limits>

#include "cli/cli_commands.h"
#include "cli/cli_cpus.h"
#include "core/core_errors.h"
#include "core/core_realtime.h"
#include "lab/run/lab_runner.h"
#include "lab/scenario/lab_scenario.h"

namespace vlab::cli {

int BenchTask(const BenchArgs& args) {
  return WithErrorReport([&args] {
    lab::Scenario builtin = lab::LoadScenario(lab::ResolveScenarioPath("scenes/pa10_reach"));
    lab::Scenario script =
        lab::LoadScenario(lab::ResolveScenarioPath(args.scenario.empty() ? "scenes/pa10_reach_task" : args.scenario));
    if (args.duration_s > 0) builtin.duration_s = script.duration_s = args.duration_s;
    if (script.controller.type != lab::ControllerType::kTask) {
      throw InputError(script.file + ": bench task needs a scenario whose controller is of type task");
    }
    const std::string out_dir =
        (std::filesystem::temp_directory_path() / ("vlab-bench-task-" + std::to_string(::getpid()))).string();
    const std::vector<int> allowed = ThreadCpus();
    std::printf("vlab bench task: %s (built-in task_space) vs %s (task script), %.2f s simulated each, best of %d\n",
                builtin.name.c_str(), script.name.c_str(), builtin.duration_s, args.repeat);
    std::printf("  CPUs: %zu allowed (%s) of %ld online; log.csv written by both\n", allowed.size(),
                CpuListText(allowed).c_str(), sysconf(_SC_NPROCESSORS_ONLN));
    double best_a = std::numeric_limits<double>::infinity(), best_b = best_a;
    bool passed = true;
    for (int i = 0; i < args.repeat; ++i) {
      for (int which = 0; which < 2; ++which) {
        lab::RunOptions options;
        options.out_dir = out_dir;
        // a fresh lab per run: the same start for both (creation is not timed)
        const std::unique_ptr<lab::Lab> lab = lab::Lab::Create(which == 0 ? builtin : script);
        const lab::RunResult r = lab->Run(options);
        if (r.exit_code != 0 && passed) {
          std::printf("  %s failed: %s\n", (which == 0 ? builtin : script).name.c_str(), r.failure.c_str());
        }
        passed = passed && r.exit_code == 0;
        const double period_us = 1e6 * r.loop_wall_s / std::max<long>(1, r.periods);
        double& best = which == 0 ? best_a : best_b;
        best = std::min(best, period_us);
      }
    }
    std::error_code ec;
    std::filesystem::remove_all(out_dir, ec);
    const double ratio = best_b / best_a;
    std::printf("    a. built-in task_space controller  %8.1f us per period (%.0fx real time)\n", best_a,
                1e6 * builtin.control_period_s / best_a);
    std::printf("    b. task script (Lua + planner)     %8.1f us per period (%.0fx real time)  ratio b/a %.3f\n",
                best_b, 1e6 * script.control_period_s / best_b, ratio);
    std::printf("  both runs passed their checks: %s\n", passed ? "yes" : "NO");
    std::printf("  goal: b/a <= 1.2 -> %s\n", ratio <= 1.2 ? "met" : "NOT met");
    return passed ? 0 : 1;
  });
}

}  // namespace vlab::cli
