// vlab: a virtual robotics lab. See README.md and `vlab --help`.
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "cli/cli_commands.h"
#include "lab/scenario/lab_scenario.h"
#include "lab/scenario/lab_yaml.h"

#ifndef VLAB_VERSION
#define VLAB_VERSION "0.0.0"
#endif

int main(int argc, char** argv) {
  CLI::App app{"vlab " VLAB_VERSION
               ": a virtual robotics lab on MuJoCo.\n"
               "Exit codes: 0 success; 1 a check failed, the run diverged or raised a MuJoCo warning the\n"
               "scenario does not allow, or it was interrupted (SIGINT, SIGTERM: what ran is written, result\n"
               "'interrupted'); 2 bad input (file, key, option, output folder)."};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("vlab ") + VLAB_VERSION);

  // --out of vlab run and vlab serve (docs/scenarios.md, "Outputs")
  const char* kOutHelp =
      "Output folder (default: out/<scenario name>; a trailing / is dropped). An existing one is replaced only if "
      "it is empty, or vlab wrote it and it holds nothing vlab did not write (else exit 2, naming those entries). "
      "Written whole: staged in PARENT/.vlab-PID-N and renamed into place; when another run put its folder there "
      "meanwhile, this run's goes to DIR.2 (DIR.3, ...) and says so";
  vlab::cli::RunArgs run;
  CLI::App* run_cmd =
      app.add_subcommand("run",
                         "Run a scenario headless; write out/NAME/log.csv, summary.json and the scenario's outputs "
                         "(the plots' paths are printed)");
  run_cmd->add_option("scenario", run.scenario, "Scenario file (YAML); the .yaml extension may be left out")
      ->required();
  run_cmd->add_option("--out", run.out_dir, kOutHelp);
  run_cmd->add_flag("-q,--quiet", run.quiet,
                    "No progress bar, no per-check lines and no task print() lines (kept in the output folder's "
                    "task.log)");
  run_cmd->add_option("--duration", run.duration_s, "Override the scenario's duration, s (> 0, at most 1e6)");
  run_cmd->add_option("--seed", run.seed, "Override the scenario's seed: an integer from 0 to 2^53")
      ->check(CLI::Validator(vlab::lab::CheckSeedText, ""));
  run_cmd->add_flag("--list-signals", run.list_signals, "Print the log columns (usable in checks) and exit");
  const char* rt_help =
      "SCHED_FIFO priority (1-99) of the control thread in lockstep and realtime runs, with memory locked, "
      "when permitted (root, CAP_SYS_NICE or ulimit -r); on the realtime clock it then asks for "
      "SCHED_DEADLINE too (90 % of each period; root or CAP_SYS_NICE); 0: normal priority (default: the "
      "scenario's realtime.priority); what was granted is printed and recorded in summary.json";
  run_cmd->add_option("--rt-priority", run.rt_priority, rt_help)->check(CLI::Range(0, 99));
  run_cmd
      ->add_option("--set", run.sets,
                   "KEY=VALUE: override a scenario key by its dotted path, list items by name or index "
                   "(devices.jr3.filter=2, controller.gains.position=15); VALUE is YAML, typed and checked "
                   "like the file; repeatable; recorded in summary.json")
      ->allow_extra_args(false);
  run_cmd->add_option("--overrides", run.overrides_file,
                      "FILE of KEY=VALUE lines, one --set each ('#' comments), applied before the --set options "
                      "(vlab identify's overrides.txt)");

  vlab::cli::ServeArgs serve;
  CLI::App* serve_cmd =
      app.add_subcommand("serve",
                         "Run a scenario with its devices served over UDP (lockstep or realtime clock); "
                         "a lockstep run that no controller sent a command to fails");
  vlab::cli::ServeArgs devices;
  CLI::App* devices_cmd = app.add_subcommand("devices", "List a scenario's devices, UDP endpoints and layouts");
  for (auto [cmd, a] : {std::pair{serve_cmd, &serve}, std::pair{devices_cmd, &devices}}) {
    cmd->add_option("scenario", a->scenario, "Scenario file (YAML); the .yaml extension may be left out")->required();
    cmd->add_option("--bind", a->bind, "Address the device sockets bind to (default 127.0.0.1)");
    cmd->add_option("--port", a->ports, "DEVICE=PORT: serve DEVICE on PORT (0 or auto: any free port); repeatable");
    cmd->add_option("--ports", a->ports_mode,
                    "auto: every device that has a port on a free port instead (vlab serve prints the ports it "
                    "took on its first line and keeps them in summary.json), so that runs of one scenario can go "
                    "side by side")
        ->check(CLI::IsMember({"auto"}));
    cmd->add_option("--clock", a->clock, "fast | lockstep | realtime (default: the scenario's)")
        ->check(CLI::IsMember({"fast", "lockstep", "realtime"}));
  }
  serve_cmd->add_option("--out", serve.out_dir, kOutHelp);
  serve_cmd->add_flag("-q,--quiet", serve.quiet,
                      "Only the start line and the result line (no line saying whom it waits for, no counters)");
  serve_cmd->add_option("--duration", serve.duration_s, "Override the scenario's duration, s (> 0, at most 1e6)");
  serve_cmd->add_option("--rt-priority", serve.rt_priority, rt_help)->check(CLI::Range(0, 99));
  serve_cmd
      ->add_option("--subscribers", serve.max_subscribers,
                   "Subscribers each device keeps (default 16; cameras keep 16); a full table drops the one "
                   "heard from least recently, never a device's owner")
      ->check(CLI::Range(1, 4096));
  devices_cmd->add_flag("--json", devices.json, "Print each device's describe reply too");

  vlab::cli::BenchArgs bench;
  CLI::App* bench_cmd =
      app.add_subcommand("bench", "Measure performance against a baseline in the same run; prints the CPUs used first");
  bench_cmd
      ->add_option("what", bench.what,
                   "Benchmark: physics (lab loop vs bare mj_step, b/a on the CPUs allowed and on one CPU) | "
                   "bridge (echo floor and lockstep period p50: same core, cross core, unpinned; then realtime) "
                   "| render (fps per size and profile, JPEG, send) | realtime (1 kHz beside 2 and 4 served 640x480 "
                   "cameras: quiet, under 2 CPU hogs, "
                   "and under them at realtime priority when permitted; 4 cameras at priority in the draft "
                   "profile too) "
                   "| task (a task script vs the built-in task_space controller, period time) "
                   "| sweep (runs per minute of vlab sweep -j 2 vs -j 1) "
                   "| view (lab period with and without the scene stream + one viewer) "
                   "| log (a run's wall time and log bytes per log format against CSV) "
                   "| identify (vlab identify's fit of 20 PA10 parameters with 1 and 2 threads)")
      ->required()
      ->check(CLI::IsMember({"physics", "bridge", "render", "realtime", "task", "sweep", "view", "log", "identify"}));
  bench_cmd->add_option(
      "--scenario", bench.scenario,
      "Scenario to measure (default: scenes/pa10_reach for physics, scenes/pa10_serve for bridge "
      "and realtime, scenes/pa10_reach_task for task, scenes/pa10_view for view, scenes/pa10_reach for log); "
      "sweep: a sweep "
      "file (default scenes/sweeps/pa10_gains.yaml)");
  bench_cmd->add_option(
      "--duration", bench.duration_s,
      "Simulated seconds per measurement (> 0); bridge: of the lockstep run (default 5); "
      "realtime: of each run (default 10); log: of each run (default 60); identify: of the fitted log (default 20)");
  bench_cmd->add_option("--realtime", bench.realtime_s, "bridge: seconds of the 1 kHz realtime run (default 30)");
  bench_cmd->add_option("--repeat", bench.repeat, "Measurements per variant, 1 to 100 (best kept)");
  bench_cmd->add_option("--iterations", bench.iterations,
                        "identify: the fit's most iterations, 1 to 1000 (0 or absent: the spec's default, 50; "
                        "fewer for a short run whose estimates do not matter)");
  bench_cmd
      ->add_option("--set", bench.sets,
                   "physics: KEY=VALUE, a scenario override as vlab run's (devices.pa10.servo.feedforward=model); "
                   "repeatable")
      ->allow_extra_args(false);

  // subcommands that define themselves in their own files
  const std::vector<vlab::cli::Subcommand> more = {
      vlab::cli::AddRenderCommand(app),  vlab::cli::AddCameraCommand(app), vlab::cli::AddVisionCommand(app),
      vlab::cli::AddCubesCommand(app),   vlab::cli::AddTaskCommand(app),   vlab::cli::AddCompareCommand(app),
      vlab::cli::AddGoldenCommand(app),  vlab::cli::AddSweepCommand(app),  vlab::cli::AddCollectCommand(app),
      vlab::cli::AddViewCommand(app),    vlab::cli::AddExportCommand(app), vlab::cli::AddFollowCommand(app),
      vlab::cli::AddConvertCommand(app), vlab::cli::AddRecordCommand(app), vlab::cli::AddExciteCommand(app),
      vlab::cli::AddIdentifyCommand(app)};

  try {
    app.parse(argc, argv);
    // range checks here, so that each error is one short line
    auto given = [](CLI::App* cmd, const char* name) { return cmd->get_option(name)->count() > 0; };
    if (run_cmd->parsed() && given(run_cmd, "--duration") && !vlab::lab::ValidDuration(run.duration_s)) {
      throw CLI::ValidationError("--duration must be > 0 s and at most 1e6 s");
    }
    if (run_cmd->parsed() && given(run_cmd, "--seed") && run.seed < 0) {
      throw CLI::ValidationError("--seed must be >= 0");
    }
    for (auto [cmd, out] : {std::pair{run_cmd, &run.out_dir}, std::pair{serve_cmd, &serve.out_dir}}) {
      if (cmd->parsed() && given(cmd, "--out") && out->empty()) {
        throw CLI::ValidationError("--out: an empty name (give a folder, e.g. --out results)");
      }
    }
    if (serve_cmd->parsed() && given(serve_cmd, "--duration") && !vlab::lab::ValidDuration(serve.duration_s)) {
      throw CLI::ValidationError("--duration must be > 0 s and at most 1e6 s");
    }
    if (bench_cmd->parsed() && given(bench_cmd, "--duration") && !vlab::lab::ValidDuration(bench.duration_s)) {
      throw CLI::ValidationError("--duration must be > 0 s and at most 1e6 s");
    }
    if (bench_cmd->parsed() && !(bench.realtime_s > 0 && bench.realtime_s <= 3600)) {
      throw CLI::ValidationError("--realtime must be > 0 and <= 3600 s");
    }
    if (bench_cmd->parsed() && (bench.repeat < 1 || bench.repeat > 100)) {
      throw CLI::ValidationError("--repeat must be 1 to 100");
    }
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    // no subcommand, or one vlab does not have: name the ones it has
    bool any = false;
    for (const CLI::App* sub : app.get_subcommands({})) any = any || sub->parsed();
    if (!any) {
      std::string known;
      for (const CLI::App* sub : app.get_subcommands({})) known += (known.empty() ? "" : ", ") + sub->get_name();
      const bool named = argc > 1 && argv[1][0] != '-';
      const std::string what = named      ? "unknown subcommand '" + std::string(argv[1]) + "'"
                               : argc > 1 ? std::string(e.what())
                                          : std::string("a subcommand is required");
      std::fprintf(stderr, "vlab: error: %s (known: %s; see vlab --help)\n", what.c_str(), known.c_str());
      return 2;
    }
    std::fprintf(stderr, "vlab: error: %s (see vlab --help)\n", e.what());
    return 2;
  }
  if (run_cmd->parsed()) return vlab::cli::RunCommand(run);
  if (serve_cmd->parsed()) return vlab::cli::ServeCommand(serve);
  if (devices_cmd->parsed()) return vlab::cli::DevicesCommand(devices);
  if (bench_cmd->parsed()) {
    if (bench.what == "bridge") return vlab::cli::BenchBridge(bench);
    if (bench.what == "render") return vlab::cli::BenchRender(bench);
    if (bench.what == "realtime") return vlab::cli::BenchRealtime(bench);
    if (bench.what == "task") return vlab::cli::BenchTask(bench);
    if (bench.what == "sweep") return vlab::cli::BenchSweep(bench);
    if (bench.what == "view") return vlab::cli::BenchView(bench);
    if (bench.what == "log") return vlab::cli::BenchLog(bench);
    if (bench.what == "identify") return vlab::cli::BenchIdentify(bench);
    return vlab::cli::BenchCommand(bench);
  }
  for (const auto& sub : more) {
    if (sub.app->parsed()) return sub.run();
  }
  return 2;
}
