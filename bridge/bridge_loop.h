// A fixed-rate loop for controllers: absolute deadlines on CLOCK_MONOTONIC.
#pragma once

#include <cstdint>

namespace vlab::bridge {

/// Paces a loop at a fixed rate on CLOCK_MONOTONIC: deadline k is start +
/// k * period, computed from k (never accumulated), so the loop never drifts.
/// A Wait() that finds its deadline already past counts an overrun and moves
/// on to the next deadline still ahead (the missed ones are skipped, the
/// phase kept).
class FixedRateLoop {
 public:
  /// Starts the clock now. Throws std::invalid_argument unless 0 < rate_hz <= 1e6.
  explicit FixedRateLoop(double rate_hz);
  /// Sleeps (clock_nanosleep, absolute) until the next deadline. Returns false
  /// when the deadline had already passed (an overrun; no sleep).
  bool Wait();
  /// Restarts the clock now: deadline 1 is one period from now.
  void Reset();

  double period_s() const { return static_cast<double>(period_ns_) * 1e-9; }
  long overruns() const { return overruns_; }
  /// Wait() calls so far.
  long iterations() const { return iterations_; }

 private:
  std::int64_t Deadline(std::int64_t k) const;
  double rate_hz_;
  std::int64_t period_ns_;
  std::int64_t start_ns_ = 0;
  std::int64_t k_ = 0;
  long overruns_ = 0;
  long iterations_ = 0;
};

}  // namespace vlab::bridge
