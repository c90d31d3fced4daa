#include "core/core_realtime.h"

#include <fcntl.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <stdexcept>

namespace vlab {

namespace {

// The kernel's struct sched_attr (include/uapi/linux/sched/types.h); glibc 2.36
// has no wrapper for sched_setattr / sched_getattr.
struct SchedAttr {
  std::uint32_t size;
  std::uint32_t sched_policy;
  std::uint64_t sched_flags;
  std::int32_t sched_nice;
  std::uint32_t sched_priority;
  std::uint64_t sched_runtime;
  std::uint64_t sched_deadline;
  std::uint64_t sched_period;
  std::uint32_t sched_util_min;
  std::uint32_t sched_util_max;
};

bool GetAttr(SchedAttr* a) {
  *a = SchedAttr{};
  return ::syscall(SYS_sched_getattr, 0, a, sizeof(SchedAttr), 0) == 0;
}

std::string SliceText(std::uint64_t ns) {
  if (ns == 0) return "the kernel keeps no per-thread slice (Linux < 6.12)";
  char text[64];
  std::snprintf(text, sizeof text, "a %.1f ms scheduler slice", static_cast<double>(ns) * 1e-6);
  return text;
}

// the device CPUs of the last grant that kept a CPU (BindDeviceThread)
std::mutex g_device_cpus_mutex;
DeviceCpus g_device_cpus;
// the priority of the last SCHED_DEADLINE loop granted in this process (0: none)
std::atomic<int> g_deadline_priority{0};

constexpr std::uint32_t kSchedDeadline = 6;            // SCHED_DEADLINE (linux/sched.h)
constexpr std::uint64_t kSchedFlagResetOnFork = 0x01;  // SCHED_FLAG_RESET_ON_FORK
constexpr std::uint64_t kSchedFlagReclaim = 0x02;      // SCHED_FLAG_RECLAIM

// the calling thread on SCHED_DEADLINE: `runtime_ns` of every `period_ns`, due by the
// period's end; threads it makes start at normal priority (a SCHED_DEADLINE thread may
// not pass its reservation on), and it may use bandwidth other reservations leave
bool SetThreadDeadline(std::uint64_t runtime_ns, std::uint64_t period_ns) {
  SchedAttr a{};
  a.size = sizeof(SchedAttr);
  a.sched_policy = kSchedDeadline;
  a.sched_flags = kSchedFlagResetOnFork | kSchedFlagReclaim;
  a.sched_runtime = runtime_ns;
  a.sched_deadline = period_ns;
  a.sched_period = period_ns;
  return ::syscall(SYS_sched_setattr, 0, &a, 0) == 0;
}

// the PM QoS request on the CPUs' wake-up latency: its file, open while held
std::mutex g_wake_mutex;
int g_wake_fd = -1;
int g_wake_holders = 0;

std::string Millis(std::uint64_t ns) {
  char text[32];
  std::snprintf(text, sizeof text, "%g ms", static_cast<double>(ns) * 1e-6);
  return text;
}

// keeps the CPU the calling thread runs on for it, the others for device threads
void KeepCpu(RealtimeGrant* g) {
  const std::vector<int> allowed = ThreadCpus();
  const int cpu = ::sched_getcpu();
  if (allowed.size() < 2 || cpu < 0 || !BindThread(0, {cpu})) return;
  g->loop_cpu = cpu;
  g->allowed_cpus = allowed;
  for (const int c : allowed) {
    if (c != cpu) g->device_cpus.push_back(c);
  }
  std::lock_guard<std::mutex> lock(g_device_cpus_mutex);
  g_device_cpus = {g->device_cpus, allowed};
}

}  // namespace

std::vector<int> ThreadCpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  std::vector<int> cpus;
  if (::sched_getaffinity(0, sizeof(set), &set) != 0) return cpus;
  for (int c = 0; c < CPU_SETSIZE; ++c) {
    if (CPU_ISSET(c, &set)) cpus.push_back(c);
  }
  return cpus;
}

bool BindThread(int tid, const std::vector<int>& cpus) {
  if (cpus.empty()) return false;
  cpu_set_t set;
  CPU_ZERO(&set);
  for (const int c : cpus) {
    if (c < 0 || c >= CPU_SETSIZE) return false;
    CPU_SET(c, &set);
  }
  return ::sched_setaffinity(tid, sizeof(set), &set) == 0;
}

std::string CpuListText(const std::vector<int>& cpus) {
  std::string text;
  for (const int c : cpus) text += (text.empty() ? "" : ",") + std::to_string(c);
  return text;
}

int DeadlineLoopPriority() { return g_deadline_priority.load(); }

DeviceCpus BindDeviceThread() {
  DeviceCpus cpus;
  {
    std::lock_guard<std::mutex> lock(g_device_cpus_mutex);
    cpus = g_device_cpus;
  }
  if (cpus.device.empty() || !BindThread(0, cpus.device)) return {};
  return cpus;
}

std::uint64_t ThreadSlice() {
  SchedAttr a{};
  if (!GetAttr(&a) || (a.sched_policy != SCHED_OTHER && a.sched_policy != SCHED_BATCH)) return 0;
  return a.sched_runtime;
}

std::uint64_t SetThreadSlice(std::uint64_t ns) {
  SchedAttr a{};
  if (!GetAttr(&a) || (a.sched_policy != SCHED_OTHER && a.sched_policy != SCHED_BATCH)) return 0;
  // the nice value read back goes in again; util clamps and the policy stay
  a.size = sizeof(SchedAttr);
  a.sched_flags = 0;
  a.sched_runtime = ns;
  ::syscall(SYS_sched_setattr, 0, &a, 0);
  return ThreadSlice();
}

bool HoldWakeLatency(std::string* error) {
  std::lock_guard<std::mutex> lock(g_wake_mutex);
  if (g_wake_holders == 0) {
    const int fd = ::open("/dev/cpu_dma_latency", O_WRONLY | O_CLOEXEC);
    const std::int32_t us = 0;  // (the kernel reads a binary s32)
    if (fd < 0 || ::write(fd, &us, sizeof(us)) != static_cast<ssize_t>(sizeof(us))) {
      *error = std::string("/dev/cpu_dma_latency: ") + std::strerror(errno) + (errno == EACCES ? " (root only)" : "");
      if (fd >= 0) ::close(fd);
      return false;
    }
    g_wake_fd = fd;
  }
  ++g_wake_holders;
  return true;
}

void ReleaseWakeLatency() {
  std::lock_guard<std::mutex> lock(g_wake_mutex);
  if (g_wake_holders == 0 || --g_wake_holders > 0) return;
  ::close(g_wake_fd);  // (closing withdraws the request)
  g_wake_fd = -1;
}

std::string RealtimeGrant::Line() const {
  std::string slice = SliceText(slice_ns);
  if (loop_cpu >= 0) {
    slice += ", alone on CPU " + std::to_string(loop_cpu) + " (device threads on " + CpuListText(device_cpus) + ")";
  }
  if (requested == 0) return "realtime priority not requested; " + slice;
  const std::string p = "realtime priority " + std::to_string(requested);
  if (!granted) return p + " not granted: " + reason + "; running at normal priority with " + slice;
  std::string how = "SCHED_FIFO";
  if (deadline_period_ns > 0) {
    how = "SCHED_DEADLINE " + Millis(deadline_runtime_ns) + " of every " + Millis(deadline_period_ns) +
          ", device threads SCHED_FIFO " + std::to_string(std::max(kMinRealtimePriority, requested - 1));
  } else if (!deadline_refused.empty()) {
    how += "; SCHED_DEADLINE refused: " + deadline_refused;
  }
  if (wake_latency_held) how += ", CPUs kept out of deep idle";
  if (!wake_latency_refused.empty()) how += "; CPUs may idle deeply: " + wake_latency_refused;
  if (memory_locked) return p + " granted (" + how + ", memory locked)";
  if (reason.empty()) return p + " granted (" + how + ")";
  return p + " granted (" + how + ", memory not locked: " + reason + ")";
}

std::string RealtimeRefusal(int priority, int error) {
  std::string why = std::strerror(error);
  if (error == EPERM) {
    rlimit limit{};
    std::string have = "unknown";
    if (::getrlimit(RLIMIT_RTPRIO, &limit) == 0) {
      have = limit.rlim_cur == RLIM_INFINITY ? "unlimited" : std::to_string(limit.rlim_cur);
    }
    why += " (SCHED_FIFO " + std::to_string(priority) +
           " needs root, CAP_SYS_NICE or an rtprio limit >= " + std::to_string(priority) + "; ulimit -r is " + have +
           ")";
  }
  return why;
}

bool SetThreadRealtime(int priority) {
  if (priority < kMinRealtimePriority || priority > kMaxRealtimePriority) {
    errno = EINVAL;
    return false;
  }
  sched_param param{};
  param.sched_priority = priority;
  const int error = ::pthread_setschedparam(::pthread_self(), SCHED_FIFO, &param);
  if (error != 0) errno = error;
  return error == 0;
}

void SetThreadNormal() {
  sched_param param{};
  param.sched_priority = 0;
  ::pthread_setschedparam(::pthread_self(), SCHED_OTHER, &param);
}

RealtimeGrant RequestRealtime(int priority, bool keep_cpu, double period_s) {
  if (priority < 0 || priority > kMaxRealtimePriority) {
    throw std::invalid_argument("realtime priority " + std::to_string(priority) + " is outside 0..99");
  }
  RealtimeGrant g;
  g.requested = priority;
  if (priority == 0) {
    g.slice_ns = SetThreadSlice(kLoopSlice_ns);
    if (keep_cpu) KeepCpu(&g);
    return g;
  }
  if (!SetThreadRealtime(priority)) {
    g.reason = RealtimeRefusal(priority, errno);
    g.slice_ns = SetThreadSlice(kLoopSlice_ns);
    if (keep_cpu) KeepCpu(&g);
    return g;
  }
  g.granted = true;
  if (period_s > 0) {
    const auto period_ns = static_cast<std::uint64_t>(std::llround(period_s * 1e9));
    const auto runtime_ns = static_cast<std::uint64_t>(std::llround(period_s * kDeadlineShare * 1e9));
    if (SetThreadDeadline(runtime_ns, period_ns)) {
      g.deadline_runtime_ns = runtime_ns;
      g.deadline_period_ns = period_ns;
      g_deadline_priority = priority;
    } else {
      g.deadline_refused = std::strerror(errno);  // (still SCHED_FIFO)
    }
    g.wake_latency_held = HoldWakeLatency(&g.wake_latency_refused);
  }
  if (::mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
    g.memory_locked = true;
  } else {
    g.reason = std::string("mlockall: ") + std::strerror(errno);
  }
  return g;
}

void DropRealtime(const RealtimeGrant& grant) {
  if (grant.slice_ns != 0) SetThreadSlice(0);
  if (grant.loop_cpu >= 0) {
    BindThread(0, grant.allowed_cpus);
    std::lock_guard<std::mutex> lock(g_device_cpus_mutex);
    if (g_device_cpus.device == grant.device_cpus) g_device_cpus = {};
  }
  if (!grant.granted) return;
  if (grant.wake_latency_held) ReleaseWakeLatency();
  if (grant.deadline_period_ns > 0) {
    int expected = grant.requested;
    g_deadline_priority.compare_exchange_strong(expected, 0);
  }
  SetThreadNormal();
  if (grant.memory_locked) ::munlockall();
}

int ProcessRealtimePriority(int pid) {
  const int policy = ::sched_getscheduler(pid);
  if (policy < 0) return -1;
  if (policy != SCHED_FIFO && policy != SCHED_RR) return 0;
  sched_param param{};
  if (::sched_getparam(pid, &param) != 0) return -1;
  return param.sched_priority;
}

}  // namespace vlab
