// vlab bench physics: the lab's step loop against bare mj_step, same run.
//
// 1. One untimed lab run records the motor controls of every physics step.
// 2. Timed: the full lab loop (servo, JR3 model, controller, log.csv and
//    checks) and the same loop without outputs.
// 3. Timed: bare mj_step on a fresh mjData of the same model replaying the
//    recorded controls, i.e. exactly the physics the lab computed.
// The best of --repeat measurements of each is kept; the ratio lab / bare is
// the fraction of raw engine speed the lab keeps (goal >= 0.90).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include <unistd.h>

#include "cli/cli_commands.h"
#include "lab/lab_errors.h"
#include "lab/lab_runner.h"
#include "lab/lab_scenario.h"

namespace vlab::cli {

namespace {

struct BareResult {
  double steps_per_s = 0.0;
  bool same_trajectory = false;
};

BareResult BareReplay(const lab::Lab& lab, const std::vector<double>& controls, const std::vector<double>& final_qpos) {
  const mjModel* m = lab.model();
  lab::DataPtr data = lab::MakeData(m);
  mjData* d = data.get();
  lab.InitialState(d);
  const long steps = m->nu ? static_cast<long>(controls.size() / m->nu) : 0;
  const auto t0 = std::chrono::steady_clock::now();
  for (long i = 0; i < steps; ++i) {
    std::memcpy(d->ctrl, controls.data() + i * m->nu, sizeof(double) * m->nu);
    mj_step(m, d);
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  BareResult r;
  r.steps_per_s = steps / wall;
  r.same_trajectory = std::memcmp(d->qpos, final_qpos.data(), sizeof(double) * m->nq) == 0;
  return r;
}

}  // namespace

int BenchCommand(const BenchArgs& args) {
  try {
    lab::Scenario scenario =
        lab::LoadScenario(lab::ResolveScenarioPath(args.scenario.empty() ? "scenes/pa10_reach" : args.scenario));
    if (args.duration_s > 0) scenario.duration_s = args.duration_s;
    std::unique_ptr<lab::Lab> lab = lab::Lab::Create(scenario);
    const mjModel* m = lab->model();
    const std::string out_dir =
        (std::filesystem::temp_directory_path() / ("vlab-bench-" + std::to_string(::getpid()))).string();

    std::printf("vlab bench physics: scenario %s, scene %s\n", scenario.name.c_str(), scenario.scene.c_str());
    std::printf("  %.2f s simulated per measurement, timestep %g s, control period %g s, best of %d\n",
                scenario.duration_s, m->opt.timestep, scenario.control_period_s, args.repeat);

    // recording run (untimed): controls of every step and the final state
    lab::RunOptions record;
    record.record_controls = true;
    const lab::RunResult recorded = lab->Run(record);
    const std::vector<double> final_qpos = lab->FinalQpos();

    double best_lab = 0, best_nolog = 0, best_bare = 0;
    bool same = true;
    for (int i = 0; i < args.repeat; ++i) {
      lab::RunOptions full;
      full.out_dir = out_dir;
      const lab::RunResult r = lab->Run(full);
      best_lab = std::max(best_lab, r.steps / r.loop_wall_s);
      const lab::RunResult r2 = lab->Run(lab::RunOptions{});
      best_nolog = std::max(best_nolog, r2.steps / r2.loop_wall_s);
    }
    for (int i = 0; i < args.repeat; ++i) {
      const BareResult b = BareReplay(*lab, recorded.controls, final_qpos);
      best_bare = std::max(best_bare, b.steps_per_s);
      same = same && b.same_trajectory;
    }
    std::error_code ec;
    std::filesystem::remove_all(out_dir, ec);

    const double ratio = best_lab / best_bare;
    std::printf("  bare mj_step (recorded controls)      %10.0f steps/s  %6.0fx real time\n", best_bare,
                best_bare * m->opt.timestep);
    std::printf("  lab loop, no outputs                  %10.0f steps/s  ratio %.3f\n", best_nolog,
                best_nolog / best_bare);
    std::printf("  lab loop, JR3 + log.csv + checks      %10.0f steps/s  ratio %.3f\n", best_lab, ratio);
    std::printf("  replay reproduces the lab trajectory bit for bit: %s\n", same ? "yes" : "NO");
    std::printf("  goal: ratio >= 0.90 -> %s\n", ratio >= 0.90 ? "met" : "NOT met");
    return 0;
  } catch (const lab::InputError& e) {
    std::fprintf(stderr, "vlab: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vlab: error: %s\n", e.what());
    return 1;
  }
}

}  // namespace vlab::cli
