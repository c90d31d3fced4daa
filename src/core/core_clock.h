// The owner of time: when the lab may start the next control period.
//
// Only the clock differs between run modes; the step loop is the same in all.
// Before period k the loop calls BeginPeriod(k); the clock returns when the
// period may start:
//   fast      at once (in-process controllers)
//   lockstep  when every controlled device has a command answering period k,
//             or when the wait times out (the run then holds or fails, as the
//             scenario says)
//   realtime  at the wall-clock deadline of period k (start + k T / factor);
//             commands arriving meanwhile are received as they come. The wall
//             clock starts when period 0 is answered (the controllers are
//             there), or after the lockstep start timeout
// While a clock waits, it lets the command source receive (Poll), so commands
// are timestamped when they arrive. With a stop flag (ClockConfig::stop) every
// wait is cut into slices of at most kStopCheck_s and ends once the flag is set.
#pragma once

#include <csignal>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/core_stall_probe.h"

namespace vlab {

/// The clock modes (the scenario's `clock` key, `--clock`).
enum class ClockMode { kFast, kLockstep, kRealtime };
/// "fast", "lockstep" or "realtime".
const char* ClockModeName(ClockMode mode);
/// The mode of a name; throws InputError "WHAT: unknown clock 'NAME' (known: ...)".
ClockMode ParseClockMode(const std::string& name, const std::string& what);

/// What a lockstep run does when a period's commands do not come in time.
enum class OnTimeout {
  kHold,  ///< the devices hold, the run goes on
  kFail,  ///< the run stops, exit 1
};

/// Lockstep clock: the lab waits for the commands that answer each period.
struct LockstepConfig {
  double timeout_s = 1.0;         ///< wait per period (wall time)
  double start_timeout_s = 30.0;  ///< wait for the first command (period 0)
  OnTimeout on_timeout = OnTimeout::kHold;
  int release_after = 3;  ///< consecutive timeouts after which the silent owner is released
};

/// Realtime clock: periods paced to the wall clock.
struct RealtimeConfig {
  double factor = 1.0;  ///< simulated seconds per wall second
  /// SCHED_FIFO priority of the lab's control thread in lockstep and realtime
  /// runs, when the user may have it (core_realtime.h); 0: normal priority.
  int priority = 0;
};

/// Simulated times closer than this, s, are one instant (a period's boundary, a frame or log time).
inline constexpr double kSameTime_s = 1e-9;

/// Longest a clock waits without looking at its stop flag, s.
inline constexpr double kStopCheck_s = 0.05;

/// Everything a clock is made from.
struct ClockConfig {
  ClockMode mode = ClockMode::kFast;
  double period_s = 0.002;  ///< control period, s
  LockstepConfig lockstep;
  RealtimeConfig realtime;  ///< (realtime also waits for period 0 up to lockstep.start_timeout_s)
  /// Non-zero (a signal's number, g_stop_requested of bridge_signals.h) ends every
  /// wait within kStopCheck_s: BeginPeriod returns kStopped. nullptr: never.
  const volatile std::sig_atomic_t* stop = nullptr;
};

/// How a wait for datagrams passes its time.
/// - kSpin: polls for a short while first, yielding the CPU between polls, then
///   sleeps. The lockstep wait: a controller's answer usually comes within tens of
///   microseconds, is taken without a thread wake-up, and a controller on the same
///   core runs at once.
/// - kSleep: sleeps at once, until a datagram or the timeout. The realtime wait: a
///   yield there hands the CPU to work below the control thread (camera workers at
///   nice 10) for a whole scheduler slice, and the deadline passes meanwhile (2 cameras
///   at 30 Hz beside the 1 kHz loop: 10 % of the deadlines missed, lateness p99 3.3 ms).
enum class PollWait { kSpin, kSleep };

/// What a clock waits on: the lab's bridge, or nothing (fast).
class CommandSource {
 public:
  virtual ~CommandSource() = default;
  /// Receives what arrives within timeout_s; returns early after a datagram.
  virtual void Poll(double timeout_s, PollWait wait) = 0;
  /// True when every controlled device has accepted a command answering period k.
  virtual bool Answered(std::int64_t k) const = 0;
};

/// Statistics a clock keeps about its own pacing.
struct ClockStats {
  std::int64_t periods = 0;           ///< periods begun
  std::int64_t missed_deadlines = 0;  ///< realtime: periods begun after their deadline
  double max_lateness_s = 0.0;        ///< realtime: worst start after a deadline
  std::vector<double> lateness_s;     ///< realtime: start - deadline of every period (jitter)
  std::int64_t timeouts = 0;          ///< lockstep: periods that began without their commands
  /// realtime: the control thread's counters and the machine's steal time over the
  /// run, and the worst period with what it waited on (core_stall_probe.h); the steal
  /// is counted up to the last read of /proc/stat (at most StallProbe::kStealEvery
  /// periods before the end)
  StallReport stall;
};

/// How a wait for a period ended: it may begin (with its commands, or without
/// them after a timeout), the run must fail (lockstep on_timeout: fail), or the
/// stop flag was set (the period does not begin).
enum class PeriodStart { kReady, kTimedOut, kFail, kStopped };

class Clock {
 public:
  virtual ~Clock() = default;
  virtual ClockMode mode() const = 0;
  /// Mode name: "fast", "lockstep" or "realtime".
  const char* name() const { return ClockModeName(mode()); }
  /// Blocks until period k may begin (see the file comment).
  virtual PeriodStart BeginPeriod(std::int64_t k, CommandSource* source) = 0;
  /// Simulated seconds per wall second (realtime); can change during a run.
  virtual void set_factor(double /*factor*/) {}
  virtual double factor() const { return 0.0; }
  virtual const ClockStats& stats() const = 0;
};

/// Creates a clock for a run of `periods` periods.
std::unique_ptr<Clock> MakeClock(const ClockConfig& config, std::int64_t periods);

/// Monotonic wall time, s.
double WallNow();

}  // namespace vlab
