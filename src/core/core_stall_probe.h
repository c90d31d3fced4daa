// Whose fault a late period was: the control thread's own counters, sampled at
// the start of every realtime period, and the machine's steal time.
//
// A realtime period can start late for reasons the lab causes (a page fault, a
// lock or a system call that blocked the control thread) and for reasons it
// cannot prevent (another thread or process on its CPU, the hypervisor running
// another guest: steal time). The kernel counts each of them per thread or per
// machine; the probe reads them where the period starts and keeps the deltas of
// the worst period, so a failed realtime run says what its longest stall waited on.
//
// Sources, all read without allocation on the period path:
//   getrusage(RUSAGE_THREAD)     voluntary and involuntary context switches, minor
//                                and major page faults of the control thread
//   /proc/thread-self/schedstat  time the thread spent runnable but waiting for a
//                                CPU (run delay), ns; needs schedstats in the kernel
//                                (present since Linux 2.6; -1 where unreadable)
//   CLOCK_THREAD_CPUTIME_ID      the thread's time on a CPU
//   /proc/stat, first line       the machine's steal time (8th value, USER_HZ ticks),
//                                read every kStealEvery periods and after a late one
// Threading: one probe per control thread; Sample is called only from that thread.
#pragma once

#include <cstdint>
#include <string>

namespace vlab {

/// Counters of the calling thread (getrusage, schedstat).
struct ThreadCounters {
  long voluntary_switches = 0;    ///< the thread gave the CPU up (sleep, lock, I/O)
  long involuntary_switches = 0;  ///< the kernel took the CPU away (preempted)
  long minor_faults = 0;          ///< page faults served without I/O
  long major_faults = 0;          ///< page faults that waited for I/O
  double run_delay_s = -1;        ///< total time runnable but not running, s; -1: unknown
  double on_cpu_s = -1;           ///< total time running on a CPU, s; -1: unknown
};

/// Reads the calling thread's counters; `schedstat_fd` is an open
/// /proc/thread-self/schedstat (-1: run delay unknown).
ThreadCounters ReadThreadCounters(int schedstat_fd);

/// The machine's steal time since boot, s (all CPUs added); -1 where /proc/stat
/// cannot be read. `stat_fd` is an open /proc/stat.
double ReadStealSeconds(int stat_fd);

/// The worst period of a run and what the kernel counted across it (from the
/// start of the period before it to its own start).
struct StallRecord {
  std::int64_t period = -1;  ///< -1: no period was sampled
  double lateness_s = 0;     ///< start - deadline
  long voluntary_switches = 0;
  long involuntary_switches = 0;
  long minor_faults = 0;
  long major_faults = 0;
  double run_delay_s = -1;    ///< -1: unknown
  double on_cpu_s = -1;       ///< the control thread's time on a CPU across the window; -1: unknown
  double window_s = 0;        ///< the window's wall time (the previous period's start to this one's), s
  double steal_s = -1;        ///< the machine's steal (all CPUs) in the window that holds the stall; -1: unknown
  double steal_window_s = 0;  ///< that window's wall time (since the read of /proc/stat before it), s
  /// One line: the largest of the causes the counters show, e.g.
  /// "waited 4.1 ms for a CPU (3 involuntary switches)" (or "... after its
  /// wake-up" where it was never preempted), "steal 9.8 ms (the
  /// hypervisor ran another guest)", "2 major page faults"; when none of those
  /// explains it, by the thread's time on a CPU: "its CPU was taken without a
  /// switch" when, never waiting, it lost time it neither ran nor waited for a
  /// CPU (its vCPU stopped, or interrupts ran), "busy in the lab" when it ran or
  /// waited for a CPU past its deadline, else "a late wake-up" (it slept past
  /// its deadline: a CPU leaving deep idle, a timer or interrupt delivered late),
  /// or "not explained" where the kernel gives no on-CPU time.
  std::string Cause() const;
};

/// What the probe found over a run.
struct StallReport {
  double steal_s = -1;          ///< the machine's steal time over the run, s (all CPUs); -1: unknown
  double wall_s = 0;            ///< the run's wall time from the first sample to the last, s
  long voluntary_switches = 0;  ///< of the control thread over the run
  long involuntary_switches = 0;
  long minor_faults = 0;
  long major_faults = 0;
  double run_delay_s = -1;  ///< of the control thread over the run; -1: unknown
  StallRecord worst;        ///< the latest-starting period
};

/// Samples the control thread at the start of every period (see the file comment).
class StallProbe {
 public:
  /// Periods between two reads of /proc/stat when no period is late.
  static constexpr int kStealEvery = 100;

  StallProbe() = default;
  ~StallProbe();
  StallProbe(const StallProbe&) = delete;
  StallProbe& operator=(const StallProbe&) = delete;

  /// Called by the control thread at the start of period k, `lateness_s` after
  /// its deadline, and `late_s`: the lateness from which a period counts as
  /// late (a /proc/stat read follows at once). The first call opens the
  /// files (from the control thread, so the thread's own schedstat is read).
  void Sample(std::int64_t k, double lateness_s, double late_s, double wall_s);

  /// What was found so far.
  const StallReport& report() const { return report_; }

 private:
  bool started_ = false;
  int schedstat_fd_ = -1;
  int stat_fd_ = -1;
  ThreadCounters first_, last_;
  double first_wall_s_ = 0;
  double last_wall_s_ = 0;  // the previous sample's wall time, s
  double first_steal_s_ = -1;
  double window_steal_s_ = -1;  // steal at the last /proc/stat read
  double window_wall_s_ = 0;    // and its wall time
  int since_steal_ = 0;
  StallReport report_;
};

}  // namespace vlab
