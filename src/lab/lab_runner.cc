#include "lab/lab_runner.h"

#include <chrono>
#include <cmath>
#include <fstream>

#include <nlohmann/json.hpp>

#include "lab/lab_arm_device.h"
#include "lab/lab_clock.h"
#include "lab/lab_controller.h"
#include "lab/lab_errors.h"
#include "lab/lab_log.h"
#include "lab/lab_output.h"
#include "lab/lab_wrench_device.h"

#ifndef VLAB_VERSION
#define VLAB_VERSION "0.0.0"
#endif

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
  std::vector<std::string> columns;
  std::vector<bridge::ArmState> arm_states;
  std::vector<bridge::ArmCommand> arm_commands;

  void ResetState();
  void WriteRow(double time_s, std::vector<double>& row) const;
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
    } else {
      impl->wrenches.push_back(SimWrench::Create(m, device, DeviceSeed(scenario.seed, device.name)));
    }
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

RunResult Lab::Run(const RunOptions& options) {
  Impl& s = *impl_;
  const auto t_start = WallClock::now();
  const mjModel* m = s.model.get();
  mjData* d = s.data.get();
  RunResult result;

  InstallMujocoHandlers();
  TakeMujocoWarningTexts();
  s.ResetState();
  std::unique_ptr<Clock> clock = MakeClock(s.scenario.clock, s.scenario.control_period_s);

  // checks first: a bad signal name is bad input, and must leave nothing behind
  CheckSet checks(s.scenario.checks, s.columns);
  // outputs: staging folder, log
  std::unique_ptr<OutputDir> out;
  std::unique_ptr<CsvLog> log;
  if (!options.out_dir.empty()) {
    out = OutputDir::Create(options.out_dir);
    const std::string staging = out->File("");
    SetMujocoErrorCleanup([staging] {
      std::error_code ec;
      std::filesystem::remove_all(staging, ec);
    });
    if (s.scenario.outputs.log) log = CsvLog::Open(out->File("log.csv"), s.columns);
  }
  std::vector<double> row(s.columns.size(), 0.0);
  const std::size_t controller_offset = s.columns.size() - (s.controller ? s.controller->Columns().size() : 0);

  const long periods = std::lround(s.scenario.duration_s / s.scenario.control_period_s);
  const double dt = m->opt.timestep;
  int warning_counts[mjNWARNING] = {0};
  double warning_first[mjNWARNING] = {0};
  if (options.record) {
    result.recording.controls.reserve(static_cast<std::size_t>(periods) * s.steps_per_period * m->nu);
  }
  // the controller's work for one period: computed, or replayed from a recording
  const std::size_t controller_columns = s.controller ? s.controller->Columns().size() : 0;
  std::size_t replay_at = 0;
  auto run_controller = [&](double t) {
    const int a = s.controller_arm;
    bridge::ArmCommand& cmd = s.arm_commands[a];
    double* columns = row.data() + controller_offset;
    if (options.replay) {
      if (replay_at + 1 + s.arms[a]->dof() + controller_columns > options.replay->controller.size()) {
        throw std::runtime_error("replay: the recording is shorter than this run");
      }
      const double* r = options.replay->controller.data() + replay_at;
      cmd.mode = static_cast<bridge::ArmMode>(static_cast<int>(r[0]));
      cmd.value = Eigen::Map<const Eigen::VectorXd>(r + 1, s.arms[a]->dof());
      std::copy(r + 1 + s.arms[a]->dof(), r + 1 + s.arms[a]->dof() + controller_columns, columns);
      replay_at += 1 + s.arms[a]->dof() + controller_columns;
      return;
    }
    s.controller->Update(t, s.arm_states[a], &cmd, columns);
    if (options.record) {
      std::vector<double>& rec = result.recording.controller;
      rec.push_back(static_cast<double>(static_cast<int>(cmd.mode)));
      for (int i = 0; i < s.arms[a]->dof(); ++i) rec.push_back(i < cmd.value.size() ? cmd.value[i] : 0.0);
      rec.insert(rec.end(), columns, columns + controller_columns);
    }
  };

  auto emit_row = [&](double t) {
    s.WriteRow(t, row);
    if (log) log->Append(row.data());
    checks.Add(t, row.data());
  };
  // controller columns of row 0: let the controller see the initial state
  if (s.controller) run_controller(0.0);
  emit_row(0.0);

  const auto t_loop = WallClock::now();
  auto t_progress = t_loop;
  bool diverged = false;
  long k = 0;
  for (; k < periods && !diverged; ++k) {
    // period k runs from t_k = k T to t_k+1; times are exact multiples of T
    const double t_k = k * s.scenario.control_period_s;
    const double t_next = (k + 1) * s.scenario.control_period_s;
    clock->BeginPeriod(k, t_k);
    // 1. commands: the controller answers the newest sample
    if (s.controller) {
      const int a = s.controller_arm;
      if (k > 0) run_controller(t_k);
      if (s.arm_commands[a].mode != bridge::ArmMode::kHold || k > 0) s.arms[a]->Command(s.arm_commands[a]);
    }
    // 2. physics
    for (int i = 0; i < s.steps_per_period; ++i) {
      const double t_step = d->time;
      mj_step1(m, d);
      for (auto& arm : s.arms) arm->Actuate(*d, dt);
      if (options.record) result.recording.controls.insert(result.recording.controls.end(), d->ctrl, d->ctrl + m->nu);
      mj_step2(m, d);
      for (auto& w : s.wrenches) w->Step(*d, dt);
      ++result.steps;
      for (int w = 0; w < mjNWARNING; ++w) {
        // (a divergence resets mjData, time and other counters included: keep ours)
        if (d->warning[w].number > warning_counts[w]) {
          if (warning_counts[w] == 0) warning_first[w] = t_step;
          warning_counts[w] = d->warning[w].number;
          if (IsDivergenceWarning(w)) diverged = true;
        }
      }
      if (diverged) break;
    }
    if (diverged) break;
    // 3. sample devices and log
    for (auto& w : s.wrenches) w->EndPeriod();
    for (std::size_t i = 0; i < s.arms.size(); ++i) s.arms[i]->Sample(*d, t_next, &s.arm_states[i]);
    emit_row(t_next);
    clock->EndPeriod(k);
    if (options.interrupt && *options.interrupt) {
      if (log) log->Close();
      throw std::runtime_error("interrupted at t = " + FormatDouble(t_next) + " s; nothing written");
    }
    if (options.progress && (k & 63) == 0) {
      const auto now = WallClock::now();
      if (Seconds(t_progress, now) > 0.1) {
        options.progress(static_cast<double>(k + 1) / periods);
        t_progress = now;
      }
    }
  }
  result.loop_wall_s = Seconds(t_loop, WallClock::now());
  result.periods = k;
  result.sim_time_s = k * s.scenario.control_period_s;

  // warnings: MuJoCo's own text for the last occurrence of each kind
  TakeMujocoWarningTexts();
  for (int w = 0; w < mjNWARNING; ++w) {
    if (warning_counts[w] == 0) continue;
    WarningReport report;
    report.name = WarningName(w);
    report.count = warning_counts[w];
    report.first_time_s = warning_first[w];
    report.message = mju_warningText(w, d->warning[w].lastinfo);
    for (const auto& allowed : s.scenario.allow_warnings) report.allowed = report.allowed || allowed == report.name;
    result.warnings.push_back(report);
  }
  result.checks = checks.Results();

  // verdict: divergence first, then disallowed warnings, then checks
  if (diverged) {
    for (const auto& wr : result.warnings) {
      if (IsDivergenceWarning(WarningIndex(wr.name))) {
        result.failure = "diverged at t = " + FormatDouble(wr.first_time_s) + " s: " + wr.message;
        break;
      }
    }
  }
  if (result.failure.empty()) {
    for (const auto& wr : result.warnings) {
      if (!wr.allowed) {
        result.failure = "MuJoCo warning '" + wr.name + "' (" + std::to_string(wr.count) + "x, first at t = " +
                         FormatDouble(wr.first_time_s) + " s): " + wr.message;
        break;
      }
    }
  }
  if (result.failure.empty()) {
    for (const auto& c : result.checks) {
      if (!c.pass) {
        result.failure = "check '" + c.config.name + "' failed: " + c.config.reduce + "(" + c.config.signal +
                         ") = " + FormatDouble(c.value);
        break;
      }
    }
  }
  result.exit_code = result.failure.empty() ? 0 : 1;

  if (out) {
    if (log) log->Close();
    result.total_wall_s = Seconds(t_start, WallClock::now());
    std::ofstream summary(out->File("summary.json"));
    summary << SummaryJson(s.scenario, m, result).dump(2) << "\n";
    summary.close();
    if (!summary) throw std::runtime_error("summary '" + out->File("summary.json") + "': write failed");
    out->Commit();
    SetMujocoErrorCleanup(nullptr);
  }
  result.total_wall_s = Seconds(t_start, WallClock::now());
  return result;
}

nlohmann::json SummaryJson(const Scenario& sc, const mjModel* m, const RunResult& r) {
  using nlohmann::json;
  auto number = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  json checks = json::array();
  for (const auto& c : r.checks) {
    json bound = json::object();
    if (std::isfinite(c.config.min)) bound["min"] = c.config.min;
    if (std::isfinite(c.config.max)) bound["max"] = c.config.max;
    json window = {{"from", c.config.from_s}, {"to", number(c.config.to_s)}};
    checks.push_back({{"name", c.config.name}, {"signal", c.config.signal}, {"reduce", c.config.reduce},
                      {"value", number(c.value)}, {"bound", bound}, {"window_s", window},
                      {"samples", c.samples}, {"pass", c.pass}});
  }
  json warnings = json::array();
  for (const auto& w : r.warnings) {
    warnings.push_back({{"name", w.name}, {"count", w.count}, {"first_time_s", w.first_time_s},
                        {"message", w.message}, {"allowed", w.allowed}});
  }
  const double rtf = r.loop_wall_s > 0 ? r.sim_time_s / r.loop_wall_s : 0.0;
  return {
      {"scenario", sc.name},
      {"file", sc.file},
      {"description", sc.description},
      {"scene", sc.scene},
      {"result", r.exit_code == 0 ? "pass" : "fail"},
      {"exit_code", r.exit_code},
      {"failure", r.failure},
      {"seed", sc.seed},
      {"clock", sc.clock},
      {"duration_s", sc.duration_s},
      {"control_period_s", sc.control_period_s},
      {"timestep_s", m->opt.timestep},
      {"checks", checks},
      {"warnings", warnings},
      {"versions",
       {{"vlab", VLAB_VERSION}, {"mujoco", MujocoVersion()}, {"compiler", __VERSION__},
        {"eigen", std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) + "." +
                      std::to_string(EIGEN_MINOR_VERSION)}}},
      {"timings",
       {{"sim_time_s", r.sim_time_s}, {"steps", r.steps}, {"control_periods", r.periods},
        {"loop_wall_s", r.loop_wall_s}, {"total_wall_s", r.total_wall_s},
        {"steps_per_s", r.loop_wall_s > 0 ? r.steps / r.loop_wall_s : 0.0}, {"realtime_factor", rtf}}},
  };
}

}  // namespace vlab::lab
