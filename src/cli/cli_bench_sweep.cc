// vlab bench sweep: runs per minute of `vlab sweep -j 2` against `-j 1`, the same
// sweep in the same process, best of --repeat each. The goal on 2 free cores is a
// ratio of at least 1.8 (the runs are independent processes; what is left is the
// sweep's own waiting, the cores' shared caches and memory bandwidth, and the last
// round: n equal runs on 2 cores take ceil(n/2) rounds, so b/a <= n / ceil(n/2),
// printed as the bound the sweep's run count allows).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include <unistd.h>

#include "cli/cli_commands.h"
#include "cli/cli_cpus.h"
#include "core/core_clock.h"
#include "core/core_errors.h"
#include "core/core_realtime.h"
#include "lab/scenario/lab_scenario.h"
#include "lab/sweep/lab_sweep.h"

namespace vlab::cli {

namespace {

namespace fs = std::filesystem;

constexpr const char* kDefaultSweep = "scenes/sweeps/pa10_gains_bench.yaml";

}  // namespace

int BenchSweep(const BenchArgs& args) {
  return WithErrorReport([&args] {
    lab::Sweep sweep = lab::LoadSweep(args.scenario.empty() ? kDefaultSweep : args.scenario);
    if (args.duration_s > 0) sweep.duration_s = args.duration_s;
    const lab::Scenario scenario = lab::LoadScenario(sweep.scenario, sweep.runs.at(0).sets);
    const std::vector<int> cpus = ThreadCpus();
    std::printf("CPUs: %zu allowed (%s); %ld online\n", cpus.size(), CpuListText(cpus).c_str(),
                ::sysconf(_SC_NPROCESSORS_ONLN));
    std::printf("sweep %s: %zu runs of %s%s, %.3g s simulated each\n", sweep.name.c_str(), sweep.runs.size(),
                sweep.scenario.c_str(), scenario.outputs.images.empty() ? " (no cameras)" : " (WITH camera images)",
                sweep.duration_s > 0 ? sweep.duration_s : scenario.duration_s);
    if (cpus.size() < 2) std::printf("note: fewer than 2 CPUs allowed: -j 2 cannot be faster\n");

    std::string work = (fs::temp_directory_path() / "vlab-bench-sweep-XXXXXX").string();
    if (!::mkdtemp(work.data())) throw std::runtime_error("cannot create a temporary folder");
    double best[3] = {0, 1e300, 1e300};  // by jobs
    int failures = 0;
    try {
      for (int r = 0; r < args.repeat; ++r) {
        for (int jobs : {1, 2}) {
          const std::string out = work + "/j" + std::to_string(jobs) + "_" + std::to_string(r);
          const double t0 = WallNow();
          failures += RunSweepHere(sweep, out, jobs, true) != 0;
          best[jobs] = std::min(best[jobs], WallNow() - t0);
          fs::remove_all(out);
        }
      }
    } catch (...) {
      fs::remove_all(work);
      throw;
    }
    fs::remove_all(work);
    const double n = static_cast<double>(sweep.runs.size());
    const double a = n / best[1] * 60.0, b = n / best[2] * 60.0;
    std::printf("(a) vlab sweep -j 1: %zu runs in %.2f s: %8.1f runs/min (best of %d)\n", sweep.runs.size(), best[1], a,
                args.repeat);
    std::printf("(b) vlab sweep -j 2: %zu runs in %.2f s: %8.1f runs/min (best of %d)   ratio b/a %.2f (goal >= 1.8)\n",
                sweep.runs.size(), best[2], b, args.repeat, b / a);
    const double rounds = std::ceil(n / 2.0);
    std::printf("    bound set by the run count: %zu runs in %.0f rounds of 2 -> b/a <= %.2f\n", sweep.runs.size(),
                rounds, n / rounds);
    if (failures) std::printf("note: %d of the sweeps had a run that did not pass\n", failures);
    return 0;
  });
}

}  // namespace vlab::cli
