// A clock's waits end when its stop flag is set (src/core/core_clock.h): the
// lockstep wait for period 0 (start timeout 600 s), the realtime wait for the
// controllers and for a far deadline. The command source here ignores signals
// as the bridge's does (its wait resumes after EINTR), so only the clock's own
// slices can end the wait. Without a flag, waits end as before.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <thread>

#include "core/core_clock.h"

namespace vlab {
namespace {

// never answers; each Poll sleeps its whole timeout, like a wait nobody wakes
class SilentSource final : public CommandSource {
 public:
  void Poll(double timeout_s, PollWait) override {
    ++polls;
    std::this_thread::sleep_for(std::chrono::duration<double>(timeout_s));
  }
  bool Answered(std::int64_t) const override { return false; }
  std::atomic<int> polls{0};
};

// BeginPeriod(k) with the stop flag set from another thread after 100 ms; the wall time it took
double StoppedAfter(Clock& clock, std::int64_t k, CommandSource* source, volatile std::sig_atomic_t* stop,
                    PeriodStart* result) {
  std::thread signal([stop] {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    *stop = 2;  // SIGINT
  });
  const double t0 = WallNow();
  *result = clock.BeginPeriod(k, source);
  const double took = WallNow() - t0;
  signal.join();
  return took;
}

ClockConfig Config(ClockMode mode, volatile std::sig_atomic_t* stop) {
  ClockConfig c;
  c.mode = mode;
  c.period_s = 0.002;
  c.lockstep.start_timeout_s = 600;
  c.lockstep.timeout_s = 600;
  c.stop = stop;
  return c;
}

TEST(ClockStop, EndsTheLockstepWaitForPeriodZero) {
  volatile std::sig_atomic_t stop = 0;
  std::unique_ptr<Clock> clock = MakeClock(Config(ClockMode::kLockstep, &stop), 10);
  SilentSource source;
  PeriodStart result = PeriodStart::kReady;
  const double took = StoppedAfter(*clock, 0, &source, &stop, &result);
  EXPECT_EQ(result, PeriodStart::kStopped);
  EXPECT_LT(took, 60.0);  // the start timeout is 600 s; the flag is looked at every kStopCheck_s
  EXPECT_GE(source.polls.load(), 2) << "the wait is sliced";
  EXPECT_EQ(clock->stats().timeouts, 0);  // not a timeout
}

TEST(ClockStop, EndsTheLockstepWaitOfALaterPeriod) {
  volatile std::sig_atomic_t stop = 0;
  std::unique_ptr<Clock> clock = MakeClock(Config(ClockMode::kLockstep, &stop), 10);
  SilentSource source;
  PeriodStart result = PeriodStart::kReady;
  StoppedAfter(*clock, 5, &source, &stop, &result);
  EXPECT_EQ(result, PeriodStart::kStopped);
}

TEST(ClockStop, EndsTheRealtimeWaits) {
  // for the controllers at period 0 (start timeout 600 s)
  volatile std::sig_atomic_t stop = 0;
  std::unique_ptr<Clock> clock = MakeClock(Config(ClockMode::kRealtime, &stop), 10);
  SilentSource source;
  PeriodStart result = PeriodStart::kReady;
  StoppedAfter(*clock, 0, &source, &stop, &result);
  EXPECT_EQ(result, PeriodStart::kStopped);

  // for a deadline 2000 s away (period 1 at a factor of 1e-6), with and without a source
  for (CommandSource* s : {static_cast<CommandSource*>(&source), static_cast<CommandSource*>(nullptr)}) {
    volatile std::sig_atomic_t stop2 = 0;
    ClockConfig c = Config(ClockMode::kRealtime, &stop2);
    c.realtime.factor = 1e-6;
    c.lockstep.start_timeout_s = 0;
    std::unique_ptr<Clock> slow = MakeClock(c, 10);
    ASSERT_EQ(slow->BeginPeriod(0, s), PeriodStart::kReady);
    StoppedAfter(*slow, 1, s, &stop2, &result);
    EXPECT_EQ(result, PeriodStart::kStopped) << (s ? "with a source" : "without");
  }
}

TEST(ClockStop, WithoutAFlagTheWaitsAreAsBefore) {
  ClockConfig c = Config(ClockMode::kLockstep, nullptr);
  c.lockstep.start_timeout_s = 0.2;
  std::unique_ptr<Clock> clock = MakeClock(c, 10);
  SilentSource source;
  EXPECT_EQ(clock->BeginPeriod(0, &source), PeriodStart::kTimedOut);
  EXPECT_EQ(source.polls.load(), 1) << "one poll for the whole wait";
  c.lockstep.on_timeout = OnTimeout::kFail;
  c.lockstep.timeout_s = 0.05;
  EXPECT_EQ(MakeClock(c, 10)->BeginPeriod(3, &source), PeriodStart::kFail);
  EXPECT_EQ(MakeClock(Config(ClockMode::kFast, nullptr), 10)->BeginPeriod(0, &source), PeriodStart::kReady);
}

// how each clock waits (core_clock.h, PollWait): lockstep spins before it sleeps (an
// answer comes within microseconds), realtime sleeps at once (a yield would hand the
// CPU to the camera workers below it for a whole scheduler slice)
class RecordingSource final : public CommandSource {
 public:
  void Poll(double timeout_s, PollWait wait) override {
    (wait == PollWait::kSpin ? spins : sleeps) += 1;
    std::this_thread::sleep_for(std::chrono::duration<double>(std::min(timeout_s, 0.0005)));
    if (spins + sleeps >= 3) answered = true;  // period 0 answered after three polls
  }
  bool Answered(std::int64_t) const override { return answered; }
  int spins = 0, sleeps = 0;
  bool answered = false;
};

TEST(ClockWait, LockstepSpinsAndRealtimeSleeps) {
  RecordingSource lockstep_source;
  std::unique_ptr<Clock> lockstep = MakeClock(Config(ClockMode::kLockstep, nullptr), 10);
  ASSERT_EQ(lockstep->BeginPeriod(0, &lockstep_source), PeriodStart::kReady);
  EXPECT_EQ(lockstep_source.spins, 3);
  EXPECT_EQ(lockstep_source.sleeps, 0);

  RecordingSource realtime_source;
  std::unique_ptr<Clock> realtime = MakeClock(Config(ClockMode::kRealtime, nullptr), 10);
  ASSERT_EQ(realtime->BeginPeriod(0, &realtime_source), PeriodStart::kReady);  // waits for the controllers
  ASSERT_EQ(realtime->BeginPeriod(1, &realtime_source), PeriodStart::kReady);  // waits for its deadline
  EXPECT_EQ(realtime_source.spins, 0);
  EXPECT_GE(realtime_source.sleeps, 4) << "three polls for period 0, at least one until period 1's deadline";
}

}  // namespace
}  // namespace vlab
