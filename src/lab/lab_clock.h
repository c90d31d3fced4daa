// The owner of time: when the lab may start the next control period.
//
// Only the clock differs between run modes. The lab's step loop is the same in
// every mode; it calls BeginPeriod(k) before period k and EndPeriod(k) after it.
//   fast      as fast as the CPU allows (in-process controllers)
//   lockstep  (bridge) wait for the commands that answer period k
//   realtime  (bridge) sleep until the wall-clock deadline of period k
#pragma once

#include <cstdint>
#include <memory>
#include <string>

namespace vlab::lab {

/// Statistics a clock keeps about its own pacing.
struct ClockStats {
  std::int64_t periods = 0;          ///< periods begun
  std::int64_t missed_deadlines = 0;  ///< periods started after their deadline (realtime)
  double max_lateness_s = 0.0;        ///< worst lateness of a period start (realtime)
};

class Clock {
 public:
  virtual ~Clock() = default;
  /// Mode name: "fast", "lockstep" or "realtime".
  virtual const char* name() const = 0;
  /// Blocks until period k (starting at simulated time sim_time_s) may begin.
  virtual void BeginPeriod(std::int64_t k, double sim_time_s) = 0;
  /// Called after period k has been simulated and published.
  virtual void EndPeriod(std::int64_t k) = 0;
  virtual ClockStats stats() const = 0;
};

/// Creates a clock by mode name; throws InputError for an unknown mode.
std::unique_ptr<Clock> MakeClock(const std::string& mode, double control_period_s);

}  // namespace vlab::lab
