// The vlab command line: one function per subcommand, called by main().
// Each returns the process exit code: 0 success, 1 a check failed, the run
// diverged or was interrupted (SIGINT, SIGTERM), 2 bad input.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace vlab::lab {
struct Scenario;
struct RunResult;
struct Sweep;
}  // namespace vlab::lab

namespace vlab::cli {

struct RunArgs {
  std::string scenario;
  std::string out_dir;  ///< "" = out/<scenario name>
  bool quiet = false;
  bool list_signals = false;
  double duration_s = 0;          ///< > 0 overrides the scenario's duration
  long long seed = -1;            ///< >= 0 overrides the scenario's seed
  int rt_priority = -1;           ///< >= 0 overrides the scenario's realtime.priority
  std::vector<std::string> sets;  ///< --set KEY=VALUE scenario overrides, in order
  std::string overrides_file;     ///< --overrides FILE: KEY=VALUE lines applied before the --set ones
};
int RunCommand(const RunArgs& args);

struct ServeArgs {
  std::string scenario;
  std::string bind = "127.0.0.1";
  std::vector<std::string> ports;  ///< DEVICE=PORT overrides
  std::string ports_mode;          ///< "auto": every served device on a free port
  std::string clock;               ///< "" = the scenario's
  std::string out_dir;
  double duration_s = 0;
  bool json = false;         ///< devices: print the describe JSON too
  bool quiet = false;        ///< serve: no per-device counter lines
  int rt_priority = -1;      ///< >= 0 overrides the scenario's realtime.priority
  int max_subscribers = 16;  ///< serve: subscribers each device endpoint keeps
};
int ServeCommand(const ServeArgs& args);
int DevicesCommand(const ServeArgs& args);

struct BenchArgs {
  std::string what;               ///< "physics"
  std::string scenario;           ///< scenario whose scene and devices are measured
  double duration_s = 0;          ///< simulated seconds per measurement (0: scenario's)
  int repeat = 3;                 ///< measurements per variant; the best is reported
  double realtime_s = 30;         ///< bridge: length of the realtime run, s
  int iterations = 0;             ///< identify: the fit's most Ceres iterations (0: the spec's default)
  std::vector<std::string> sets;  ///< physics: --set KEY=VALUE scenario overrides, in order
};
int BenchCommand(const BenchArgs& args);
/// The median of `v` (0 when empty): a benchmark's figure of several measurements.
double Median(std::vector<double> v);
int BenchBridge(const BenchArgs& args);
int BenchRender(const BenchArgs& args);
int BenchRealtime(const BenchArgs& args);  // cli_bench_realtime.cc
int BenchTask(const BenchArgs& args);      // cli_bench_task.cc
int BenchSweep(const BenchArgs& args);     // cli_bench_sweep.cc
int BenchView(const BenchArgs& args);      // cli_bench_view.cc
int BenchLog(const BenchArgs& args);       // cli_bench_log.cc
int BenchIdentify(const BenchArgs& args);  // cli_bench_identify.cc

/// A subcommand defined wholly in its own file: Add*Command adds it (name,
/// help, options) to `app` and returns the function that runs it once parsed.
/// The function validates its options itself (a bad value: one line, exit 2).
struct Subcommand {
  CLI::App* app = nullptr;
  std::function<int()> run;
};
Subcommand AddRenderCommand(CLI::App& app);    // cli_render.cc
Subcommand AddCameraCommand(CLI::App& app);    // cli_camera.cc
Subcommand AddVisionCommand(CLI::App& app);    // cli_vision.cc
Subcommand AddCubesCommand(CLI::App& app);     // cli_cubes.cc
Subcommand AddTaskCommand(CLI::App& app);      // cli_task.cc
Subcommand AddCompareCommand(CLI::App& app);   // cli_compare.cc
Subcommand AddGoldenCommand(CLI::App& app);    // cli_compare.cc
Subcommand AddSweepCommand(CLI::App& app);     // cli_sweep.cc
Subcommand AddCollectCommand(CLI::App& app);   // cli_collect.cc
Subcommand AddViewCommand(CLI::App& app);      // cli_view.cc
Subcommand AddExportCommand(CLI::App& app);    // cli_view.cc
Subcommand AddFollowCommand(CLI::App& app);    // cli_follow.cc
Subcommand AddConvertCommand(CLI::App& app);   // cli_convert.cc
Subcommand AddRecordCommand(CLI::App& app);    // cli_record.cc
Subcommand AddExciteCommand(CLI::App& app);    // cli_excite.cc
Subcommand AddIdentifyCommand(CLI::App& app);  // cli_identify.cc

/// Runs a sweep's runs here, `jobs` at a time, into out/ID, skipping complete runs
/// (cli_sweep.cc); quiet: no lines printed. Returns 0 when every run passed.
int RunSweepHere(const lab::Sweep& sweep, const std::string& out, int jobs, bool quiet);

/// Prints one line about realtime priority (RunOptions::on_realtime) on stderr.
void PrintRealtime(const std::string& line);
/// Runs a command body; an InputError prints one line and gives exit code 2,
/// any other exception one line and exit code 1.
int WithErrorReport(const std::function<int()>& body);

/// A run's verdict for its result line: "pass", "FAIL" or "INTERRUPTED".
const char* Verdict(const lab::RunResult& result);

/// After a run into out_dir: "plot: PATH" for each plot written, "plot skipped: why"
/// for each one the run skipped (stdout).
void PrintPlots(const lab::Scenario& scenario, const std::string& out_dir, const lab::RunResult& result);

/// Progress bar on stderr, drawn only on a terminal and only once a run has
/// lasted about a second.
class ProgressBar {
 public:
  explicit ProgressBar(bool enabled);
  void Update(double fraction);
  void Finish();

 private:
  bool enabled_;
  bool drawn_ = false;
  double start_s_;
};

}  // namespace vlab::cli
