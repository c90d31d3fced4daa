#include "lab/lab_runner.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "core/core_errors.h"
#include "lab/devices/device_kinds.h"
#include "lab/lab_external.h"
#include "lab/lab_images.h"
#include "lab/lab_log.h"
#include "lab/lab_output.h"
#include "lab/lab_plot.h"
#include "lab/lab_run_watch.h"
#include "lab/lab_runner_impl.h"

namespace vlab::lab {

namespace {

using WallClock = std::chrono::steady_clock;

double Seconds(WallClock::time_point a, WallClock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// 64-bit mix of the scenario seed and a device name: each device gets its own stream
std::uint64_t DeviceSeed(std::uint64_t seed, const std::string& name) {
  std::uint64_t h = 1469598103934665603ULL;  // FNV-1a
  for (unsigned char c : name) h = (h ^ c) * 1099511628211ULL;
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ULL * (h | 1);  // splitmix64 finaliser
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

}  // namespace

Lab::Lab(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Lab::~Lab() = default;
const mjModel* Lab::model() const { return impl_->model.get(); }
const Scenario& Lab::scenario() const { return impl_->scenario; }
std::vector<std::string> Lab::Columns() const { return impl_->columns; }
std::vector<double> Lab::FinalQpos() const {
  return std::vector<double>(impl_->data->qpos, impl_->data->qpos + impl_->model->nq);
}

std::unique_ptr<Lab> Lab::Create(const Scenario& scenario) {
  auto impl = std::make_unique<Impl>();
  impl->scenario = scenario;
  impl->model = LoadModel(scenario.scene);
  const mjModel* m = impl->model.get();
  impl->data = MakeData(m);
  if (!scenario.keyframe.empty()) {
    impl->keyframe = mj_name2id(m, mjOBJ_KEY, scenario.keyframe.c_str());
    if (impl->keyframe < 0) {
      throw InputError(scenario.keyframe_where + ": keyframe: the scene '" + scenario.scene + "' has no keyframe '" +
                       scenario.keyframe + "'");
    }
  }

  // the control period must be a whole number of physics steps
  const double ts = m->opt.timestep;
  const double ratio = scenario.control_period_s / ts;
  impl->steps_per_period = static_cast<int>(std::lround(ratio));
  if (impl->steps_per_period < 1 || std::abs(ratio - impl->steps_per_period) > 1e-9 * ratio) {
    throw InputError(scenario.file + ": control_period " + FormatDouble(scenario.control_period_s) +
                     " s is not a whole multiple of the scene timestep " + FormatDouble(ts) + " s");
  }

  // every device by its kind's factory, then bound to the others (a point device to its arm)
  for (const DeviceConfig& device : scenario.devices) {
    const DeviceContext context{m, scenario.control_period_s, DeviceSeed(scenario.seed, device.name), scenario.scene};
    impl->devices.push_back(MakeDevice(context, device));
    impl->device_ptrs.push_back(impl->devices.back().get());
    if (auto* sim = dynamic_cast<SimControl*>(impl->devices.back().get())) impl->sim = sim;
  }
  for (Device* device : impl->device_ptrs) device->Bind(impl->device_ptrs);
  impl->log_order = impl->device_ptrs;
  std::stable_sort(impl->log_order.begin(), impl->log_order.end(),
                   [](const Device* a, const Device* b) { return a->log_rank() < b->log_rank(); });

  impl->columns.push_back("time");
  for (const Device* device : impl->log_order) {
    for (auto& c : device->Columns()) impl->columns.push_back(c);
  }

  impl->ResetState();
  const ControllerConfig& cc = scenario.controller;
  if (cc.type == ControllerType::kExternal) {
    ExpandCommand(cc.command, CommandValues(scenario, {}), cc.where);  // placeholders checked now
  } else if (cc.type != ControllerType::kNone) {
    for (Device* device : impl->device_ptrs) {
      if (device->name() == cc.arm) impl->controller_arm = dynamic_cast<SimArm*>(device);
    }
    if (!impl->controller_arm) {
      throw InputError(cc.where + ": controller.arm: no arm device named '" + cc.arm + "'");
    }
    SimArm& arm = *impl->controller_arm;
    if (!arm.driver().empty()) {
      const Device& driver = **std::find_if(impl->device_ptrs.begin(), impl->device_ptrs.end(),
                                           [&arm](const Device* d) { return d->name() == arm.driver(); });
      throw InputError(driver.where() + ": device '" + driver.name() + "': arm: arm '" + arm.name() +
                       "' is commanded by the built-in controller: one owner at a time");
    }
    impl->controller = MakeController(m, cc, arm.joint_names(), arm.state());
    impl->controller_columns = impl->controller->Columns().size();
    for (auto& c : impl->controller->Columns()) impl->columns.push_back(c);
  }
  return std::unique_ptr<Lab>(new Lab(std::move(impl)));
}

void Lab::InitialState(mjData* d) const {
  impl_->ResetData(d);
  for (const auto& device : impl_->devices) device->SetInitialState(*d);
  mj_forward(impl_->model.get(), d);
}

namespace {

// Clears the MuJoCo error cleanup when a run ends, however it ends.
struct ErrorCleanupGuard {
  ~ErrorCleanupGuard() { SetMujocoErrorCleanup(nullptr); }
};

// how long an external controller gets to exit after SIGTERM at the end of a run
constexpr double kControllerGrace_s = 2.0;

std::string ControllerFailure(ExternalController& c, double t) {
  const std::string last = c.LastLogLine();
  return "controller '" + c.program() + "' ended with " + c.Outcome() + " (t = " + FormatDouble(t) + " s)" +
         (last.empty() ? "" : ": " + last);
}

// The sim device's state at period k.
bridge::SimStateMsg SimState(double t, bool paused, const Clock& clock, long k, const LabBridge* bridge) {
  bridge::SimStateMsg m;
  m.sim_time = t;
  m.mode = paused ? 1 : 0;
  m.clock = static_cast<int>(clock.mode() == ClockMode::kLockstep   ? bridge::ClockCode::kLockstep
                             : clock.mode() == ClockMode::kRealtime ? bridge::ClockCode::kRealtime
                                                                    : bridge::ClockCode::kFast);
  m.periods = static_cast<double>(k);
  m.refused_packets = bridge ? static_cast<double>(bridge->refused_total()) : 0.0;
  m.missed_deadlines = static_cast<double>(clock.stats().missed_deadlines);
  m.realtime_factor = clock.factor();
  m.max_lateness = clock.stats().max_lateness_s;
  return m;
}

}  // namespace

RunResult Lab::Run(const RunOptions& options) {
  Impl& s = *impl_;
  const auto t_start = WallClock::now();
  const mjModel* m = s.model.get();
  mjData* d = s.data.get();
  const double period = s.scenario.control_period_s;
  const long periods = std::lround(s.scenario.duration_s / period);
  RunResult result;

  InstallMujocoHandlers();
  TakeMujocoWarningTexts();
  s.ResetState();
  for (auto& device : s.devices) {
    if (OwnTransport* t = device->own_transport()) t->Unserve();  // MakeBridge serves them again when serving
  }
  // a scenario's external controller: vlab run serves on loopback and starts it
  const bool external = StartsExternalController(s.scenario, options.serve != nullptr);
  const BridgeOptions external_serve = external ? ExternalBridgeOptions(s.scenario) : BridgeOptions{};
  const BridgeOptions* serve = external ? &external_serve : options.serve;
  const ClockMode mode = external ? ExternalClock(s.scenario, options.clock) : options.clock.value_or(s.scenario.clock);
  std::unique_ptr<Clock> clock = MakeClock(ScenarioClock(s.scenario, mode), periods);
  result.clock = clock->mode();

  // checks first: a bad signal name is bad input, and must leave nothing behind
  CheckSet checks(s.scenario.checks, s.columns);
  for (const PlotConfig& plot : s.scenario.outputs.plots) CheckPlotColumns(plot, s.columns);
  // image outputs: cameras and sizes checked against the scene before anything is written
  std::unique_ptr<ImageOutputs> images;
  if (!options.out_dir.empty() && !s.scenario.outputs.images.empty()) {
    images = ImageOutputs::Create(m, s.scenario.outputs.images, s.scenario.scene, period);
  }
  // the wire: bind every served device before anything is written
  std::unique_ptr<LabBridge> bridge;
  if (serve) {
    bridge = s.MakeBridge(*serve, clock->name());
    if (options.on_serving && !external) options.on_serving(bridge->Devices());
  }
  // outputs: staging folder (removed on a MuJoCo error too), log
  std::unique_ptr<OutputDir> out;
  std::unique_ptr<CsvLog> log;
  ErrorCleanupGuard cleanup_guard;
  if (!options.out_dir.empty()) {
    out = OutputDir::Create(options.out_dir);
    SetMujocoErrorCleanup([staging = out->File("")] {
      std::error_code ec;
      std::filesystem::remove_all(staging, ec);
    });
    if (s.scenario.outputs.log) log = CsvLog::Open(out->File("log.csv"), s.columns);
    if (images) images->Open(*out);
  }
  std::unique_ptr<ExternalController> controller;
  if (external) {
    const std::string log_path = out ? out->File("controller.log") : "";
    controller = ExternalController::Start(
        ExpandCommand(s.scenario.controller.command,
                      CommandValues(s.scenario, bridge->Devices(), out ? out->File("") : ""),
                      s.scenario.controller.where),
        log_path);
    bridge->WatchPeerExit(controller->exit_fd());
  }

  if (options.record) result.recording.controls.reserve(static_cast<std::size_t>(periods) * s.steps_per_period * m->nu);
  std::vector<double> row(s.columns.size(), 0.0);
  double* controller_columns = row.data() + s.columns.size() - s.controller_columns;
  std::size_t replay_at = 0;
  auto emit_row = [&](double t) {
    s.WriteRow(t, row);
    if (log) log->Append(row.data());
    checks.Add(t, row.data());
  };
  bool paused = false;
  long steps_left = -1;  // periods to run before pausing again (sim "step N"); -1: not stepping
  auto publish = [&](long k) {
    if (!bridge) return;
    if (s.sim) s.sim->set_state(SimState(k * period, paused, *clock, k, bridge.get()));
    bridge->Publish(k, k * period);
  };
  // what renders from the state at period end t without being part of the period's states:
  // the camera frames delivered later, the image outputs; after the states went out, so that
  // rendering does not delay them (the state is still that of t: the next period has not begun)
  auto render_after_publish = [&](double t) {
    for (auto& device : s.devices) device->AfterPublish(d);
    if (images) images->Observe(t, d);
  };
  // row 0: the initial state, with the controller's view of it
  if (s.controller) s.RunController(0.0, options, &replay_at, &result, controller_columns);
  emit_row(0.0);
  if (options.observe) options.observe(0.0, m, d);
  for (auto& device : s.devices) device->BeforeRun(d);
  for (auto& device : s.devices) device->Deliver(0.0, d);
  publish(0);
  render_after_publish(0.0);

  WarningWatch warnings;
  const auto t_loop = WallClock::now();
  auto t_progress = t_loop;
  bool diverged = false;
  long k = 0;
  while (k < periods && !diverged) {
    // period k runs from t_k = k T to t_k+1; times are exact multiples of T
    const double t_k = k * period;
    const double t_next = (k + 1) * period;
    if (options.interrupt && *options.interrupt) {
      throw std::runtime_error("interrupted at t = " + FormatDouble(t_k) + " s; nothing written");
    }
    // 0. the sim device: pause, resume, step, reset, pace
    if (bridge && s.HandleSimCommands(*bridge, *clock, &paused, &steps_left)) publish(k);
    if (paused) {
      bridge->Poll(0.02);
      continue;
    }
    // 1. the clock lets the period begin; commands: the newest of each device
    const PeriodStart start = clock->BeginPeriod(k, bridge.get());
    if (controller && bridge->peer_gone() && controller->Exited() && !controller->Succeeded()) {
      result.failure = ControllerFailure(*controller, t_k);
      break;
    }
    if (start == PeriodStart::kFail) {
      result.failure = "lockstep: no command answering period " + std::to_string(k) + " (t = " +
                       FormatDouble(t_k) + " s) within " + FormatDouble(s.scenario.lockstep.timeout_s) + " s";
      break;
    }
    if (bridge) {
      if (start == PeriodStart::kTimedOut) {
        bridge->NoteTimeout(s.scenario.lockstep.release_after);
      } else {
        bridge->NoteAnswered();
      }
      bridge->ApplyCommands(k);
    }
    if (s.controller) {
      if (k > 0) s.RunController(t_k, options, &replay_at, &result, controller_columns);
      s.controller_arm->Command(s.controller_command);
    }
    for (auto& dev : s.devices) dev->BeginPeriod(*d, t_k);  // point devices command their arms
    // 2. physics: the servo acts between the two halves of every step
    for (int i = 0; i < s.steps_per_period && !diverged; ++i) {
      const double t_step = d->time;
      mj_step1(m, d);
      for (auto& dev : s.devices) dev->Actuate(*d, m->opt.timestep);
      if (options.record) result.recording.controls.insert(result.recording.controls.end(), d->ctrl, d->ctrl + m->nu);
      mj_step2(m, d);
      for (auto& dev : s.devices) dev->AfterStep(*d, m->opt.timestep);
      ++result.steps;
      diverged = warnings.Update(*d, t_step);
    }
    if (diverged) break;
    // 3. sample devices, log, publish the state that closes the period
    for (auto& dev : s.devices) dev->Sample(*d, t_next);
    emit_row(t_next);
    if (options.observe) options.observe(t_next, m, d);
    for (auto& dev : s.devices) dev->Deliver(t_next, d);
    ++k;
    if (steps_left > 0 && --steps_left == 0) paused = true;
    publish(k);
    render_after_publish(t_next);
    if (options.progress && (k & 63) == 0 && Seconds(t_progress, WallClock::now()) > 0.1) {
      options.progress(static_cast<double>(k) / periods);
      t_progress = WallClock::now();
    }
  }
  result.loop_wall_s = Seconds(t_loop, WallClock::now());
  if (controller) {
    controller->Stop(kControllerGrace_s);
    if (!controller->Succeeded() && result.failure.empty()) result.failure = ControllerFailure(*controller, k * period);
    result.controller = {controller->program(), controller->Outcome()};
  }
  result.periods = k;
  result.sim_time_s = k * period;
  TakeMujocoWarningTexts();  // their content is in the reports: mju_warningText
  result.warnings = warnings.Reports(s.scenario.allow_warnings);
  result.checks = checks.Results();
  if (result.failure.empty()) result.failure = Verdict(result, diverged);
  result.exit_code = result.failure.empty() ? 0 : 1;
  result.clock_stats = clock->stats();
  if (bridge) {
    result.served = bridge->Devices();
    result.latencies_s = bridge->latencies();
  }

  if (out) {
    if (log) log->Close();
    if (images) images->Finish();
    // a plot that cannot be drawn fails the run, and the rest is written; a plot of a CSV
    // that an external controller writes into {out} is skipped where the lab did not start
    // the controller (vlab serve: one started by hand has no {out}) and the file is not there
    for (const PlotConfig& plot : s.scenario.outputs.plots) {
      if (!controller && plot.csv != "log.csv" && !std::filesystem::exists(out->File(plot.csv))) {
        result.plots_skipped.push_back(plot.file + ": no " + plot.csv +
                                       " (written by an external controller that vlab run starts)");
        continue;
      }
      try {
        WritePlot(out->File(""), plot);
      } catch (const std::runtime_error& e) {
        if (result.failure.empty()) result.failure = e.what();
        result.exit_code = 1;
      }
    }
    result.total_wall_s = Seconds(t_start, WallClock::now());
    nlohmann::json summary_json = SummaryJson(s.scenario, m, result);
    if (images) summary_json["images"] = images->Summary();
    std::ofstream summary(out->File("summary.json"));
    summary << summary_json.dump(2) << "\n";
    summary.close();
    if (!summary) throw std::runtime_error("summary '" + out->File("summary.json") + "': write failed");
    out->Commit();
  }
  result.total_wall_s = Seconds(t_start, WallClock::now());
  return result;
}

std::vector<ServedDevice> Lab::Describe(const BridgeOptions& options, std::optional<ClockMode> clock) const {
  const std::string name = ClockModeName(clock.value_or(impl_->scenario.clock));
  std::unique_ptr<LabBridge> bridge = impl_->MakeBridge(options, name);
  return bridge->Devices();  // the bridge's end frees the ports
}

}  // namespace vlab::lab
