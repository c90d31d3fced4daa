// SIGINT and SIGTERM as a stop request for a program's loop: the one stop handler of every
// vlab program: the lab's commands (vlab run, serve, render, compare, sweep, task, camera,
// vision, view and follow; vlab-kinsim, vlab-yoyosim) and the controller programs beside the
// lab (bridge_program.h). The handler only records which signal came, and the loop reads
// it. Header only, and in the bridge because the bridge is the one library every program
// links.
#pragma once

#include <pthread.h>
#include <signal.h>

#include <csignal>
#include <string>

namespace vlab {

/// The number of the first SIGINT or SIGTERM since InstallStopSignals() ran (0:
/// none yet). Later signals leave it as it is: the first one says why a run stopped,
/// and a second one while the program finishes its files changes nothing.
inline volatile std::sig_atomic_t g_stop_requested = 0;

/// SIGINT and SIGTERM set g_stop_requested (once). Without SA_RESTART: a blocking
/// call that the kernel does not restart (a sleep, poll) returns EINTR; loops that
/// retry on EINTR must read g_stop_requested themselves, so waits are sliced
/// (the clocks of core_clock.h look at it at least every kStopCheck_s).
/// Installed whatever the program inherited: SIG_IGN (bash gives it to a
/// script's `&` jobs for SIGINT) is replaced, and both signals are unblocked in
/// the calling thread, so one that came while they were blocked is taken now.
/// StopRequested() reads it.
/// Call it first thing, before loading, from the main thread before any other
/// thread starts (threads inherit the mask): a signal during loading then stops
/// the run before its first period instead of being lost.
inline void InstallStopSignals() {
  struct sigaction action {};
  // the first signal stays: a compare-and-swap, since two threads may each run the handler
  // at once (SIGINT on one, SIGTERM on another: sa_mask below blocks a second signal only in
  // the thread that runs the first handler), and a plain test-and-set let the later one win
  action.sa_handler = [](int signal_number) {
    __sync_bool_compare_and_swap(&g_stop_requested, 0, signal_number);  // (lock-free: signal-safe)
  };
  // one handler at a time in a thread
  sigemptyset(&action.sa_mask);
  sigaddset(&action.sa_mask, SIGINT);
  sigaddset(&action.sa_mask, SIGTERM);
  action.sa_flags = 0;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_UNBLOCK, &stop_signals, nullptr);
}

/// True once SIGINT or SIGTERM came (after InstallStopSignals()).
inline bool StopRequested() { return g_stop_requested != 0; }

/// A loop's stop request: the flag a signal handler sets (g_stop_requested above,
/// or another), or none.
class StopCheck {
 public:
  /// `flag` null: never stops.
  explicit StopCheck(const volatile std::sig_atomic_t* flag = nullptr) : flag_(flag) {}
  /// True once the flag is non-zero.
  bool operator()() const { return flag_ != nullptr && *flag_ != 0; }

 private:
  const volatile std::sig_atomic_t* flag_;
};

/// "SIGINT", "SIGTERM", or "signal N".
inline std::string StopSignalName(int signal_number) {
  if (signal_number == SIGINT) return "SIGINT";
  if (signal_number == SIGTERM) return "SIGTERM";
  return "signal " + std::to_string(signal_number);
}

}  // namespace vlab
