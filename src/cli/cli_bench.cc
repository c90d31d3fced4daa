// vlab bench physics: the lab's step loop against bare mj_step, same run.
//
// 1. One untimed lab run records the controller's commands and the motor
//    controls of every physics step.
// 2. Timed, best of --repeat each, the loop on the first CPU allowed (it does
//    not migrate, as a realtime loop that keeps a CPU; the log writer is free
//    on all the CPUs allowed, so mostly on another):
//    a. bare mj_step on a fresh mjData of the same model, replaying the
//       recorded motor controls: exactly the physics the lab computed;
//    b. the lab loop with the recorded commands replayed: arm servo, JR3
//       model at 8 kHz, log.csv (writer thread), checks — the lab's own cost;
//    c. the full lab loop with the built-in controller computing live.
// 3. a and b again, best of --repeat, with the whole process on that one CPU.
// The ratio b / a is the fraction of raw engine speed the lab keeps with the
// JR3 model and logging on (goal >= 0.90): the median over the repeats of b / a
// measured one right after the other, as a shared machine's speed drifts
// between repeats; the rates printed are the best of each. c shows the
// controller's share.
// log.csv is formatted on a writer thread, which has a core of its own when
// more than one is allowed: the one-CPU b / a counts that work, the other does
// not, so both are printed, after the CPUs the process may use. An unpinned
// loop is not measured: where a thread's migration is dear (some virtual
// machines) it slows a and b alike and hides the lab's cost.
#include <sched.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

#include "cli/cli_commands.h"
#include "cli/cli_cpus.h"
#include "core/core_realtime.h"
#include "lab/run/lab_runner.h"
#include "lab/scenario/lab_scenario.h"

namespace vlab::cli {

namespace {

// best of --repeat, steps per second: a (bare replay) and b (lab replay); and the median
// over the repeats of b / a measured one right after the other (a slower or faster machine
// between repeats changes both of a pair alike)
struct Rates {
  double bare = 0, replayed = 0;
  double ratio = 0;
};

// steps per second of bare mj_step replaying `controls`; sets *same when the
// final state equals `final_qpos` bit for bit
double BareReplay(const lab::Lab& lab, const std::vector<double>& controls, const std::vector<double>& final_qpos,
                  bool* same) {
  const mjModel* m = lab.model();
  vlab::DataPtr data = vlab::MakeData(m);
  mjData* d = data.get();
  lab.InitialState(d);
  const long steps = m->nu ? static_cast<long>(controls.size() / m->nu) : 0;
  const auto t0 = std::chrono::steady_clock::now();
  for (long i = 0; i < steps; ++i) {
    std::memcpy(d->ctrl, controls.data() + i * m->nu, sizeof(double) * m->nu);
    mj_step(m, d);
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  *same = std::memcmp(d->qpos, final_qpos.data(), sizeof(double) * m->nq) == 0;
  return steps / wall;
}

}  // namespace

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

int BenchCommand(const BenchArgs& args) {
  return WithErrorReport([&args] {
    lab::Scenario scenario = lab::LoadScenario(
        lab::ResolveScenarioPath(args.scenario.empty() ? "scenes/pa10_reach" : args.scenario), args.sets);
    if (args.duration_s > 0) scenario.duration_s = args.duration_s;
    std::unique_ptr<lab::Lab> lab = lab::Lab::Create(scenario);
    const mjModel* m = lab->model();
    const std::string out_dir =
        (std::filesystem::temp_directory_path() / ("vlab-bench-" + std::to_string(::getpid()))).string();

    std::printf("vlab bench physics: scenario %s, scene %s\n", scenario.name.c_str(), scenario.scene.c_str());
    for (const std::string& set : args.sets) std::printf("  --set %s\n", set.c_str());
    std::printf("  %.2f s simulated per measurement, timestep %g s, control period %g s, best of %d\n",
                scenario.duration_s, m->opt.timestep, scenario.control_period_s, args.repeat);

    lab::RunOptions record;
    record.record = true;
    const lab::RunResult recorded = lab->Run(record);
    const std::vector<double> final_qpos = lab->FinalQpos();

    const std::vector<int> allowed = ThreadCpus();
    std::printf("  CPUs: %zu allowed (%s) of %ld online; log.csv is formatted on a writer thread\n", allowed.size(),
                CpuListText(allowed).c_str(), sysconf(_SC_NPROCESSORS_ONLN));

    // a and b, best of --repeat, the loop on `loop_cpu` (the rest of the process where it is);
    // c too when `live` is given
    const int loop_cpu = allowed.empty() ? 0 : allowed.front();
    const std::vector<int> one = {loop_cpu};
    bool same_all = true;
    const auto measure = [&](double* live) {
      const std::vector<int> before = ThreadCpus();
      Rates best;
      std::vector<double> ratios;
      for (int i = 0; i < args.repeat; ++i) {
        bool same = false;
        BindThread(0, one);
        const double bare = BareReplay(*lab, recorded.recording.controls, final_qpos, &same);
        best.bare = std::max(best.bare, bare);
        BindThread(0, before);
        same_all = same_all && same;

        lab::RunOptions replay;
        replay.out_dir = out_dir;
        replay.replay = &recorded.recording;
        replay.loop_cpu = loop_cpu;
        const lab::RunResult r = lab->Run(replay);
        best.replayed = std::max(best.replayed, r.steps / r.loop_wall_s);
        ratios.push_back(r.steps / r.loop_wall_s / bare);
        same_all = same_all && lab->FinalQpos() == final_qpos;

        if (!live) continue;
        lab::RunOptions full;
        full.out_dir = out_dir;
        full.loop_cpu = loop_cpu;
        const lab::RunResult f = lab->Run(full);
        *live = std::max(*live, f.steps / f.loop_wall_s);
      }
      best.ratio = Median(ratios);
      return best;
    };
    double live = 0;
    const Rates all = measure(&live);
    BindThread(0, one);
    const Rates single = measure(nullptr);
    BindThread(0, allowed);
    std::error_code ec;
    std::filesystem::remove_all(out_dir, ec);

    const double ratio = all.ratio;
    const double ratio_one = single.ratio;
    std::printf("  the loop on CPU %d, the log writer %s:\n", loop_cpu,
                allowed.size() > 1 ? ("free on the CPUs allowed (" + CpuListText(allowed) + ")").c_str()
                                   : "sharing the one CPU with the loop");
    std::printf("    a. bare mj_step, recorded controls           %9.0f steps/s  (%.0fx real time)\n", all.bare,
                all.bare * m->opt.timestep);
    std::printf("    b. lab: servo + JR3 8 kHz + log.csv + checks %9.0f steps/s  b/a %.3f (median of pairs)\n",
                all.replayed, ratio);
    std::printf("    c. lab with the built-in controller live     %9.0f steps/s  ratio c/a %.3f\n", live,
                live / all.bare);
    std::printf("  on one CPU (%s), the log writer sharing it with the loop:\n", CpuListText(one).c_str());
    std::printf("    a. bare mj_step, recorded controls           %9.0f steps/s\n", single.bare);
    std::printf("    b. lab: servo + JR3 8 kHz + log.csv + checks %9.0f steps/s  b/a %.3f (median of pairs)\n",
                single.replayed, ratio_one);
    std::printf("  a and b reproduce the recorded trajectory bit for bit: %s\n", same_all ? "yes" : "NO");
    std::printf("  goal: b/a >= 0.90 -> %s with the log writer beside the loop, %s on one CPU\n",
                ratio >= 0.90 ? "met" : "NOT met", ratio_one >= 0.90 ? "met" : "NOT met");
    return 0;
  });
}

}  // namespace vlab::cli
