// What a late realtime period waited on (src/core/core_stall_probe.h): the
// parsers against /proc files written here with known numbers, the thread's
// counters against what the test makes the thread do (fresh pages touched,
// a blocking wait, a second thread spinning on the same CPU), and the cause
// line against records whose answer is known.
#include <fcntl.h>
#include <poll.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "core/core_clock.h"
#include "core/core_realtime.h"
#include "core/core_stall_probe.h"

namespace vlab {
namespace {

// a file holding `text`, opened for reading; removed when the test ends
class TextFile {
 public:
  explicit TextFile(const std::string& text) {
    char name[] = "/tmp/vlab_stall_probe_XXXXXX";
    fd_ = mkstemp(name);
    path_ = name;
    EXPECT_EQ(write(fd_, text.data(), text.size()), static_cast<ssize_t>(text.size()));
  }
  ~TextFile() {
    close(fd_);
    unlink(path_.c_str());
  }
  int fd() const { return fd_; }

 private:
  int fd_ = -1;
  std::string path_;
};

TEST(StallProbe, ReadsStealFromTheEighthValueOfProcStat) {
  // user nice system idle iowait irq softirq steal guest guest_nice, in USER_HZ ticks
  TextFile stat("cpu  10 20 30 40 50 60 70 800 0 0\ncpu0 5 10 15 20 25 30 35 400 0 0\n");
  EXPECT_DOUBLE_EQ(ReadStealSeconds(stat.fd()), 800.0 / static_cast<double>(sysconf(_SC_CLK_TCK)));
  TextFile short_line("cpu  10 20 30\n");
  EXPECT_EQ(ReadStealSeconds(short_line.fd()), -1);
  EXPECT_EQ(ReadStealSeconds(-1), -1);
}

TEST(StallProbe, ReadsRunDelayFromSchedstat) {
  // cpu time ns, run delay ns, timeslices
  TextFile schedstat("123456 456789000 7\n");
  EXPECT_DOUBLE_EQ(ReadThreadCounters(schedstat.fd()).run_delay_s, 0.456789);
  EXPECT_EQ(ReadThreadCounters(-1).run_delay_s, -1);
}

TEST(StallProbe, CountsTheThreadsPageFaultsAndWaits) {
  const int schedstat = open("/proc/thread-self/schedstat", O_RDONLY | O_CLOEXEC);
  const ThreadCounters before = ReadThreadCounters(schedstat);
  // 1024 fresh pages, one fault each (no huge pages for this mapping)
  const long page = sysconf(_SC_PAGESIZE);
  const std::size_t pages = 1024;
  char* memory =
      static_cast<char*>(mmap(nullptr, pages * page, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0));
  ASSERT_NE(memory, MAP_FAILED);
  madvise(memory, pages * page, MADV_NOHUGEPAGE);
  for (std::size_t i = 0; i < pages; ++i) memory[i * page] = 1;
  // a wait that must block: poll on a pipe nobody writes
  int fds[2];
  ASSERT_EQ(pipe(fds), 0);
  pollfd p{fds[0], POLLIN, 0};
  EXPECT_EQ(poll(&p, 1, 2), 0);
  const ThreadCounters after = ReadThreadCounters(schedstat);
  EXPECT_GE(after.minor_faults - before.minor_faults, static_cast<long>(pages));
  EXPECT_GE(after.voluntary_switches - before.voluntary_switches, 1);
  munmap(memory, pages * page);
  close(fds[0]);
  close(fds[1]);
  close(schedstat);
}

TEST(StallProbe, SeesTheRunDelayOfASharedCpu) {
  const int schedstat = open("/proc/thread-self/schedstat", O_RDONLY | O_CLOEXEC);
  if (ReadThreadCounters(schedstat).run_delay_s < 0) {
    close(schedstat);
    GTEST_SKIP() << "this kernel gives no schedstat";
  }
  // this thread and a spinning one on the same CPU: each waits while the other runs
  const std::vector<int> allowed = ThreadCpus();
  ASSERT_FALSE(allowed.empty());
  ASSERT_TRUE(BindThread(0, {allowed.front()}));
  std::atomic<bool> stop{false};
  std::thread rival([&] {
    BindThread(0, {allowed.front()});
    while (!stop.load(std::memory_order_relaxed)) {
    }
  });
  const ThreadCounters before = ReadThreadCounters(schedstat);
  // spin until the kernel has taken the CPU away a few times (each slice is a few ms)
  ThreadCounters now = before;
  while (now.involuntary_switches - before.involuntary_switches < 5) now = ReadThreadCounters(schedstat);
  stop = true;
  rival.join();
  BindThread(0, allowed);
  EXPECT_GT(now.run_delay_s - before.run_delay_s, 0.0);
  close(schedstat);
}

TEST(StallProbe, NamesTheLargestCause) {
  StallRecord r;
  EXPECT_EQ(r.Cause(), "no period sampled");
  r.period = 7;
  r.lateness_s = 0.012;
  r.run_delay_s = 0.0005;
  r.steal_s = 0.010;
  r.steal_window_s = 0.1;
  EXPECT_NE(r.Cause().find("steal 10.0 ms"), std::string::npos) << r.Cause();
  r.steal_s = 0.001;
  r.run_delay_s = 0.009;
  r.involuntary_switches = 3;
  EXPECT_NE(r.Cause().find("waited 9.0 ms for a CPU (3 involuntary"), std::string::npos) << r.Cause();
  r.involuntary_switches = 0;  // woken, then kept off the CPU
  EXPECT_NE(r.Cause().find("waited 9.0 ms for a CPU after its wake-up"), std::string::npos) << r.Cause();
  r.involuntary_switches = 3;
  r.run_delay_s = 0.001;
  r.voluntary_switches = 4;
  EXPECT_NE(r.Cause().find("not explained by a CPU wait or steal; on-CPU time unknown"), std::string::npos)
      << r.Cause();
  // neither: 12 ms late in a 22 ms window; the deadline fell 10 ms into it
  r.window_s = 0.022;
  r.on_cpu_s = 0.003;  // ran 3 ms, waited 1: asleep at the deadline
  EXPECT_NE(r.Cause().find("a late wake-up: it slept past its deadline (ran 3.0 ms of the 22.0 ms window"),
            std::string::npos)
      << r.Cause();
  r.on_cpu_s = 0.0095;  // ran 9.5 ms and waited 1: still at work at the deadline
  EXPECT_NE(r.Cause().find("busy in the lab: it ran 9.5 ms of the 22.0 ms window (4 voluntary waits"),
            std::string::npos)
      << r.Cause();
  r.on_cpu_s = 0.0008;  // ran 0.8 ms, waited 1, never slept: 20.2 ms in none of them
  r.voluntary_switches = 0;
  EXPECT_NE(r.Cause().find("its CPU was taken without a switch: it ran 0.8 ms of the 22.0 ms window, never waited "
                           "for a CPU nor slept, and lost 20.2 ms"),
            std::string::npos)
      << r.Cause();
  r.on_cpu_s = 0.0195;  // ran 19.5 of 22 without a wait: busy
  EXPECT_NE(r.Cause().find("busy in the lab: it ran 19.5 ms"), std::string::npos) << r.Cause();
  r.run_delay_s = -1;  // (a kernel without schedstat: every line says so)
  EXPECT_NE(r.Cause().find("0 minor page faults; run delay unknown)"), std::string::npos) << r.Cause();
  r.run_delay_s = 0.001;
  r.voluntary_switches = 4;
  r.major_faults = 2;
  EXPECT_NE(r.Cause().find("2 major page faults"), std::string::npos) << r.Cause();
}

TEST(StallProbe, KeepsTheLatestPeriodWithItsCounters) {
  StallProbe probe;
  probe.Sample(0, 0.0, 0.001, 10.0);
  probe.Sample(1, 0.0002, 0.001, 10.001);
  // period 2 starts 5 ms late after 256 fresh pages were touched
  const long page = sysconf(_SC_PAGESIZE);
  char* memory =
      static_cast<char*>(mmap(nullptr, 256 * page, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0));
  ASSERT_NE(memory, MAP_FAILED);
  madvise(memory, 256 * page, MADV_NOHUGEPAGE);
  for (int i = 0; i < 256; ++i) memory[i * page] = 1;
  probe.Sample(2, 0.005, 0.001, 10.007);
  probe.Sample(3, 0.0001, 0.001, 10.008);
  munmap(memory, 256 * page);
  const StallReport& r = probe.report();
  EXPECT_EQ(r.worst.period, 2);
  EXPECT_DOUBLE_EQ(r.worst.lateness_s, 0.005);
  EXPECT_GE(r.worst.minor_faults, 256);
  EXPECT_GE(r.minor_faults, 256);
  EXPECT_NEAR(r.wall_s, 0.008, 1e-12);          // first sample to last
  EXPECT_NEAR(r.worst.window_s, 0.006, 1e-12);  // period 1's start to period 2's
  EXPECT_GT(r.worst.on_cpu_s, 0.0);             // (touching 256 pages took CPU time)
  // a late period reads the steal at once: known wherever /proc/stat is
  const int stat = open("/proc/stat", O_RDONLY | O_CLOEXEC);
  if (ReadStealSeconds(stat) >= 0) {
    EXPECT_GE(r.worst.steal_s, 0.0);
    EXPECT_NEAR(r.worst.steal_window_s, 0.007, 1e-12);  // since the read at the first sample
  }
  if (stat >= 0) close(stat);
}

TEST(StallProbe, TheRealtimeClockReportsItsWorstPeriod) {
  auto clock = MakeClock(ClockConfig{ClockMode::kRealtime, 0.001, {}, {}, nullptr}, 20);
  for (int k = 0; k < 20; ++k) ASSERT_EQ(clock->BeginPeriod(k, nullptr), PeriodStart::kReady);
  const ClockStats& s = clock->stats();
  EXPECT_GE(s.stall.worst.period, 1);  // period 0 starts the probe
  ASSERT_EQ(s.lateness_s.size(), 20u);
  double worst = s.lateness_s[1];
  for (std::size_t k = 1; k < s.lateness_s.size(); ++k) worst = std::max(worst, s.lateness_s[k]);
  EXPECT_DOUBLE_EQ(s.stall.worst.lateness_s, worst);
  EXPECT_DOUBLE_EQ(s.stall.worst.lateness_s, s.lateness_s[s.stall.worst.period]);
  EXPECT_GT(s.stall.wall_s, 0.0);
}

}  // namespace
}  // namespace vlab
