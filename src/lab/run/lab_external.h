// External controllers that `vlab run` starts itself (scenario controller type
// `external`): a separate program that talks to the lab's devices over UDP,
// exactly as it would under `vlab serve` or against real hardware.
//
// Ports
//   input   the program's command line, with placeholders expanded, and its
//           environment (lab_command.h): {DEVICE} -> ADDRESS:PORT of a served
//           device, {port:NAME} -> a device's port or a free port for a
//           program it starts, {bin} -> the folder of the running vlab
//           executable, {scenario_dir} -> the folder of the scenario file,
//           {duration} -> the run's duration in seconds, {out} -> the run's
//           output folder (files written there move into place with log.csv:
//           the program is stopped before that)
//   output  the program's stdout and stderr, into a log file
//   exit    exit_fd() becomes readable (end of file) once the program and
//           every process it started have closed their copy of it: the lab
//           waits on it together with its sockets, so a controller that dies
//           does not leave the lockstep clock waiting
// The program gets only descriptors 0 (/dev/null), 1 and 2 (the log) and 3
// (its end of the exit pipe); every other descriptor of the lab (the served
// devices' sockets, log.csv, images, a video) is closed before exec.
// The program runs in its own process group, which Stop() ends (SIGTERM,
// then SIGKILL after a grace period); it also gets SIGTERM if vlab dies.
// Threading: one thread. Errors: Start() throws InputError naming the program
// when it cannot be executed.
#pragma once

#include <sys/types.h>

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/core_realtime.h"
#include "lab/run/lab_bridge.h"
#include "lab/run/lab_command.h"
#include "lab/scenario/lab_scenario.h"

namespace vlab::lab {

/// True when a run of `scenario` starts its own external controller: the
/// scenario names one and the run serves nothing by itself (not `vlab serve`).
bool StartsExternalController(const Scenario& scenario, bool serving);
/// How such a run serves its devices: every device with a port (or `port:
/// auto`), on a free port of the loopback address.
BridgeOptions ExternalBridgeOptions(const Scenario& scenario);
/// Its clock: the one asked for, else the scenario's; `fast` becomes
/// `lockstep` (an external controller is never in process).
ClockMode ExternalClock(const Scenario& scenario, std::optional<ClockMode> requested);

class ExternalController {
 public:
  /// Starts argv[0] (searched on PATH when it has no slash) with stdin from
  /// /dev/null and stdout and stderr appended to log_path ("": a temporary
  /// file, removed with this object). Throws InputError
  /// when the program cannot be executed (missing, not executable).
  /// realtime_priority > 0: the program (and every process it starts) runs
  /// SCHED_FIFO at that priority when the user may have it (core_realtime.h);
  /// refused, it runs at normal priority and realtime() says why.
  /// environment: "NAME=VALUE" entries added to (or replacing in) vlab's own.
  static std::unique_ptr<ExternalController> Start(const std::vector<std::string>& argv, const std::string& log_path,
                                                   int realtime_priority = 0,
                                                   const std::vector<std::string>& environment = {});
  ~ExternalController();
  ExternalController(const ExternalController&) = delete;
  ExternalController& operator=(const ExternalController&) = delete;

  /// Readable (end of file) once the program has exited; for poll/select.
  int exit_fd() const { return exit_fd_; }
  /// True once the program has exited (never blocks).
  bool Exited();
  /// Exited(), waiting at most timeout_s for it (a program whose exit closed
  /// exit_fd() is reaped a moment later).
  bool WaitExited(double timeout_s);
  /// Ends the program if it still runs: SIGTERM to its process group, then
  /// SIGKILL after grace_s. Returns once it has been reaped.
  void Stop(double grace_s);
  /// True when the program exited with status 0 (on its own, or after the
  /// SIGTERM of Stop()), or was killed by the signals of Stop().
  bool Succeeded() const;
  /// "exit status N" or "killed by signal N" (after Exited() or Stop()).
  std::string Outcome() const;
  /// The last non-empty line the program wrote (for error messages).
  std::string LastLogLine() const;
  const std::string& program() const { return program_; }
  /// What the realtime_priority of Start() got, read off the program after its exec.
  const RealtimeGrant& realtime() const { return realtime_; }

 private:
  ExternalController() = default;
  pid_t pid_ = -1;
  int exit_fd_ = -1;
  int status_ = 0;
  bool reaped_ = false;
  bool stopped_ = false;  // ended by Stop() rather than by itself
  std::string program_;
  RealtimeGrant realtime_;
  std::string log_path_;
  bool log_is_temporary_ = false;
};

}  // namespace vlab::lab
