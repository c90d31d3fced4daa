#include "lab/run/lab_run_session.h"

#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "bridge/bridge_signals.h"
#include "core/core_mujoco.h"
#include "core/core_realtime.h"
#include "lab/outputs/lab_log_formats.h"
#include "lab/outputs/lab_plot.h"

namespace vlab::lab {

namespace {

// how long an external controller gets to exit after SIGTERM at the end of a run
constexpr double kControllerGrace_s = 2.0;
// the longest wait for a controller's answer to the final state (lockstep), s
constexpr double kFinalAnswerWait_s = 2.0;

double Seconds(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

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
  RunSession run(*impl_, options);
  run.Prepare();
  run.Start();
  while (run.period_index() < run.periods() && run.Period()) {
  }
  return run.Finish();
}

RunSession::RunSession(Lab::Impl& lab, const RunOptions& options)
    : s_(lab), options_(options), m_(lab.model.get()), d_(lab.data.get()), period_(lab.scenario.control_period_s),
      periods_(std::lround(lab.scenario.duration_s / period_)), t_start_(WallClock::now()) {}

// the MuJoCo error cleanup (the staging folder's removal) ends with the run, however it ends
RunSession::~RunSession() {
  SetMujocoErrorCleanup(nullptr);
  if (s_.task) s_.task->SetIdle(nullptr);  // the bridge goes with the session
}

void RunSession::Prepare() {
  InstallMujocoHandlers();
  TakeMujocoWarningTexts();
  s_.ResetState();  // (a camera is served only while a bridge exists: LabBridge serves and unserves it)
  // a scenario's external controller: vlab run serves on loopback and starts it
  const Scenario& sc = s_.scenario;
  external_ = StartsExternalController(sc, options_.serve != nullptr);
  if (external_) external_serve_ = ExternalBridgeOptions(sc);
  const BridgeOptions* serve = external_ ? &external_serve_ : options_.serve;
  const ClockMode mode = external_ ? ExternalClock(sc, options_.clock) : options_.clock.value_or(sc.clock);
  ClockConfig clock = ScenarioClock(sc, mode);
  clock.stop = options_.interrupt;  // a stop signal ends the clock's waits
  clock_ = MakeClock(clock, periods_);
  result_.clock = clock_->mode();

  // checks first: a bad signal name is bad input, and must leave nothing behind
  // (golden checks compare the written log after the run: lab_run_golden.cc)
  std::vector<CheckConfig> signal_checks;
  for (const CheckConfig& c : sc.checks) {
    if (c.golden.empty()) signal_checks.push_back(c);
  }
  checks_ = std::make_unique<CheckSet>(signal_checks, s_.columns);
  for (const PlotConfig& plot : sc.outputs.plots) CheckPlotColumns(plot, s_.columns);
  // image outputs: cameras and sizes checked against the scene before anything is written
  if (!options_.out_dir.empty() && !sc.outputs.images.empty()) {
    images_ = ImageOutputs::Create(m_, sc.outputs.images, sc.scene, period_);
  }
  if (!options_.out_dir.empty() && sc.outputs.poses) {
    poses_ = PoseRecorder::Create(m_, sc.outputs.poses_rate_hz, period_, sc.scene, sc.outputs.poses_where);
  }
  // the wire: bind every served device before anything is written
  if (serve) {
    bridge_ = s_.MakeBridge(*serve, clock_->name());
    // a task program waiting in wall time (markers) lets the lab serve meanwhile
    if (s_.task) s_.task->SetIdle([b = bridge_.get()] { b->Poll(0.0, PollWait::kSleep); });
    writers_.push_back(bridge_.get());  // the wire writes first
  }
  writers_.insert(writers_.end(), s_.writers.begin(), s_.writers.end());
  // outputs: staging folder (removed on a MuJoCo error too), log
  if (!options_.out_dir.empty()) {
    out_ = OutputDir::Create(options_.out_dir);
    SetMujocoErrorCleanup([staging = out_->File("")] {
      std::error_code ec;
      std::filesystem::remove_all(staging, ec);
    });
    if (sc.outputs.log)
      log_ = OpenRunLog(out_->staging_dir(), sc.outputs.log_formats, s_.columns, McapContent(), &mcap_);
    for (std::size_t i = 0; mcap_ && i < sc.outputs.images.size(); ++i) {
      const int camera = mcap_->CameraIndex(sc.outputs.images[i].camera);
      if (camera >= 0 && sc.outputs.images[i].png) mcap_cameras_.push_back({i, camera, 0});
    }
    if (images_) images_->Open(*out_);
    if (poses_) poses_->Open(*out_);
  }
  if (external_) {
    const std::string log_path = out_ ? out_->File("controller.log") : "";
    // free ports for the programs it starts ({port:NAME}), held until just before it starts
    const std::vector<ServedDevice> served = bridge_->Devices();
    PortReservations ports = PortReservations::Reserve(CommandPortNames(sc, sc.controller.where), "127.0.0.1");
    const std::string out_dir = out_ ? out_->File("") : "";
    const std::vector<std::string> argv =
        ExpandCommand(sc.controller.command, CommandValues(sc, served, out_dir, ports.ports()), sc.controller.where);
    result_.controller.ports = ports.ports();
    ports.Release();
    controller_ = ExternalController::Start(argv, log_path, sc.controller.realtime_priority,
                                            CommandEnvironment(served, ports.ports()));
    result_.controller.realtime = controller_->realtime();
    bridge_->WatchPeerExit(controller_->exit_fd(), sc.controller.ends_run);
  }
  if (options_.record) {
    result_.recording.controls.reserve(static_cast<std::size_t>(periods_) * s_.steps_per_period * m_->nu);
  }
  row_.assign(s_.columns.size(), 0.0);
  controller_columns_ = row_.data() + s_.columns.size() - s_.controller_columns;
}

void RunSession::EmitRow(double t) {
  s_.WriteRow(t, row_);
  for (LogReader* reader : s_.log_readers) reader->LogRow(row_.data());
  if (log_) log_->Append(row_.data());
  checks_->Add(t, row_.data());
}

void RunSession::Publish(long k) {
  if (!bridge_) return;
  if (s_.sim) s_.sim->set_state(SimState(k * period_, paused_, *clock_, k, bridge_.get()));
  bridge_->Publish(k, k * period_);
}

void RunSession::RenderAfterPublish(double t) {
  for (RenderedOutput* output : s_.rendered) output->AfterPublish(d_);
  if (images_) images_->Observe(t, d_);
  if (poses_) poses_->Observe(t, std::round(t / period_), *d_);
  if (mcap_) FeedMcap();
}

void RunSession::Start() {
  // first: the threads started from here on (a camera's render worker) inherit it
  RequestPriority();
  // row 0: the initial state, with the controllers' view of it (a task program may fail already)
  const CommandPeriod period0 = CommandPeriodAt(0, 0.0);
  for (CommandWriter* writer : writers_) {
    if (!restart_failed_ && !writer->Restart(period0, &result_.failure)) restart_failed_ = true;
  }
  EmitRow(0.0);
  if (options_.observe) options_.observe(0.0, m_, d_);
  for (RenderedOutput* output : s_.rendered) output->BeforeRun(d_);
  // the ports line says the devices answer now: after the cameras' GL start-up, which can take
  // seconds on a loaded machine while nothing reads the sockets
  if (bridge_ && options_.on_serving && !external_) options_.on_serving(bridge_->Devices());
  for (RenderedOutput* output : s_.rendered) output->Deliver(0.0, d_);
  Publish(0);
  Recorded(0.0);  // (a failed write ends the run before its first period)
  NoteWaiting();
  if (options_.loop_cpu >= 0) {
    loop_cpus_before_ = ThreadCpus();
    if (!BindThread(0, {options_.loop_cpu})) loop_cpus_before_.clear();
  }
  t_loop_ = t_progress_ = WallClock::now();
}

void RunSession::RequestPriority() {
  // the threads made before (the log writer, in Prepare) keep normal priority
  const int priority = options_.realtime_priority.value_or(s_.scenario.realtime.priority);
  if (clock_->mode() != ClockMode::kFast) {
    // realtime beside cameras without SCHED_FIFO: the loop keeps a CPU, their workers take the others
    bool cameras = false;
    for (const auto& device : s_.devices) cameras = cameras || device->kind() == bridge::DeviceKind::kCamera;
    // and a realtime loop asks for SCHED_DEADLINE over its period (core_realtime.h)
    const bool realtime = clock_->mode() == ClockMode::kRealtime;
    result_.realtime = RequestRealtime(priority, cameras && realtime, realtime ? period_ : 0.0);
  } else if (priority > 0) {
    result_.realtime.requested = priority;
    result_.realtime.reason = "not used: the fast clock has no deadlines";
  }
  if (!options_.on_realtime) return;
  if (priority > 0) options_.on_realtime(result_.realtime.Line());
  if (result_.controller.realtime.requested > 0) {
    options_.on_realtime("controller: " + result_.controller.realtime.Line());
  }
}

void RunSession::NoteWaiting() {
  if (!options_.on_waiting || external_ || !bridge_ || clock_->mode() == ClockMode::kFast || bridge_->Answered(0)) {
    return;
  }
  const std::string line =
      WaitingLine(bridge_->Devices(), s_.device_ptrs, clock_->name(), s_.scenario.lockstep.start_timeout_s);
  if (!line.empty()) options_.on_waiting(line);
}

bool RunSession::Interrupted() {
  if (!options_.interrupt || *options_.interrupt == 0) return false;
  result_.interrupted_by = *options_.interrupt;
  result_.failure = "interrupted by " + StopSignalName(result_.interrupted_by) +
                    " at t = " + FormatDouble(k_ * period_) + " s, after " + std::to_string(k_) + " of " +
                    std::to_string(periods_) + " periods";
  return true;
}

std::string RunSession::NoController() const {
  if (!bridge_ || external_ || clock_->mode() != ClockMode::kLockstep) return "";
  return NoControllerReason(result_.served, s_.device_ptrs);
}

bool RunSession::Commands(long k, double t_k) {
  // the clock lets the period begin; commands: the newest of each device
  const PeriodStart start = clock_->BeginPeriod(k, bridge_.get());
  if (start == PeriodStart::kStopped && Interrupted()) return false;
  // a controller that ends the run (controller.ends_run) exited without answering period k: its
  // status, read at once (its exit closed the pipe the clock waited on), says how the run ends.
  // Lockstep: the first period it left unanswered, the same every run
  // (waited for once: a program that closed the pipe and runs on is not waited for every period)
  bool ended = false;
  if (controller_ && s_.scenario.controller.ends_run && bridge_->GoneWithoutAnswering(k)) {
    if (!exit_waited_) controller_->WaitExited(kControllerGrace_s);
    exit_waited_ = true;
    ended = controller_->Exited();
  }
  if (controller_ && bridge_->peer_gone() && controller_->Exited() && !controller_->Succeeded()) {
    result_.failure = ControllerFailure(*controller_, t_k);
    return false;
  }
  if (ended) {
    result_.controller.ended_run = true;  // (status 0: the run ends here, its checks judge it)
    return false;
  }
  if (start == PeriodStart::kFail) {
    result_.failure = "lockstep: no command answering period " + std::to_string(k) + " (t = " + FormatDouble(t_k) +
                      " s) within " + FormatDouble(s_.scenario.lockstep.timeout_s) + " s";
    return false;
  }
  if (bridge_) {
    if (start == PeriodStart::kTimedOut) {
      bridge_->NoteTimeout(s_.scenario.lockstep.release_after);
    } else {
      bridge_->NoteAnswered();
    }
  }
  // the command sources, in order (the wire, the lab's controller, the devices that drive another);
  // a failure ends the run (a task program's script error: the log keeps the periods before)
  const CommandPeriod period = CommandPeriodAt(k, t_k);
  for (CommandWriter* writer : writers_) {
    if (!writer->Write(period, &result_.failure)) return false;
  }
  return true;
}

bool RunSession::Period() {
  // period k runs from t_k = k T to t_k+1; times are exact multiples of T
  const double t_k = k_ * period_;
  const double t_next = (k_ + 1) * period_;
  if (Interrupted() || output_failed_) return false;  // the periods run so far are written
  if (restart_failed_) return false;  // a command source failed at row 0 (a task program's script error)
  // 0. the sim device: pause, resume, step, reset, pace
  if (bridge_ && s_.HandleSimCommands(*bridge_, *clock_, &paused_, &steps_left_)) Publish(k_);
  if (paused_) {
    bridge_->Poll(0.02, PollWait::kSpin);
    // the pauser owner no more (silent, unsubscribed, or no driver while a controller drives):
    // nobody else may resume, so the lab resumes itself, or stays paused if the scenario says so
    bridge_->ReleaseSilentOwner(*s_.sim);
    if (!bridge_->HasOwner(*s_.sim) && s_.sim->on_owner_lost() == OnOwnerLost::kResume) {
      paused_ = false;
      steps_left_ = -1;
      clock_->set_factor(clock_->factor());  // realtime: pace from now
      Publish(k_);
    }
    return true;
  }
  // 1. the clock, the commands
  if (!Commands(k_, t_k)) return false;
  // 2. physics: the servo acts between the two halves of every step
  for (int i = 0; i < s_.steps_per_period && !diverged_; ++i) {
    const double t_step = d_->time;
    mj_step1(m_, d_);
    for (StepHooks* hooks : s_.step_hooks) hooks->Actuate(*d_, m_->opt.timestep);
    if (options_.record)
      result_.recording.controls.insert(result_.recording.controls.end(), d_->ctrl, d_->ctrl + m_->nu);
    mj_step2(m_, d_);
    for (StepHooks* hooks : s_.step_hooks) hooks->AfterStep(*d_, m_->opt.timestep);
    ++result_.steps;
    diverged_ = warnings_.Update(*d_, t_step);
  }
  if (diverged_) return false;
  // 3. sample devices, log, publish the state that closes the period
  for (auto& dev : s_.devices) dev->Sample(*d_, t_next);
  EmitRow(t_next);
  if (options_.observe) options_.observe(t_next, m_, d_);
  for (RenderedOutput* output : s_.rendered) output->Deliver(t_next, d_);
  ++k_;
  if (steps_left_ > 0 && --steps_left_ == 0) paused_ = true;
  Publish(k_);
  if (!Recorded(t_next)) return false;  // the first failed write ends the run: what ran is kept
  if (options_.progress && (k_ & 63) == 0 && Seconds(t_progress_, WallClock::now()) > 0.1) {
    options_.progress(static_cast<double>(k_) / periods_);
    t_progress_ = WallClock::now();
  }
  return true;
}

CommandPeriod RunSession::CommandPeriodAt(long k, double t_k) {
  CommandPeriod period;
  period.k = k;
  period.t_s = t_k;
  period.columns = controller_columns_;
  period.data = d_;
  // realtime: the watchdog also counts wall time, so the periods the lab runs back to back
  // to catch up on its own lateness earn a prompt controller no hold
  const bool paced = clock_->mode() == ClockMode::kRealtime && clock_->factor() > 0;
  period.pace_s = paced ? period_ / clock_->factor() : 0.0;
  period.options = &options_;
  period.result = &result_;
  return period;
}

void RunSession::AwaitFinalAnswer() {
  // The last period publishes the state that closes the run, and nothing applies a command
  // to it. Stopped at once, the controller had or had not handled it (and written a row of
  // its own log for it) by the time SIGTERM came: its log's last row varied from run to run.
  if (!controller_ || !bridge_ || clock_->mode() != ClockMode::kLockstep || diverged_ || !result_.failure.empty()) {
    return;
  }
  const auto until = WallClock::now() + std::chrono::duration_cast<WallClock::duration>(std::chrono::duration<double>(
                                            std::min(s_.scenario.lockstep.timeout_s, kFinalAnswerWait_s)));
  while (!bridge_->Answered(k_) && !controller_->Exited() && WallClock::now() < until) {
    if (options_.interrupt && *options_.interrupt != 0) return;
    bridge_->Poll(0.001, PollWait::kSpin);
  }
}

RunResult RunSession::Finish() {
  result_.loop_wall_s = Seconds(t_loop_, WallClock::now());
  if (!loop_cpus_before_.empty()) BindThread(0, loop_cpus_before_);
  AwaitFinalAnswer();
  DropRealtime(result_.realtime);  // the outputs are written at normal priority
  if (controller_) {
    controller_->Stop(kControllerGrace_s);
    if (!controller_->Succeeded() && result_.failure.empty()) {
      result_.failure = ControllerFailure(*controller_, k_ * period_);
    }
    result_.controller.program = controller_->program();
    result_.controller.outcome = controller_->Outcome();
  }
  result_.periods = k_;
  result_.sim_time_s = k_ * period_;
  TakeMujocoWarningTexts();  // their content is in the reports: mju_warningText
  result_.warnings = warnings_.Reports(s_.scenario.allow_warnings);
  result_.checks = checks_->Results(k_ * period_);
  if (bridge_) {
    result_.served = bridge_->Devices();
    result_.latencies_s = bridge_->latencies();
    result_.command_ages_s = bridge_->command_ages();
  }
  if (result_.failure.empty()) result_.failure = Verdict(result_, diverged_, NoController());
  result_.exit_code = result_.failure.empty() ? 0 : 1;
  result_.clock_stats = clock_->stats();
  if (out_) WriteOutputs();
  result_.total_wall_s = Seconds(t_start_, WallClock::now());
  return result_;
}

}  // namespace vlab::lab
