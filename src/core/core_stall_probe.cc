#include "core/core_stall_probe.h"

#include <fcntl.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <ctime>

namespace vlab {

namespace {

// reads a small /proc file from its start into buf (NUL-terminated); false when unreadable
bool ReadSmall(int fd, char* buf, std::size_t size) {
  if (fd < 0) return false;
  const ssize_t n = pread(fd, buf, size - 1, 0);
  if (n <= 0) return false;
  buf[n] = '\0';
  return true;
}

std::string Milliseconds(double s) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f ms", s * 1e3);
  return text;
}

}  // namespace

ThreadCounters ReadThreadCounters(int schedstat_fd) {
  ThreadCounters c;
  rusage u{};
  if (getrusage(RUSAGE_THREAD, &u) == 0) {
    c.voluntary_switches = u.ru_nvcsw;
    c.involuntary_switches = u.ru_nivcsw;
    c.minor_faults = u.ru_minflt;
    c.major_faults = u.ru_majflt;
  }
  // (schedstat's on-CPU time lags by up to a tick for the running thread; this clock does not)
  timespec cpu{};
  if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &cpu) == 0) {
    c.on_cpu_s = static_cast<double>(cpu.tv_sec) + static_cast<double>(cpu.tv_nsec) * 1e-9;
  }
  // schedstat: "cpu_ns run_delay_ns timeslices"
  char buf[128];
  if (ReadSmall(schedstat_fd, buf, sizeof buf)) {
    char* end = nullptr;
    std::strtoull(buf, &end, 10);
    const char* delay = end;
    const unsigned long long run_delay_ns = std::strtoull(delay, &end, 10);
    if (end != delay) c.run_delay_s = static_cast<double>(run_delay_ns) * 1e-9;
  }
  return c;
}

double ReadStealSeconds(int stat_fd) {
  // the first line: "cpu  user nice system idle iowait irq softirq steal ..."
  char buf[512];
  if (!ReadSmall(stat_fd, buf, sizeof buf)) return -1;
  const char* at = buf;
  while (*at && *at != ' ') ++at;  // skip "cpu"
  unsigned long long value = 0;
  for (int field = 0; field < 8; ++field) {
    char* end = nullptr;
    value = std::strtoull(at, &end, 10);
    if (end == at) return -1;
    at = end;
  }
  const long ticks = sysconf(_SC_CLK_TCK);
  return ticks > 0 ? static_cast<double>(value) / static_cast<double>(ticks) : -1;
}

std::string StallRecord::Cause() const {
  if (period < 0) return "no period sampled";
  if (major_faults > 0) return std::to_string(major_faults) + " major page faults (the control thread waited for I/O)";
  const double cpu_wait = run_delay_s > 0 ? run_delay_s : 0;
  const double steal = steal_s > 0 ? steal_s : 0;
  // a cause explains the stall when it is at least a third of the lateness
  if (steal >= cpu_wait && steal >= lateness_s / 3) {
    return "steal " + Milliseconds(steal) + " in the " + Milliseconds(steal_window_s) +
           " around it (the hypervisor ran another guest)";
  }
  if (cpu_wait >= lateness_s / 3) {
    // runnable but not running: taken off its CPU, or woken and kept waiting for one
    if (involuntary_switches == 0) {
      return "waited " + Milliseconds(cpu_wait) +
             " for a CPU after its wake-up (the kernel, an interrupt or a higher-priority thread held it)";
    }
    return "waited " + Milliseconds(cpu_wait) + " for a CPU (" + std::to_string(involuntary_switches) +
           " involuntary switches: another thread or process ran on its CPU)";
  }
  // neither: where was the thread across the window? On a CPU, waiting for one, or asleep
  // (voluntary waits); time in none of them, without a wait, was taken from it while it held
  // its CPU: its vCPU stopped (steal that /proc/stat's 10 ms ticks missed) or interrupts ran
  // (with IRQ time accounting, not charged to the thread)
  const std::string counts = " (" + std::to_string(voluntary_switches) + " voluntary waits, " +
                             std::to_string(minor_faults) + " minor page faults" +
                             (run_delay_s < 0 ? "; run delay unknown)" : ")");
  if (on_cpu_s < 0) return "not explained by a CPU wait or steal; on-CPU time unknown" + counts;
  const std::string ran = "ran " + Milliseconds(on_cpu_s) + " of the " + Milliseconds(window_s) + " window";
  const double unaccounted = window_s - on_cpu_s - cpu_wait;
  if (voluntary_switches == 0 && unaccounted >= lateness_s / 3) {
    return "its CPU was taken without a switch: it " + ran + ", never waited for a CPU nor slept, and lost " +
           Milliseconds(unaccounted) + " (its vCPU stopped, or interrupts ran)" + counts;
  }
  // where at its deadline? still at work (busy), or gone to sleep and woken late
  if (on_cpu_s + cpu_wait >= window_s - lateness_s) return "busy in the lab: it " + ran + counts;
  return "a late wake-up: it slept past its deadline (" + ran +
         "; a CPU leaving deep idle, or a timer or interrupt "
         "delivered late)" +
         counts;
}

StallProbe::~StallProbe() {
  if (schedstat_fd_ >= 0) close(schedstat_fd_);
  if (stat_fd_ >= 0) close(stat_fd_);
}

void StallProbe::Sample(std::int64_t k, double lateness_s, double late_s, double wall_s) {
  if (!started_) {
    started_ = true;
    schedstat_fd_ = open("/proc/thread-self/schedstat", O_RDONLY | O_CLOEXEC);
    stat_fd_ = open("/proc/stat", O_RDONLY | O_CLOEXEC);
    first_ = last_ = ReadThreadCounters(schedstat_fd_);
    first_wall_s_ = window_wall_s_ = last_wall_s_ = wall_s;
    first_steal_s_ = window_steal_s_ = ReadStealSeconds(stat_fd_);
    return;
  }
  const ThreadCounters now = ReadThreadCounters(schedstat_fd_);
  const bool late = lateness_s > late_s;
  double steal_window = -1, steal_window_s = 0;
  if (late || ++since_steal_ >= kStealEvery) {
    const double steal = ReadStealSeconds(stat_fd_);
    if (steal >= 0 && window_steal_s_ >= 0) {
      steal_window = steal - window_steal_s_;
      steal_window_s = wall_s - window_wall_s_;
    }
    window_steal_s_ = steal;
    window_wall_s_ = wall_s;
    since_steal_ = 0;
    if (steal >= 0 && first_steal_s_ >= 0) report_.steal_s = steal - first_steal_s_;
  }
  StallRecord& w = report_.worst;
  if (w.period < 0 || lateness_s > w.lateness_s) {
    w.period = k;
    w.lateness_s = lateness_s;
    w.voluntary_switches = now.voluntary_switches - last_.voluntary_switches;
    w.involuntary_switches = now.involuntary_switches - last_.involuntary_switches;
    w.minor_faults = now.minor_faults - last_.minor_faults;
    w.major_faults = now.major_faults - last_.major_faults;
    w.run_delay_s = now.run_delay_s >= 0 && last_.run_delay_s >= 0 ? now.run_delay_s - last_.run_delay_s : -1;
    w.on_cpu_s = now.on_cpu_s >= 0 && last_.on_cpu_s >= 0 ? now.on_cpu_s - last_.on_cpu_s : -1;
    w.window_s = wall_s - last_wall_s_;
    w.steal_s = steal_window;
    w.steal_window_s = steal_window_s;
  }
  report_.wall_s = wall_s - first_wall_s_;
  last_wall_s_ = wall_s;
  report_.voluntary_switches = now.voluntary_switches - first_.voluntary_switches;
  report_.involuntary_switches = now.involuntary_switches - first_.involuntary_switches;
  report_.minor_faults = now.minor_faults - first_.minor_faults;
  report_.major_faults = now.major_faults - first_.major_faults;
  report_.run_delay_s = now.run_delay_s >= 0 && first_.run_delay_s >= 0 ? now.run_delay_s - first_.run_delay_s : -1;
  last_ = now;
}

}  // namespace vlab
