// The lab: one scenario's model, devices, controller and clock, and the step
// loop that advances them.
//
// Each control period k (length T, a whole number of model timesteps):
//   1. the clock lets period k begin;
//   2. the controller reads the newest device outputs and sends its commands;
//   3. T / timestep physics steps: mj_step1, arm servo, mj_step2, wrench
//      sensors sample the new contact/constraint forces;
//   4. the devices are sampled and one log row is written.
// Sensors and logging read the state and never change it.
#pragma once

#include <csignal>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "core/core_clock.h"
#include "core/core_mujoco.h"
#include "core/core_realtime.h"
#include "lab/judge/lab_checks.h"
#include "lab/run/lab_bridge.h"
#include "lab/scenario/lab_scenario.h"

namespace vlab::lab {

struct RunOptions {
  std::string out_dir;  ///< where to write log.csv and summary.json ("" = nothing written)
  /// Called about every 0.1 s of wall time with the fraction of the run done.
  std::function<void(double fraction)> progress;
  /// The number of a signal that asks the run to stop (0 while none came;
  /// g_stop_requested of bridge_signals.h). The run ends at the next period
  /// boundary (a clock's wait, a pause, within kStopCheck_s) and writes what ran:
  /// log.csv up to the last whole period, summary.json with result
  /// `interrupted`, the plots and images (RunResult::interrupted_by, exit code 1).
  /// Once the run loop has ended it is no longer read: a signal while the files
  /// are written changes nothing.
  const volatile std::sig_atomic_t* interrupt = nullptr;
  /// Record what the run computed, for replay (the physics benchmark).
  bool record = false;
  /// Replay a recording of the same scenario: the controller's commands and
  /// log columns come from it instead of the controller (same trajectory, no
  /// controller cost).
  const struct Recording* replay = nullptr;
  /// Serve the devices over UDP (vlab serve) with these options (nullptr: don't).
  const BridgeOptions* serve = nullptr;
  /// Clock to use instead of the scenario's (none: the scenario's).
  std::optional<ClockMode> clock;
  /// Called once the served devices are bound and answer (after the cameras' render start-up),
  /// before the first period.
  std::function<void(const std::vector<ServedDevice>&)> on_serving;
  /// Served runs that vlab does not start the controller of (vlab serve),
  /// lockstep or realtime: called once when period 0 begins waiting for the
  /// controllers, with one line naming the devices waited for, their addresses,
  /// the clock and the start timeout.
  std::function<void(const std::string& message)> on_waiting;
  /// Called with the state at t = 0 and at the end of every period, after the
  /// log row and before the states are published (renderers, image outputs,
  /// cameras). It reads the state and must not change it: mjv_updateScene
  /// wants a non-const mjData, nothing else may write through it.
  std::function<void(double t, const mjModel* m, mjData* d)> observe;
  /// SCHED_FIFO priority of the control thread (0: normal) instead of the
  /// scenario's realtime.priority; lockstep and realtime runs only.
  std::optional<int> realtime_priority;
  /// Called once before period 0 with what each realtime priority asked for got
  /// (the lab's, and an external controller's), one line each.
  std::function<void(const std::string& line)> on_realtime;
  /// The CPU the step loop runs on from period 0 to its end (vlab bench physics: a loop
  /// that does not migrate, as a realtime loop that keeps a CPU); the threads made before,
  /// the log writer's among them, keep the CPUs the calling thread had, and it has them
  /// again when the loop ends. -1: the thread's CPUs are left as they are.
  int loop_cpu = -1;
  /// No print() output of task programs (controller type task) on stdout; it
  /// is still kept in RunResult::task_output (vlab run -q).
  bool quiet = false;
};

/// What a recorded run computed.
struct Recording {
  std::vector<double> controls;    ///< nu motor controls per physics step
  std::vector<double> controller;  ///< per control period: mode, command values, controller columns
};

struct WarningReport {
  std::string name;
  int count = 0;
  double first_time_s = 0.0;
  std::string message;
  bool allowed = false;
};

struct RunResult {
  int exit_code = 0;    ///< 0 all checks pass, 1 a check failed, the run diverged or was interrupted
  std::string failure;  ///< one line when exit_code != 0
  /// The signal that interrupted the run (RunOptions::interrupt), 0 when none did.
  int interrupted_by = 0;
  std::vector<CheckResult> checks;
  std::vector<WarningReport> warnings;
  long steps = 0;    ///< physics steps taken
  long periods = 0;  ///< control periods taken
  double sim_time_s = 0.0;
  double loop_wall_s = 0.0;            ///< wall time of the step loop
  double total_wall_s = 0.0;           ///< wall time including writing outputs
  Recording recording;                 ///< if RunOptions::record
  ClockMode clock = ClockMode::kFast;  ///< the clock that ran
  /// The control thread's realtime priority: asked for, granted, and why not.
  RealtimeGrant realtime;
  ClockStats clock_stats;
  std::vector<ServedDevice> served;    ///< served devices with their counters (vlab serve)
  std::vector<double> latencies_s;     ///< command arrival-to-apply latencies (vlab serve)
  long log_waits = 0;                  ///< times the step loop waited for the log writer (it fell behind)
  double log_wait_s = 0;               ///< and how long in all, s
  std::vector<double> command_ages_s;  ///< newest command's age at each period's start (vlab serve)
  /// Plots not drawn, each "FILE: why": a CSV an external controller writes, where the lab
  /// did not start the controller (vlab serve) and nobody wrote it.
  std::vector<std::string> plots_skipped;
  /// The folder that holds the run's files ("" without one): RunOptions::out_dir, or a
  /// sibling DIR.N when another run put its folder at DIR meanwhile (lab_output.h).
  std::string out_dir;
  /// "" when the files are in RunOptions::out_dir as asked; else one line: where and why.
  std::string out_note;
  /// The external controller `vlab run` started: program and how it ended ("" when none).
  struct {
    std::string program;
    std::string outcome;
    RealtimeGrant realtime;            ///< its controller.realtime_priority, read off the program
    std::map<std::string, int> ports;  ///< the free ports its {port:NAME} placeholders got
    bool ended_run = false;            ///< it ended the run (controller.ends_run: it exited with status 0)
  } controller;
  /// What the task programs (controller type task) printed, one line each:
  /// "[ROBOT t=SECONDS] TEXT" (simulated time), and a script error's first line
  /// as "[error t=SECONDS] FILE:LINE: ...": the run's task.log.
  std::string task_output;
};

class Lab {
 public:
  /// Loads the scene and binds devices and controller. Throws InputError.
  static std::unique_ptr<Lab> Create(const Scenario& scenario);
  ~Lab();

  /// Runs the scenario once from its initial state. Throws InputError for bad
  /// input (nothing written). The first failed write (disk full, a file size
  /// limit) ends the run at once: exit_code 1, failure names the file and the
  /// error, and what was written is kept in out_dir.
  RunResult Run(const RunOptions& options);

  /// Puts `data` (made for model()) into the scenario's initial state: reset,
  /// initial joint positions, mj_forward. The same state Run() starts from.
  void InitialState(mjData* data) const;

  /// Binds the served devices as `vlab serve` would and returns their
  /// endpoints and describe replies, then frees the ports.
  std::vector<ServedDevice> Describe(const BridgeOptions& options, std::optional<ClockMode> clock) const;

  /// qpos at the end of the last Run().
  std::vector<double> FinalQpos() const;

  /// Log column names, in order.
  std::vector<std::string> Columns() const;
  const mjModel* model() const;
  const Scenario& scenario() const;

 private:
  struct Impl;
  friend class RunSession;  // one run of the lab (lab_run_session.h)
  explicit Lab(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

/// Writes summary.json's content for a run.
nlohmann::json SummaryJson(const Scenario& scenario, const mjModel* model, const RunResult& result);

}  // namespace vlab::lab
