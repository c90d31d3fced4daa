// vlab task SCRIPT --arm HOST:PORT [--wrench HOST:PORT] [--device KIND=HOST:PORT]
//                  (KIND a float64 kind, or markers: a vision program)
//                  --scene MJCF --tip SITE: runs a task-language script
// (src/task/) against devices over UDP: vlab serve, vlab run's external
// controller seam, vlab-kinsim or a real driver. The same script as a scenario's
// `task` controller; only the transport differs.
//
// Each arm state (the clock of the loop) resumes the program once and answers
// with a position command carrying the state's seq, so under a lockstep clock
// the run is exact and repeatable, and in real time it follows the device's rate.
// Exit: 0 when the script ended (and, with --hold, when the devices stopped
// or SIGINT/SIGTERM came), 1 on a script error (file:line and traceback on
// stderr) or a device that went silent, 2 on bad options or a syntax error.
#include <cstdio>
#include <memory>

#include "bridge/bridge_signals.h"
#include "cli/cli_commands.h"
#include "core/core_errors.h"
#include "core/core_mujoco.h"
#include "lab/scenario/lab_yaml.h"
#include "task/task_runtime.h"
#include "task/task_udp.h"

namespace vlab::cli {

namespace {

struct TaskArgs {
  std::string script;
  std::string arm;
  std::vector<std::string> wrenches;
  std::vector<std::string> devices;  // KIND=HOST:PORT
  std::vector<std::string> params;   // NAME=VALUE
  std::string scene;
  std::string tip_site;
  std::string base_body = "world";
  double period_s = 0;  // 0: from the arm's describe reply
  long long seed = 1;
  double timeout_s = 5.0;
  bool hold = false;
  bool quiet = false;
  std::string log;  // task.log: every print() line and the error, with the simulated time
};

// where the script's output goes: stdout unless --quiet, and the --log file
class TaskOutput {
 public:
  TaskOutput(const std::string& path, bool quiet) : quiet_(quiet) {
    if (path.empty()) return;
    file_ = std::fopen(path.c_str(), "w");
    if (!file_) throw InputError("task: --log: cannot write '" + path + "'");
  }
  ~TaskOutput() {
    if (file_) std::fclose(file_);
  }
  TaskOutput(const TaskOutput&) = delete;
  TaskOutput& operator=(const TaskOutput&) = delete;
  // one print() line of the script at simulated time t
  void Print(const std::string& who, double t, const std::string& text) {
    char head[160];
    std::snprintf(head, sizeof head, "[%s t=%.3f] ", who.c_str(), t);
    if (file_) {
      std::fprintf(file_, "%s%s\n", head, text.c_str());
      std::fflush(file_);
    }
    if (quiet_) return;
    std::printf("%s%s\n", head, text.c_str());
    std::fflush(stdout);
  }
  // the script's error (its first line) in the log; the whole message goes to stderr
  void Error(double t, const std::string& error) {
    if (!file_) return;
    std::fprintf(file_, "[error t=%.3f] %s\n", t, error.substr(0, error.find('\n')).c_str());
    std::fflush(file_);
  }

 private:
  bool quiet_;
  std::FILE* file_ = nullptr;
};

int Task(const TaskArgs& a) {
  InstallStopSignals();
  if (a.scene.empty()) throw InputError("task: --scene MJCF is required (the robot's kinematics)");
  if (a.tip_site.empty()) throw InputError("task: --tip SITE is required (the site at the tool flange)");
  if (!(a.timeout_s > 0)) throw InputError("task: --timeout must be > 0 s");
  if (a.seed < 0) throw InputError("task: --seed must be >= 0");
  task::CheckSyntax(a.script);  // before any device is contacted: exit 2, nothing has run
  std::map<std::string, std::string> params;
  for (const std::string& text : a.params) {
    const auto [name, value] = task::ParseParam(text);
    if (!params.emplace(name, value).second) throw InputError("task: --param '" + name + "' given twice");
  }
  ModelPtr model = LoadModel(a.scene);
  task::UdpDevices devices;
  devices.AddArm(a.arm, a.timeout_s);
  for (const std::string& w : a.wrenches) devices.Add("wrench", w, a.timeout_s);
  for (const std::string& d : a.devices) {
    const auto eq = d.find('=');
    if (eq == std::string::npos) throw InputError("task: --device '" + d + "' is not KIND=HOST:PORT");
    devices.Add(d.substr(0, eq), d.substr(eq + 1), a.timeout_s);
  }
  task::RuntimeConfig rc;
  rc.period_s = a.period_s > 0 ? a.period_s : (devices.control_hz() > 0 ? 1.0 / devices.control_hz() : 0.002);
  rc.seed = static_cast<std::uint64_t>(a.seed);
  rc.markers_hold = !devices.realtime();  // lockstep: markers:next() holds the period for its frame
  auto output = std::make_shared<TaskOutput>(a.log, a.quiet);
  rc.print = [output](const std::string& who, double t, const std::string& text) { output->Print(who, t, text); };
  task::ProgramConfig p;
  p.script = a.script;
  p.robot = devices.arm_name();
  p.tip_site = a.tip_site;
  p.base_body = a.base_body;
  p.params = params;
  rc.programs.push_back(p);
  std::unique_ptr<task::Runtime> runtime = task::Runtime::Create(rc, model.get(), &devices);

  // the loop: one resume per arm state
  double t0 = -1;
  long periods = 0;
  while (g_stop_requested == 0) {
    double t;
    try {
      t = devices.Receive(runtime->finished() ? 1.0 : a.timeout_s);
    } catch (const bridge::TimeoutError& e) {
      if (runtime->finished()) break;  // --hold: the devices stopped after the script ended
      if (g_stop_requested != 0) break;
      std::fprintf(stderr, "vlab task: %s (the script had not ended)\n", e.what());
      return 1;
    }
    if (t0 < 0) {
      t0 = t;
      devices.set_time_origin(t0);
    }
    if (!runtime->Step(t - t0, nullptr)) {  // a script error ends the program at once, --hold or not
      output->Error(t - t0, runtime->error());
      std::fprintf(stderr, "vlab task: %s\n", runtime->error().c_str());
      return 1;
    }
    ++periods;
    if (runtime->finished() && !a.hold) break;
  }
  if (!runtime->finished()) {
    std::fprintf(stderr, "vlab task: stopped by %s before the script ended\n",
                 StopSignalName(g_stop_requested).c_str());
    return 1;
  }
  if (!a.quiet) std::printf("vlab task: %s ended after %ld periods\n", a.script.c_str(), periods);
  return 0;
}

}  // namespace

Subcommand AddTaskCommand(CLI::App& app) {
  auto a = std::make_shared<TaskArgs>();
  CLI::App* cmd = app.add_subcommand(
      "task", "Run a task-language script (Lua) against an arm and other devices over UDP (docs/tasks.md)");
  cmd->add_option("script", a->script, "The .lua script")->required();
  cmd->add_option("--arm", a->arm, "The arm the script moves: HOST:PORT")->required();
  cmd->add_option("--wrench", a->wrenches, "A wrench (force/torque) device: HOST:PORT (repeatable)");
  cmd->add_option("--device", a->devices,
                  "Any float64 device, or a markers device (vlab vision): KIND=HOST:PORT, e.g. "
                  "gripper=127.0.0.1:50020, markers=127.0.0.1:50014 (repeatable)");
  cmd->add_option("--param", a->params,
                  "NAME=VALUE: the script's PARAMS.NAME (a number, true/false, or else a string; repeatable)");
  cmd->add_option("--scene", a->scene, "MJCF with the arm's kinematic chain (e.g. scenes/pa10.xml)")->required();
  cmd->add_option("--tip", a->tip_site, "Site at the tool flange (e.g. tool)")->required();
  cmd->add_option("--base", a->base_body, "Body the chain starts from")->capture_default_str();
  cmd->add_option("--period", a->period_s, "Control period, s (default: from the arm's describe reply)");
  cmd->add_option("--seed", a->seed, "Seed of math.random, an integer from 0 to 2^53")
      ->capture_default_str()
      ->check(CLI::Validator(lab::CheckSeedText, ""));
  cmd->add_option("--timeout", a->timeout_s, "Seconds to wait for a device's state")->capture_default_str();
  cmd->add_flag("--hold", a->hold,
                "After the script ends, keep holding the arm until its states stop or SIGINT/SIGTERM (for vlab run's "
                "external controllers, unless the scenario's controller.ends_run lets the script's end end the run)");
  cmd->add_flag("-q,--quiet", a->quiet, "No print() output or end line on stdout (--log still gets it)");
  cmd->add_option("--log", a->log,
                  "Write every print() line and a script error, with the simulated time, to FILE (e.g. "
                  "{out_dir}/task.log as an external controller of vlab run)");
  return {cmd, [a]() { return WithErrorReport([a]() { return Task(*a); }); }};
}

}  // namespace vlab::cli
