#include "core/core_clock.h"

#include <sys/prctl.h>

#include <algorithm>
#include <chrono>
#include <thread>

#include "core/core_errors.h"

namespace vlab {

double WallNow() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

namespace {

// the stop flag of a clock's config: set once a stop was asked for
bool Stopped(const volatile std::sig_atomic_t* stop) { return stop && *stop != 0; }

// how long one poll of a wait may last: the time left, in slices when a stop flag is watched
// (a signal does not end the command source's wait: it retries on EINTR)
double Slice(double left_s, const volatile std::sig_atomic_t* stop) {
  return stop ? std::min(left_s, kStopCheck_s) : left_s;
}

// fast: never waits.
class FastClock final : public Clock {
 public:
  ClockMode mode() const override { return ClockMode::kFast; }
  PeriodStart BeginPeriod(std::int64_t, CommandSource*) override {
    ++stats_.periods;
    return PeriodStart::kReady;
  }
  const ClockStats& stats() const override { return stats_; }

 private:
  ClockStats stats_;
};

// lockstep: waits for the commands that answer period k.
class LockstepClock final : public Clock {
 public:
  LockstepClock(const LockstepConfig& c, const volatile std::sig_atomic_t* stop) : config_(c), stop_(stop) {}
  ClockMode mode() const override { return ClockMode::kLockstep; }

  PeriodStart BeginPeriod(std::int64_t k, CommandSource* source) override {
    ++stats_.periods;
    if (!source) return PeriodStart::kReady;
    const double limit = k == 0 ? config_.start_timeout_s : config_.timeout_s;
    const double deadline = WallNow() + limit;
    while (!source->Answered(k)) {
      if (Stopped(stop_)) return PeriodStart::kStopped;
      const double left = deadline - WallNow();
      if (left <= 0) {
        ++stats_.timeouts;
        return config_.on_timeout == OnTimeout::kFail ? PeriodStart::kFail : PeriodStart::kTimedOut;
      }
      source->Poll(Slice(left, stop_), PollWait::kSpin);
    }
    return PeriodStart::kReady;
  }
  const ClockStats& stats() const override { return stats_; }

 private:
  LockstepConfig config_;
  const volatile std::sig_atomic_t* stop_;
  ClockStats stats_;
};

// realtime: period k starts at anchor + (k - k_anchor) T / factor on the
// monotonic clock; the time until then is spent receiving commands.
class RealtimeClock final : public Clock {
 public:
  RealtimeClock(double period_s, double factor, double start_timeout_s, std::int64_t periods,
                const volatile std::sig_atomic_t* stop)
      : period_s_(period_s), factor_(factor), start_timeout_s_(start_timeout_s), stop_(stop) {
    // the kernel may otherwise wake a sleeping thread up to 50 us late (timer slack)
    prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
    stats_.lateness_s.reserve(static_cast<std::size_t>(std::max<std::int64_t>(periods, 0)) + 1);
  }
  ClockMode mode() const override { return ClockMode::kRealtime; }

  PeriodStart BeginPeriod(std::int64_t k, CommandSource* source) override {
    ++stats_.periods;
    if (k == 0 && source) {
      // the wall clock starts once the controllers are there (or after the start timeout)
      const double until = WallNow() + start_timeout_s_;
      while (!source->Answered(0) && WallNow() < until) {
        if (Stopped(stop_)) return PeriodStart::kStopped;
        source->Poll(Slice(until - WallNow(), stop_), PollWait::kSleep);
      }
    }
    if (!anchored_) {
      anchor_ = WallNow();
      anchor_k_ = k;
      anchored_ = true;
    }
    const double step = period_s_ / factor_;
    const double deadline = anchor_ + static_cast<double>(k - anchor_k_) * step;
    double now = WallNow();
    // begun after its own period had already ended: the previous one overran
    if (now > deadline + step) ++stats_.missed_deadlines;
    while (now < deadline) {
      if (Stopped(stop_)) return PeriodStart::kStopped;
      if (source) {
        source->Poll(Slice(deadline - now, stop_), PollWait::kSleep);
      } else {
        SleepUntil(std::min(deadline, now + Slice(deadline - now, stop_)));
      }
      now = WallNow();
    }
    const double lateness = now - deadline;
    stats_.max_lateness_s = std::max(stats_.max_lateness_s, lateness);
    if (stats_.lateness_s.size() < stats_.lateness_s.capacity()) stats_.lateness_s.push_back(lateness);
    // what the control thread waited on: a period counts as late a whole step after its deadline
    probe_.Sample(k, lateness, step, now);
    stats_.stall = probe_.report();
    return PeriodStart::kReady;
  }
  void set_factor(double factor) override {
    factor_ = factor;
    anchored_ = false;  // the new pace counts from the next period on, without a jump
  }
  double factor() const override { return factor_; }
  const ClockStats& stats() const override { return stats_; }

 private:
  static void SleepUntil(double wall_s) {
    const double left = wall_s - WallNow();
    if (left > 0) std::this_thread::sleep_for(std::chrono::duration<double>(left));
  }
  double period_s_;
  double factor_;
  double start_timeout_s_;
  const volatile std::sig_atomic_t* stop_;
  bool anchored_ = false;
  double anchor_ = 0;
  std::int64_t anchor_k_ = 0;
  StallProbe probe_;
  ClockStats stats_;
};

}  // namespace

std::unique_ptr<Clock> MakeClock(const ClockConfig& c, std::int64_t periods) {
  switch (c.mode) {
    case ClockMode::kFast:
      return std::make_unique<FastClock>();
    case ClockMode::kLockstep:
      return std::make_unique<LockstepClock>(c.lockstep, c.stop);
    case ClockMode::kRealtime:
      return std::make_unique<RealtimeClock>(c.period_s, c.realtime.factor, c.lockstep.start_timeout_s, periods,
                                             c.stop);
  }
  return nullptr;  // unreachable: every mode is handled above
}

const char* ClockModeName(ClockMode mode) {
  switch (mode) {
    case ClockMode::kFast:
      return "fast";
    case ClockMode::kLockstep:
      return "lockstep";
    case ClockMode::kRealtime:
      return "realtime";
  }
  return "?";
}

ClockMode ParseClockMode(const std::string& name, const std::string& what) {
  for (ClockMode m : {ClockMode::kFast, ClockMode::kLockstep, ClockMode::kRealtime}) {
    if (name == ClockModeName(m)) return m;
  }
  throw InputError(what + ": unknown clock '" + name + "' (known: fast, lockstep, realtime)");
}

}  // namespace vlab
