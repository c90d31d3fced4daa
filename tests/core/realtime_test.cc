// Realtime scheduling when permitted (src/core/core_realtime.h): what a thread
// asks for is what it gets when the machine allows SCHED_FIFO, and a refusal
// says why; either way the caller goes on. Whether this machine allows it is
// probed independently (sched_setscheduler on a scratch thread), so the test
// asserts the right outcome as root (CI), with CAP_SYS_NICE or an rtprio limit,
// and without any of them.
#include <pthread.h>
#include <sched.h>
#include <sys/utsname.h>

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <dirent.h>
#include <fcntl.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "core/core_realtime.h"

namespace vlab {
namespace {

// the kernel's answer for this process, asked without the code under test
bool FifoPermitted(int priority) {
  bool permitted = false;
  std::thread probe([&] {
    sched_param p{};
    p.sched_priority = priority;
    permitted = ::sched_setscheduler(0, SCHED_FIFO, &p) == 0;  // 0: this thread only
  });
  probe.join();
  return permitted;
}

// SCHED_DEADLINE for a scratch thread, through the raw system call (the kernel's
// struct sched_attr, the first 48 bytes), not through the code under test
bool DeadlinePermitted(std::uint64_t runtime_ns, std::uint64_t period_ns) {
  bool permitted = false;
  std::thread probe([&] {
    struct {
      std::uint32_t size, policy;
      std::uint64_t flags;
      std::int32_t nice;
      std::uint32_t priority;
      std::uint64_t runtime, deadline, period;
    } a{48, 6 /* SCHED_DEADLINE */, 0x01 /* reset on fork */, 0, 0, runtime_ns, period_ns, period_ns};
    permitted = ::syscall(SYS_sched_setattr, 0, &a, 0) == 0;
    sched_param p{};
    if (permitted) ::sched_setscheduler(0, SCHED_OTHER, &p);
  });
  probe.join();
  return permitted;
}

// the calling thread's policy without the reset-on-fork flag
int Policy() { return ::sched_getscheduler(0) & ~SCHED_RESET_ON_FORK; }

// Linux 6.12 and later keep a fair-scheduler slice per thread (sched_setattr's
// sched_runtime); read from the kernel's release, not from the code under test
bool KernelHasPerThreadSlice() {
  utsname u{};
  if (::uname(&u) != 0) return false;
  int major = 0, minor = 0;
  if (std::sscanf(u.release, "%d.%d", &major, &minor) != 2) return false;
  return major > 6 || (major == 6 && minor >= 12);
}

int ThreadPolicy(int* priority) {
  int policy = 0;
  sched_param p{};
  ::pthread_getschedparam(::pthread_self(), &policy, &p);
  *priority = p.sched_priority;
  return policy;
}

TEST(Realtime, GrantedExactlyWhenTheKernelPermitsAndDroppedAfter) {
  const bool permitted = FifoPermitted(20);
  std::thread worker([&] {
    const RealtimeGrant g = RequestRealtime(20);
    int priority = -1;
    const int policy = ThreadPolicy(&priority);
    EXPECT_EQ(g.requested, 20);
    EXPECT_EQ(g.granted, permitted) << g.Line();
    if (permitted) {
      EXPECT_EQ(policy, SCHED_FIFO);
      EXPECT_EQ(priority, 20);
      EXPECT_EQ(g.Line().rfind("realtime priority 20 granted (SCHED_FIFO", 0), 0u) << g.Line();
    } else {
      EXPECT_EQ(policy, SCHED_OTHER);
      EXPECT_FALSE(g.memory_locked);
      EXPECT_NE(g.reason.find("rtprio"), std::string::npos) << g.reason;  // says what would grant it
      EXPECT_NE(g.Line().find("running at normal priority"), std::string::npos) << g.Line();
      // refused, the loop thread asks for the shortest fair slice instead
      EXPECT_EQ(g.slice_ns, KernelHasPerThreadSlice() ? kLoopSlice_ns : 0u) << g.Line();
      EXPECT_EQ(ThreadSlice(), g.slice_ns);
    }
    DropRealtime(g);
    EXPECT_EQ(ThreadPolicy(&priority), SCHED_OTHER);
    EXPECT_EQ(priority, 0);
  });
  worker.join();
}

TEST(Realtime, ZeroAsksForNothingAndOutOfRangeIsRefused) {
  std::thread worker([] {
    const RealtimeGrant g = RequestRealtime(0);
    EXPECT_FALSE(g.granted);
    EXPECT_TRUE(g.reason.empty());
    int priority = -1;
    EXPECT_EQ(ThreadPolicy(&priority), SCHED_OTHER);
    // no SCHED_FIFO asked: the thread still asks for the shortest fair slice
    if (KernelHasPerThreadSlice()) {
      EXPECT_EQ(g.slice_ns, kLoopSlice_ns);
      EXPECT_EQ(g.Line(), "realtime priority not requested; a 0.1 ms scheduler slice");
    } else {
      EXPECT_EQ(g.slice_ns, 0u);
      EXPECT_EQ(g.Line(), "realtime priority not requested; the kernel keeps no per-thread slice (Linux < 6.12)");
    }
    DropRealtime(g);
    EXPECT_NE(ThreadSlice(), kLoopSlice_ns);  // the default again
    EXPECT_THROW(RequestRealtime(100), std::invalid_argument);
    EXPECT_THROW(RequestRealtime(-1), std::invalid_argument);
    EXPECT_FALSE(SetThreadRealtime(0));
    EXPECT_FALSE(SetThreadRealtime(100));
  });
  worker.join();
}

// SetThreadNormal undoes SetThreadRealtime, and only that: the thread's nice value is kept
TEST(Realtime, SetThreadNormalUndoesSetThreadRealtimeAndKeepsTheNiceValue) {
  const bool permitted = FifoPermitted(20);
  std::thread worker([&] {
    const id_t tid = static_cast<id_t>(::gettid());
    ASSERT_EQ(::setpriority(PRIO_PROCESS, tid, 5), 0);
    EXPECT_EQ(SetThreadRealtime(20), permitted);
    int priority = -1;
    EXPECT_EQ(ThreadPolicy(&priority), permitted ? SCHED_FIFO : SCHED_OTHER);
    EXPECT_EQ(priority, permitted ? 20 : 0);
    SetThreadNormal();
    EXPECT_EQ(ThreadPolicy(&priority), SCHED_OTHER);
    EXPECT_EQ(priority, 0);
    errno = 0;
    EXPECT_EQ(::getpriority(PRIO_PROCESS, tid), 5);
    EXPECT_EQ(errno, 0);
  });
  worker.join();
}

// the slice is asked and read back per thread, with the thread's nice value kept
TEST(Realtime, AThreadsSliceIsSetReadBackAndKeepsItsNiceValue) {
  std::thread worker([] {
    const id_t tid = static_cast<id_t>(::gettid());
    ASSERT_EQ(::setpriority(PRIO_PROCESS, tid, 5), 0);
    const std::uint64_t before = ThreadSlice();
    const std::uint64_t got = SetThreadSlice(2'000'000);
    if (KernelHasPerThreadSlice()) {
      EXPECT_GT(before, 0u);
      EXPECT_EQ(got, 2'000'000u);
      EXPECT_EQ(SetThreadSlice(kLoopSlice_ns), kLoopSlice_ns);
    } else {
      EXPECT_EQ(got, 0u);
    }
    errno = 0;
    EXPECT_EQ(::getpriority(PRIO_PROCESS, tid), 5);
    SetThreadSlice(0);
    if (KernelHasPerThreadSlice()) {
      EXPECT_EQ(ThreadSlice(), before);
    }
  });
  worker.join();
}

TEST(Realtime, AThreadsPriorityIsReadBackPerProcess) {
  EXPECT_EQ(ProcessRealtimePriority(0), 0);            // this process's main thread: normal priority
  EXPECT_EQ(ProcessRealtimePriority(0x7ffffff0), -1);  // no such process
}

TEST(Realtime, ARefusalNamesWhatWouldGrantIt) {
  const std::string why = RealtimeRefusal(50, EPERM);
  EXPECT_NE(why.find("root, CAP_SYS_NICE or an rtprio limit >= 50"), std::string::npos) << why;
  EXPECT_NE(why.find("ulimit -r is "), std::string::npos) << why;
}

// a loop with a period asks for SCHED_DEADLINE once SCHED_FIFO is granted: the
// threads it makes start at normal priority and learn its priority; refused, it
// stays at SCHED_FIFO and says why; given back, it is a normal thread again
TEST(Realtime, APeriodicLoopGetsDeadlineSchedulingWhenTheKernelAdmitsIt) {
  const bool fifo = FifoPermitted(20);
  const bool deadline = fifo && DeadlinePermitted(900'000, 1'000'000);
  std::thread loop([&] {
    const RealtimeGrant g = RequestRealtime(20, false, 0.001);
    EXPECT_EQ(g.granted, fifo) << g.Line();
    if (deadline) {
      EXPECT_EQ(Policy(), 6) << g.Line();  // SCHED_DEADLINE
      EXPECT_EQ(g.deadline_runtime_ns, 900'000u);
      EXPECT_EQ(g.deadline_period_ns, 1'000'000u);
      EXPECT_TRUE(g.deadline_refused.empty());
      EXPECT_EQ(DeadlineLoopPriority(), 20);
      EXPECT_EQ(g.Line().rfind("realtime priority 20 granted (SCHED_DEADLINE 0.9 ms of every 1 ms, device threads "
                               "SCHED_FIFO 19",
                               0),
                0u)
          << g.Line();
      std::thread made([] { EXPECT_EQ(Policy(), SCHED_OTHER); });  // (it may not pass its reservation on)
      made.join();
    } else if (fifo) {
      EXPECT_EQ(Policy(), SCHED_FIFO);
      EXPECT_EQ(g.deadline_period_ns, 0u);
      EXPECT_FALSE(g.deadline_refused.empty());
      EXPECT_EQ(DeadlineLoopPriority(), 0);
      EXPECT_NE(g.Line().find("SCHED_DEADLINE refused: "), std::string::npos) << g.Line();
    } else {
      EXPECT_EQ(Policy(), SCHED_OTHER);
      EXPECT_EQ(g.deadline_period_ns, 0u);
    }
    DropRealtime(g);
    EXPECT_EQ(Policy(), SCHED_OTHER);
    EXPECT_EQ(DeadlineLoopPriority(), 0);
  });
  loop.join();
  // without a period: SCHED_FIFO, as before
  std::thread plain([&] {
    const RealtimeGrant g = RequestRealtime(20);
    EXPECT_EQ(g.deadline_period_ns, 0u);
    EXPECT_TRUE(g.deadline_refused.empty());
    EXPECT_EQ(Policy(), fifo ? SCHED_FIFO : SCHED_OTHER);
    DropRealtime(g);
  });
  plain.join();
}

// the kernel's current wake-up latency target (us), read from /dev/cpu_dma_latency;
// -1 when it cannot be read
long CpuLatencyTarget() {
  const int fd = ::open("/dev/cpu_dma_latency", O_RDONLY | O_CLOEXEC);
  if (fd < 0) return -1;
  std::int32_t us = -1;
  const bool ok = ::read(fd, &us, sizeof(us)) == static_cast<ssize_t>(sizeof(us));
  ::close(fd);
  return ok ? us : -1;
}

// how many of this process's open files are /dev/cpu_dma_latency
int OpenLatencyFiles() {
  int n = 0;
  DIR* dir = ::opendir("/proc/self/fd");
  if (!dir) return -1;
  while (const dirent* e = ::readdir(dir)) {
    char target[256] = {};
    const std::string link = std::string("/proc/self/fd/") + e->d_name;
    const ssize_t len = ::readlink(link.c_str(), target, sizeof(target) - 1);
    if (len > 0 && std::string(target, len) == "/dev/cpu_dma_latency") ++n;
  }
  ::closedir(dir);
  return n;
}

// a periodic loop granted SCHED_FIFO holds the CPUs' wake-up latency at 0 us while any
// grant holds it (core_realtime.h), and lets it go with the last; where the file may
// not be written (not root) the grant says so and the loop goes on
TEST(Realtime, APeriodicLoopKeepsTheCpusOutOfDeepIdleWhileItsGrantHolds) {
  const bool fifo = FifoPermitted(20);
  const bool writable = ::access("/dev/cpu_dma_latency", W_OK) == 0;
  ASSERT_EQ(OpenLatencyFiles(), 0);
  std::thread loop([&] {
    const RealtimeGrant g = RequestRealtime(20, false, 0.001);
    if (fifo && writable) {
      EXPECT_TRUE(g.wake_latency_held) << g.wake_latency_refused;
      EXPECT_NE(g.Line().find("CPUs kept out of deep idle"), std::string::npos) << g.Line();
      EXPECT_EQ(CpuLatencyTarget(), 0);
      EXPECT_EQ(OpenLatencyFiles(), 1);
      const RealtimeGrant second = RequestRealtime(20, false, 0.001);  // (a second loop of the process)
      EXPECT_TRUE(second.wake_latency_held);
      EXPECT_EQ(OpenLatencyFiles(), 1);
      DropRealtime(second);
      EXPECT_EQ(OpenLatencyFiles(), 1);  // the first still holds it
      EXPECT_EQ(CpuLatencyTarget(), 0);
    } else if (fifo) {
      EXPECT_FALSE(g.wake_latency_held);
      EXPECT_NE(g.wake_latency_refused.find("/dev/cpu_dma_latency: "), std::string::npos) << g.Line();
      EXPECT_NE(g.Line().find("CPUs may idle deeply"), std::string::npos) << g.Line();
    } else {
      EXPECT_FALSE(g.wake_latency_held);  // (not asked: no SCHED_FIFO)
      EXPECT_TRUE(g.wake_latency_refused.empty());
    }
    DropRealtime(g);
    EXPECT_EQ(OpenLatencyFiles(), 0);
  });
  loop.join();
  // without a period (not a periodic loop): not held
  std::thread plain([] {
    const RealtimeGrant g = RequestRealtime(20);
    EXPECT_FALSE(g.wake_latency_held);
    EXPECT_EQ(OpenLatencyFiles(), 0);
    DropRealtime(g);
  });
  plain.join();
}

// without SCHED_FIFO, a loop that keeps a CPU is bound to the one it runs on, and
// device threads bound afterwards run on the others; the CPU is given back after
TEST(Realtime, ALoopWithoutPriorityKeepsItsCpuAndDeviceThreadsTakeTheOthers) {
  std::thread loop([] {
    const std::vector<int> allowed = ThreadCpus();
    ASSERT_FALSE(allowed.empty());
    const RealtimeGrant g = RequestRealtime(0, /*keep_cpu=*/true);
    if (allowed.size() < 2) {  // one CPU: nothing to keep
      EXPECT_EQ(g.loop_cpu, -1);
      EXPECT_TRUE(BindDeviceThread().device.empty());
      DropRealtime(g);
      return;
    }
    ASSERT_GE(g.loop_cpu, 0);
    EXPECT_EQ(ThreadCpus(), std::vector<int>{g.loop_cpu});
    EXPECT_EQ(g.allowed_cpus, allowed);
    std::vector<int> others;
    for (const int c : allowed) {
      if (c != g.loop_cpu) others.push_back(c);
    }
    EXPECT_EQ(g.device_cpus, others);
    EXPECT_NE(g.Line().find("alone on CPU " + std::to_string(g.loop_cpu)), std::string::npos) << g.Line();
    // a device thread made by the loop inherits its one CPU, then moves to the others
    std::thread device([&] {
      EXPECT_EQ(ThreadCpus(), std::vector<int>{g.loop_cpu});
      const DeviceCpus cpus = BindDeviceThread();
      EXPECT_EQ(cpus.device, others);
      EXPECT_EQ(cpus.allowed, allowed);
      EXPECT_EQ(ThreadCpus(), others);
    });
    device.join();
    DropRealtime(g);
    EXPECT_EQ(ThreadCpus(), allowed);
    std::thread late([] { EXPECT_TRUE(BindDeviceThread().device.empty()); });  // nothing kept now
    late.join();
  });
  loop.join();
  // not asked: nothing kept
  std::thread plain([] {
    const std::vector<int> allowed = ThreadCpus();
    const RealtimeGrant g = RequestRealtime(0);
    EXPECT_EQ(g.loop_cpu, -1);
    EXPECT_EQ(ThreadCpus(), allowed);
    DropRealtime(g);
  });
  plain.join();
}

}  // namespace
}  // namespace vlab
