#include "core/core_realtime.h"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/resource.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace vlab {

std::string RealtimeGrant::Line() const {
  if (requested == 0) return "realtime priority not requested";
  const std::string p = "realtime priority " + std::to_string(requested);
  if (!granted) return p + " not granted: " + reason + "; running at normal priority";
  if (memory_locked) return p + " granted (SCHED_FIFO, memory locked)";
  if (reason.empty()) return p + " granted (SCHED_FIFO)";
  return p + " granted (SCHED_FIFO, memory not locked: " + reason + ")";
}

std::string RealtimeRefusal(int priority, int error) {
  std::string why = std::strerror(error);
  if (error == EPERM) {
    rlimit limit{};
    std::string have = "unknown";
    if (::getrlimit(RLIMIT_RTPRIO, &limit) == 0) {
      have = limit.rlim_cur == RLIM_INFINITY ? "unlimited" : std::to_string(limit.rlim_cur);
    }
    why += " (SCHED_FIFO " + std::to_string(priority) + " needs root, CAP_SYS_NICE or an rtprio limit >= " +
           std::to_string(priority) + "; ulimit -r is " + have + ")";
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

RealtimeGrant RequestRealtime(int priority) {
  if (priority < 0 || priority > kMaxRealtimePriority) {
    throw std::invalid_argument("realtime priority " + std::to_string(priority) + " is outside 0..99");
  }
  RealtimeGrant g;
  g.requested = priority;
  if (priority == 0) return g;
  if (!SetThreadRealtime(priority)) {
    g.reason = RealtimeRefusal(priority, errno);
    return g;
  }
  g.granted = true;
  if (::mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
    g.memory_locked = true;
  } else {
    g.reason = std::string("mlockall: ") + std::strerror(errno);
  }
  return g;
}

void DropRealtime(const RealtimeGrant& grant) {
  if (!grant.granted) return;
  sched_param param{};
  param.sched_priority = 0;
  ::pthread_setschedparam(::pthread_self(), SCHED_OTHER, &param);
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
