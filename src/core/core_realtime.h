// Realtime scheduling when the user may have it: SCHED_FIFO for a thread (or a
// program about to exec) and locked memory, asked for, never required.
//
// Linux grants SCHED_FIFO to root, to a process with CAP_SYS_NICE, or up to the
// RLIMIT_RTPRIO limit (`ulimit -r`, /etc/security/limits.conf "rtprio"). Without
// it the call is refused with EPERM and the caller goes on at normal priority;
// the grant says what happened and why, in one line, for the console and for
// summary.json. Locking memory (mlockall) keeps page faults out of the control
// loop; it is tried once the priority is granted, and its refusal is reported
// but does not withdraw the priority.
//
// Priorities are SCHED_FIFO's 1 (lowest) to 99; 0 asks for nothing. The kernel's
// realtime throttling (/proc/sys/kernel/sched_rt_runtime_us, 95 % by default)
// still leaves the rest of the machine a share of every second.
#pragma once

#include <string>

namespace vlab {

/// SCHED_FIFO's range.
inline constexpr int kMinRealtimePriority = 1;
inline constexpr int kMaxRealtimePriority = 99;

/// What a request for realtime scheduling got.
struct RealtimeGrant {
  int requested = 0;           ///< the priority asked for (0: none asked)
  bool granted = false;        ///< SCHED_FIFO at `requested`
  bool memory_locked = false;  ///< mlockall(MCL_CURRENT | MCL_FUTURE) succeeded
  std::string reason;          ///< why not granted, or why memory is not locked ("" when all went through)
  /// One line: "realtime priority 50 granted (SCHED_FIFO, memory locked)",
  /// "realtime priority 50 not granted: ...; running at normal priority", or
  /// "realtime priority not requested".
  std::string Line() const;
};

/// Puts the calling thread on SCHED_FIFO at `priority` (1..99) and locks the
/// process's memory. priority 0 asks for nothing (granted false, no reason).
/// Throws std::invalid_argument for a priority outside 0..99.
RealtimeGrant RequestRealtime(int priority);

/// Puts the calling thread on SCHED_FIFO at `priority` (1..99), nothing else;
/// false (errno kept) when refused. For the threads that serve a realtime loop.
bool SetThreadRealtime(int priority);

/// Back to SCHED_OTHER for the calling thread, and unlocks memory if `grant`
/// locked it. Nothing when nothing was granted.
void DropRealtime(const RealtimeGrant& grant);

/// The scheduling of a process that vlab started (after its exec): its
/// SCHED_FIFO priority, 0 when it runs at normal priority, -1 when it cannot
/// be read (gone).
int ProcessRealtimePriority(int pid);

/// Why a SCHED_FIFO request at `priority` failed with `error` (an errno), for
/// people: what would grant it.
std::string RealtimeRefusal(int priority, int error);

}  // namespace vlab
