#include "lab/lab_runner.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "lab/lab_arm_device.h"
#include "lab/lab_bridge.h"
#include "lab/lab_clock.h"
#include "lab/lab_controller.h"
#include "lab/lab_errors.h"
#include "lab/lab_log.h"
#include "lab/lab_output.h"
#include "lab/lab_wrench_device.h"

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

struct Lab::Impl {
  Scenario scenario;
  ModelPtr model;
  DataPtr data;
  int steps_per_period = 1;
  std::vector<std::unique_ptr<SimArm>> arms;
  std::vector<std::unique_ptr<SimWrench>> wrenches;
  std::unique_ptr<Controller> controller;
  int controller_arm = -1;
  std::size_t controller_columns = 0;  // log columns the controller writes
  std::vector<std::string> columns;
  std::vector<bridge::ArmState> arm_states;
  std::vector<bridge::ArmCommand> arm_commands;

  void ResetState();
  void WriteRow(double time_s, std::vector<double>& row) const;
  std::unique_ptr<LabBridge> MakeBridge(const BridgeOptions& options, const std::string& clock_name);
  // applies the sim device's commands; true when something changed
  bool HandleSimCommands(LabBridge& bridge, Clock& clock, bool* paused, long* steps_left);
  // one controller period: computed (and recorded), or replayed from a recording
  void RunController(double t, const RunOptions& options, std::size_t* replay_at, RunResult* result,
                     double* columns);
};

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

  // the control period must be a whole number of physics steps
  const double ts = m->opt.timestep;
  const double ratio = scenario.control_period_s / ts;
  impl->steps_per_period = static_cast<int>(std::lround(ratio));
  if (impl->steps_per_period < 1 || std::abs(ratio - impl->steps_per_period) > 1e-9 * ratio) {
    throw InputError(scenario.file + ": control_period " + FormatDouble(scenario.control_period_s) +
                     " s is not a whole multiple of the scene timestep " + FormatDouble(ts) + " s");
  }

  for (const DeviceConfig& device : scenario.devices) {
    if (device.kind == "arm") {
      impl->arms.push_back(SimArm::Create(m, device));
    } else if (device.kind == "wrench") {
      impl->wrenches.push_back(SimWrench::Create(m, device, DeviceSeed(scenario.seed, device.name)));
    }  // sim: the run's own control device, served by the bridge
  }
  if (!impl->arms.empty() && m->opt.integrator == mjINT_RK4) {
    throw InputError("scene '" + scenario.scene + "': arm devices need the Euler or implicit integrator (RK4 "
                     "cannot split the step for the servo)");
  }

  impl->columns.push_back("time");
  for (const auto& arm : impl->arms) {
    for (auto& c : arm->Columns()) impl->columns.push_back(c);
  }
  for (const auto& w : impl->wrenches) {
    for (auto& c : w->Columns()) impl->columns.push_back(c);
  }
  impl->arm_states.resize(impl->arms.size());
  impl->arm_commands.resize(impl->arms.size());

  impl->ResetState();
  const ControllerConfig& cc = scenario.controller;
  if (cc.type != "none") {
    for (std::size_t i = 0; i < impl->arms.size(); ++i) {
      if (impl->arms[i]->name() == cc.arm) impl->controller_arm = static_cast<int>(i);
    }
    if (impl->controller_arm < 0) {
      throw InputError(cc.where + ": controller.arm: no arm device named '" + cc.arm + "'");
    }
    SimArm& arm = *impl->arms[impl->controller_arm];
    impl->controller = MakeController(m, cc, arm.joint_names(), impl->arm_states[impl->controller_arm]);
    impl->controller_columns = impl->controller->Columns().size();
    for (auto& c : impl->controller->Columns()) impl->columns.push_back(c);
  }
  return std::unique_ptr<Lab>(new Lab(std::move(impl)));
}

void Lab::InitialState(mjData* d) const {
  mj_resetData(impl_->model.get(), d);
  for (const auto& arm : impl_->arms) arm->SetInitialPositions(*d);
  mj_forward(impl_->model.get(), d);
}

void Lab::Impl::ResetState() {
  mjData* d = data.get();
  mj_resetData(model.get(), d);
  for (const auto& arm : arms) arm->SetInitialPositions(*d);
  mj_forward(model.get(), d);
  for (auto& arm : arms) arm->Start(*d, scenario.control_period_s);
  // the servos hold from the first instant: recompute forces with their torques,
  // so the sensors start settled on the load of an arm at rest
  for (auto& arm : arms) arm->Actuate(*d, 0.0);
  mj_forward(model.get(), d);
  for (auto& w : wrenches) w->Reset(*d);
  for (std::size_t i = 0; i < arms.size(); ++i) arms[i]->Sample(*d, d->time, &arm_states[i]);
}

void Lab::Impl::WriteRow(double time_s, std::vector<double>& row) const {
  double* out = row.data();
  *out++ = time_s;
  for (const auto& arm : arms) {
    arm->Row(*data, out);
    out += arm->ColumnCount();
  }
  for (const auto& w : wrenches) {
    w->Row(out);
    out += w->ColumnCount();
  }
}

namespace {

// MuJoCo's warning counters, watched after every step. A divergence resets
// mjData (its counters and time included), so the watch keeps its own.
class WarningWatch {
 public:
  /// Records new warnings of the step that started at t_step; true on divergence.
  bool Update(const mjData& d, double t_step) {
    bool diverged = false;
    for (int w = 0; w < mjNWARNING; ++w) {
      if (d.warning[w].number > count_[w]) {
        if (count_[w] == 0) first_[w] = t_step;
        count_[w] = d.warning[w].number;
        last_info_[w] = d.warning[w].lastinfo;
        diverged = diverged || IsDivergenceWarning(w);
      }
    }
    return diverged;
  }

  /// One report per kind that occurred, with MuJoCo's text.
  std::vector<WarningReport> Reports(const std::vector<std::string>& allowed) const {
    std::vector<WarningReport> reports;
    for (int w = 0; w < mjNWARNING; ++w) {
      if (count_[w] == 0) continue;
      WarningReport r;
      r.name = WarningName(w);
      r.count = count_[w];
      r.first_time_s = first_[w];
      r.message = mju_warningText(w, last_info_[w]);
      r.allowed = std::find(allowed.begin(), allowed.end(), r.name) != allowed.end();
      reports.push_back(r);
    }
    return reports;
  }

 private:
  int count_[mjNWARNING] = {0};
  int last_info_[mjNWARNING] = {0};
  double first_[mjNWARNING] = {0};
};

// The first reason a run fails, in order: divergence, a warning the scenario
// does not allow, a failed check; "" when it passes.
std::string Verdict(const RunResult& r, bool diverged) {
  for (const auto& w : r.warnings) {
    if (diverged && IsDivergenceWarning(WarningIndex(w.name))) {
      return "diverged at t = " + FormatDouble(w.first_time_s) + " s: " + w.message;
    }
  }
  for (const auto& w : r.warnings) {
    if (!w.allowed) {
      return "MuJoCo warning '" + w.name + "' (" + std::to_string(w.count) + "x, first at t = " +
             FormatDouble(w.first_time_s) + " s): " + w.message;
    }
  }
  for (const auto& c : r.checks) {
    if (!c.pass) {
      return "check '" + c.config.name + "' failed: " + c.config.reduce + "(" + c.config.signal +
             ") = " + FormatDouble(c.value);
    }
  }
  return "";
}

// Clears the MuJoCo error cleanup when a run ends, however it ends.
struct ErrorCleanupGuard {
  ~ErrorCleanupGuard() { SetMujocoErrorCleanup(nullptr); }
};

}  // namespace

void Lab::Impl::RunController(double t, const RunOptions& options, std::size_t* replay_at, RunResult* result,
                              double* columns) {
  const int a = controller_arm;
  const int n = arms[a]->dof();
  const std::size_t width = 1 + n + controller_columns;
  bridge::ArmCommand& cmd = arm_commands[a];
  if (options.replay) {
    // the recorded command and columns instead of the controller's work
    if (*replay_at + width > options.replay->controller.size()) {
      throw std::runtime_error("replay: the recording is shorter than this run");
    }
    const double* r = options.replay->controller.data() + *replay_at;
    cmd.mode = static_cast<bridge::ArmMode>(static_cast<int>(r[0]));
    cmd.value = Eigen::Map<const Eigen::VectorXd>(r + 1, n);
    std::copy(r + 1 + n, r + width, columns);
    *replay_at += width;
    return;
  }
  controller->Update(t, arm_states[a], &cmd, columns);
  if (options.record) {
    std::vector<double>& rec = result->recording.controller;
    rec.push_back(static_cast<double>(static_cast<int>(cmd.mode)));
    for (int i = 0; i < n; ++i) rec.push_back(i < cmd.value.size() ? cmd.value[i] : 0.0);
    rec.insert(rec.end(), columns, columns + (width - 1 - n));
  }
}

// The sim device's state at period k.
bridge::SimStateMsg SimState(double t, bool paused, const Clock& clock, long k, const LabBridge* bridge) {
  bridge::SimStateMsg m;
  m.sim_time = t;
  m.mode = paused ? 1 : 0;
  const std::string name = clock.name();
  m.clock = name == "lockstep" ? 1 : name == "realtime" ? 2 : 0;
  m.periods = static_cast<double>(k);
  m.refused_packets = bridge ? static_cast<double>(bridge->refused_total()) : 0.0;
  m.missed_deadlines = static_cast<double>(clock.stats().missed_deadlines);
  m.realtime_factor = clock.factor();
  m.max_lateness = clock.stats().max_lateness_s;
  return m;
}

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
  std::unique_ptr<Clock> clock = MakeClock(s.scenario, options.clock, periods);
  result.clock = clock->name();

  // checks first: a bad signal name is bad input, and must leave nothing behind
  CheckSet checks(s.scenario.checks, s.columns);
  // the wire: bind every served device before anything is written
  std::unique_ptr<LabBridge> bridge;
  if (options.serve) {
    bridge = s.MakeBridge(*options.serve, clock->name());
    if (options.on_serving) options.on_serving(bridge->Devices());
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
    if (bridge) bridge->Publish(k, k * period, s.arm_states, SimState(k * period, paused, *clock, k, bridge.get()));
  };
  // row 0: the initial state, with the controller's view of it
  if (s.controller) s.RunController(0.0, options, &replay_at, &result, controller_columns);
  emit_row(0.0);
  publish(0);

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
      bridge->ApplyArmCommands(k);
    }
    if (s.controller) {
      if (k > 0) s.RunController(t_k, options, &replay_at, &result, controller_columns);
      s.arms[s.controller_arm]->Command(s.arm_commands[s.controller_arm]);
    }
    // 2. physics: the servo acts between the two halves of every step
    for (int i = 0; i < s.steps_per_period && !diverged; ++i) {
      const double t_step = d->time;
      mj_step1(m, d);
      for (auto& arm : s.arms) arm->Actuate(*d, m->opt.timestep);
      if (options.record) result.recording.controls.insert(result.recording.controls.end(), d->ctrl, d->ctrl + m->nu);
      mj_step2(m, d);
      for (auto& w : s.wrenches) w->Step(*d, m->opt.timestep);
      ++result.steps;
      diverged = warnings.Update(*d, t_step);
    }
    if (diverged) break;
    // 3. sample devices, log, publish the state that closes the period
    for (auto& w : s.wrenches) w->EndPeriod();
    for (std::size_t i = 0; i < s.arms.size(); ++i) s.arms[i]->Sample(*d, t_next, &s.arm_states[i]);
    emit_row(t_next);
    ++k;
    if (steps_left > 0 && --steps_left == 0) paused = true;
    publish(k);
    if (options.progress && (k & 63) == 0 && Seconds(t_progress, WallClock::now()) > 0.1) {
      options.progress(static_cast<double>(k) / periods);
      t_progress = WallClock::now();
    }
  }
  result.loop_wall_s = Seconds(t_loop, WallClock::now());
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
    result.total_wall_s = Seconds(t_start, WallClock::now());
    std::ofstream summary(out->File("summary.json"));
    summary << SummaryJson(s.scenario, m, result).dump(2) << "\n";
    summary.close();
    if (!summary) throw std::runtime_error("summary '" + out->File("summary.json") + "': write failed");
    out->Commit();
  }
  result.total_wall_s = Seconds(t_start, WallClock::now());
  return result;
}

std::vector<ServedDevice> Lab::Describe(const BridgeOptions& options, const std::string& clock) const {
  const std::string name = clock.empty() ? impl_->scenario.clock : clock;
  return impl_->MakeBridge(options, name)->Devices();
}

std::unique_ptr<LabBridge> Lab::Impl::MakeBridge(const BridgeOptions& options, const std::string& clock_name) {
  std::vector<SimArm*> arm_ptrs;
  for (auto& a : arms) arm_ptrs.push_back(a.get());
  std::vector<SimWrench*> wrench_ptrs;
  for (auto& w : wrenches) wrench_ptrs.push_back(w.get());
  std::unique_ptr<LabBridge> bridge = LabBridge::Create(scenario, options, arm_ptrs, wrench_ptrs, clock_name);
  if (controller) {
    for (const ServedDevice& sd : bridge->Devices()) {
      if (sd.name == scenario.controller.arm) {
        throw InputError(scenario.controller.where + ": controller: arm '" + sd.name +
                         "' is served over UDP and commanded by the built-in controller: one owner at a time "
                         "(remove the controller, or the device's port)");
      }
    }
  }
  return bridge;
}

bool Lab::Impl::HandleSimCommands(LabBridge& bridge, Clock& clock, bool* paused, long* steps_left) {
  bool changed = false;
  bridge::SimCommandMsg c;
  while (bridge.TakeSimCommand(&c)) {
    changed = true;
    switch (static_cast<bridge::SimOp>(c.op)) {
      case bridge::SimOp::kReset:
        ResetState();
        break;
      case bridge::SimOp::kPause:
        *paused = true;
        *steps_left = -1;
        break;
      case bridge::SimOp::kResume:
        *paused = false;
        *steps_left = -1;
        clock.set_factor(clock.factor());  // realtime: pace from now, no catch-up burst
        break;
      case bridge::SimOp::kStep:
        *paused = false;
        *steps_left = static_cast<long>(c.arg);
        clock.set_factor(clock.factor());
        break;
      case bridge::SimOp::kSetRealtimeFactor:
        clock.set_factor(c.arg);
        break;
    }
  }
  return changed;
}

}  // namespace vlab::lab
