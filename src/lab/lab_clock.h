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
// are timestamped when they arrive.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "lab/lab_scenario.h"

namespace vlab::lab {

/// What a clock waits on: the lab's bridge, or nothing (fast).
class CommandSource {
 public:
  virtual ~CommandSource() = default;
  /// Receives what arrives within timeout_s; returns early after a datagram.
  virtual void Poll(double timeout_s) = 0;
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
};

enum class PeriodStart { kReady, kTimedOut, kFail };

class Clock {
 public:
  virtual ~Clock() = default;
  /// Mode name: "fast", "lockstep" or "realtime".
  virtual const char* name() const = 0;
  /// Blocks until period k may begin (see the file comment).
  virtual PeriodStart BeginPeriod(std::int64_t k, CommandSource* source) = 0;
  /// Simulated seconds per wall second (realtime); can change during a run.
  virtual void set_factor(double /*factor*/) {}
  virtual double factor() const { return 0.0; }
  virtual const ClockStats& stats() const = 0;
};

/// Creates the scenario's clock (`mode` overrides scenario.clock when not
/// empty); throws InputError for an unknown mode.
std::unique_ptr<Clock> MakeClock(const Scenario& scenario, const std::string& mode, std::int64_t periods);

/// Monotonic wall time, s.
double WallNow();

}  // namespace vlab::lab
