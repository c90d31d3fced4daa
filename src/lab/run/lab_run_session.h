// One run of a lab (Lab::Run), in three parts that each fit on a screen:
// Prepare (clock, checks, image outputs, the wire, the output folder, an
// external controller; nothing is written before all of it is valid), Period
// (one control period: the sim device, the clock, commands, physics, samples,
// log row, publish) and Finish (the controller's verdict, checks, plots,
// summary, the output folder committed). An interrupt (RunOptions::interrupt)
// ends the periods at a period boundary; Finish then writes what ran. So does
// the first failed write (the log's, the poses', an image's): the run stops in
// that period, and what was written is kept. Not a public header.
#pragma once

#include <chrono>
#include <cstddef>
#include <memory>
#include <vector>

#include "core/core_clock.h"
#include "lab/judge/lab_checks.h"
#include "lab/outputs/lab_images.h"
#include "lab/outputs/lab_log.h"
#include "lab/outputs/lab_log_mcap.h"
#include "lab/outputs/lab_output.h"
#include "lab/outputs/lab_poses.h"
#include "lab/run/lab_bridge.h"
#include "lab/run/lab_command_writer.h"
#include "lab/run/lab_external.h"
#include "lab/run/lab_run_watch.h"
#include "lab/run/lab_runner.h"
#include "lab/run/lab_runner_impl.h"

namespace vlab::lab {

class RunSession {
 public:
  RunSession(Lab::Impl& lab, const RunOptions& options);
  ~RunSession();

  /// Resets the lab and makes everything the run needs; throws InputError
  /// (nothing written) for bad input.
  void Prepare();
  /// Row 0 and the states of t = 0.
  void Start();
  /// Runs period k (or waits while paused). False when the run must stop
  /// early: a failure (result().failure), a divergence, an interrupt, or a
  /// controller that ends the run exited.
  bool Period();
  /// Ends the run: the controller's verdict, the result, and the output folder.
  RunResult Finish();

  long periods() const { return periods_; }
  long period_index() const { return k_; }

 private:
  using WallClock = std::chrono::steady_clock;
  void EmitRow(double t);
  void Publish(long k);
  // what renders from the state at period end t without being part of the period's states:
  // the camera frames delivered later, the image outputs; after the states went out, so that
  // rendering does not delay them (the state is still that of t: the next period has not begun)
  void RenderAfterPublish(double t);
  // the poses and frames written since the last call, to log.mcap's sink (lab_run_outputs.cc)
  void FeedMcap();
  // what log.mcap carries besides the columns: poses_' bodies, the PNG cameras of images_
  McapLogContent McapContent() const;
  // RenderAfterPublish, then whether every output still writes: false (the run stops, its
  // failure set) on the first failed write or render (lab_run_outputs.cc)
  bool Recorded(double t);
  // the run's failure becomes `why` (a file that could not be written), at the current period
  void StopOnOutputFailure(const std::string& why);
  // a failed write while finishing: the run fails with it, the other files are still written
  void NoteWriteFailure(const std::string& why);
  // the commands of period k: the clock lets it begin, then every command source writes; false on a failure
  bool Commands(long k, double t_k);
  // what every command source gets for period k
  CommandPeriod CommandPeriodAt(long k, double t_k);
  // true once a stop signal came: the run's failure then says which, and when
  bool Interrupted();
  // vlab serve: says once which devices period 0 waits for
  void NoteWaiting();
  // lockstep with a controller that vlab run started: waits (bounded) for its answer to the
  // final state before it is stopped, so what it makes of that state is the same every run
  void AwaitFinalAnswer();
  // lockstep and realtime: the control thread on SCHED_FIFO when asked and permitted
  void RequestPriority();
  // vlab serve in lockstep: why the run had no controller ("" when a command arrived)
  std::string NoController() const;
  // the files of the run's end, each attempted whatever failed before; the folder committed
  void WriteOutputs();
  /// Compares the written log.csv with each golden check's golden (lab_run_golden.cc).
  void EvaluateGoldenChecks();

  Lab::Impl& s_;
  const RunOptions& options_;
  const mjModel* m_;
  mjData* d_;
  double period_;
  long periods_;
  RunResult result_;
  WallClock::time_point t_start_, t_loop_, t_progress_;
  std::vector<int> loop_cpus_before_;  // the thread's CPUs before RunOptions::loop_cpu bound it
  bool external_ = false;
  BridgeOptions external_serve_;
  std::unique_ptr<Clock> clock_;
  std::unique_ptr<CheckSet> checks_;
  std::unique_ptr<ImageOutputs> images_;
  std::unique_ptr<PoseRecorder> poses_;  // outputs.poses
  std::unique_ptr<LabBridge> bridge_;
  std::unique_ptr<OutputDir> out_;
  std::unique_ptr<CsvLog> log_;
  McapLogSink* mcap_ = nullptr;  // log.mcap's sink in log_ (outputs.log.format mcap), fed poses and frames
  long mcap_poses_ = 0;          // poses_' frames handed to it
  struct McapCameraFeed {
    std::size_t output;  // index in images_
    int camera;          // McapLogSink::CameraIndex
    std::size_t frames;  // frames handed to it
  };
  std::vector<McapCameraFeed> mcap_cameras_;
  std::unique_ptr<ExternalController> controller_;
  bool exit_waited_ = false;  // ends_run: the controller's exit was waited for once
  std::vector<double> row_;
  double* controller_columns_ = nullptr;
  std::vector<CommandWriter*> writers_;  // the command sources in the order they write: the wire's first
  bool restart_failed_ = false;          // a command source failed at row 0: no period runs
  WarningWatch warnings_;
  bool paused_ = false;
  long steps_left_ = -1;  // periods to run before pausing again (sim "step N"); -1: not stepping
  bool diverged_ = false;
  bool output_failed_ = false;  // a write failed: the periods stop, the files are kept
  long k_ = 0;
};

}  // namespace vlab::lab
