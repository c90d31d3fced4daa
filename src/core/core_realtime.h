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
// Priorities are SCHED_FIFO's 1 (lowest) to 99; 0 asks for no SCHED_FIFO. The
// kernel's realtime throttling (/proc/sys/kernel/sched_rt_runtime_us, 95 % by
// default) still leaves the rest of the machine a share of every second.
//
// Without SCHED_FIFO (not asked, or refused) the thread asks for a short slice of
// the fair scheduler instead, which needs no privilege. Since Linux 6.6 the fair
// scheduler is EEVDF; a running thread keeps the core until its slice (3 ms by
// default) is used ("run to parity"), so a loop thread that wakes for its deadline
// waited up to that long behind a camera worker, whatever the worker's nice
// value. Since 6.12 a thread may ask for its own slice (sched_setattr's
// sched_runtime, 0.1 to 100 ms), and a waking thread with a shorter slice than
// the running one preempts it at once. The slice does not change a thread's share
// of the CPU, only when it gets it. Older kernels ignore the request; the grant
// then says so.
//
// A short slice is not enough beside threads that render: a loop thread woken
// for its deadline was still queued behind a camera worker (or a client
// decoding its frames) on its own CPU for up to a 4 ms tick while the other CPU
// sat idle, whatever the worker's nice value; 1.2-2.4 % of a 1 kHz loop's
// deadlines were missed beside two 30 Hz cameras on 2 CPUs (vlab bench
// realtime, quiet). So a loop thread without SCHED_FIFO may keep a CPU for
// itself (keep_cpu): it binds itself to the CPU it runs on, and the threads
// that serve its devices (BindDeviceThread) run on the other allowed CPUs; the
// same bench then missed 0.12 %. Other processes still share that CPU; a
// client placed on the other CPUs (taskset) leaves it to the loop. With
// SCHED_FIFO no CPU is kept: the priority does the work, and the devices'
// threads keep every CPU (four cameras need them).
//
// A periodic loop (the realtime clock: RequestRealtime's period_s) that may
// have SCHED_FIFO asks for SCHED_DEADLINE next: kDeadlineShare of each period,
// due by the period's end. The kernel keeps a share of every CPU for normal
// threads (its fair server, 50 ms of each second, which replaced realtime
// throttling in Linux 6.12): when realtime threads keep a CPU busy, the starved
// normal threads run for up to 50 ms at once, above every SCHED_FIFO priority.
// Four 30 Hz cameras' workers at SCHED_FIFO do that on 2 CPUs, and a SCHED_FIFO
// loop then waited 50 ms (1-4 % of deadlines missed in most runs of vlab bench
// realtime); a SCHED_DEADLINE loop's deadline comes first (0.00-0.06 %).
// Its device threads run at SCHED_FIFO one below the priority asked for, as
// under a SCHED_FIFO loop, and so do the programs vlab starts when asked. The
// kernel grants SCHED_DEADLINE to root or CAP_SYS_NICE (not to an rtprio
// limit), to a thread allowed on every CPU, and while its admission test
// leaves room; refused, the loop stays at SCHED_FIFO and the grant says why.
//
// A periodic loop granted SCHED_FIFO also keeps the CPUs out of deep idle states
// for as long as it holds its grant: it writes 0 us to /dev/cpu_dma_latency (the
// kernel's PM QoS request, as cyclictest does) and keeps the file open. A CPU
// that went idle between two periods otherwise takes its wake-up latency on the
// next one: on a virtual machine (cpuidle-haltpoll) an idle vCPU halts and is
// handed back to the host, and the loop, its camera worker or the controller it
// serves then woke 1-20 ms late, on a quiet machine more often than on a busy
// one (whose CPUs never idle). Yo-yo stage 3 on 2 vCPUs, quiet: 11-26 of 4600
// periods without the controller's command and 3-14 late webcam frames per run
// without the hold; 0-1 and 0 with it. Idle CPUs then poll instead of sleeping
// (they draw power, and on a VM keep their host CPU busy) until the loop ends.
// Only root may open the file; refused, the grant says why and the loop goes on.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

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
  /// Without SCHED_FIFO: the fair scheduler's slice now in force for the thread, ns
  /// (kLoopSlice_ns when the kernel took the request), 0 where the kernel keeps no
  /// per-thread slice (before Linux 6.12) or a SCHED_FIFO thread needs none.
  std::uint64_t slice_ns = 0;
  /// Without SCHED_FIFO, asked to keep a CPU (RequestRealtime's keep_cpu) with
  /// two or more allowed: the CPU the thread is bound to, -1 otherwise.
  int loop_cpu = -1;
  /// The CPUs the device threads run on (the allowed ones but loop_cpu); empty
  /// when loop_cpu is -1.
  std::vector<int> device_cpus;
  /// The CPUs the thread was allowed before (restored by DropRealtime).
  std::vector<int> allowed_cpus;
  /// SCHED_DEADLINE (granted, asked with a period): the runtime and period, ns;
  /// 0 when the thread is at SCHED_FIFO.
  std::uint64_t deadline_runtime_ns = 0;
  std::uint64_t deadline_period_ns = 0;
  /// Why SCHED_DEADLINE was refused when asked (the thread is at SCHED_FIFO).
  std::string deadline_refused;
  /// The CPUs are kept out of deep idle states (/dev/cpu_dma_latency held at 0 us,
  /// above) until DropRealtime; asked for by a periodic loop granted SCHED_FIFO.
  bool wake_latency_held = false;
  /// Why that was refused when asked ("" otherwise).
  std::string wake_latency_refused;
  /// One line: "realtime priority 50 granted (SCHED_FIFO, memory locked)",
  /// "realtime priority 50 not granted: ...; running at normal priority", or
  /// "realtime priority not requested".
  std::string Line() const;
};

/// The fair-scheduler slice a loop thread asks for without SCHED_FIFO: the
/// kernel's smallest (0.1 ms).
inline constexpr std::uint64_t kLoopSlice_ns = 100'000;

/// A SCHED_DEADLINE loop's runtime, as a share of its period.
inline constexpr double kDeadlineShare = 0.9;

/// Puts the calling thread on SCHED_FIFO at `priority` (1..99) and locks the
/// process's memory. priority 0 asks for no SCHED_FIFO (granted false, no
/// reason). Without SCHED_FIFO, the thread asks for a kLoopSlice_ns slice (above),
/// and with `keep_cpu` keeps the CPU it runs on for itself when two or more are
/// allowed: later BindDeviceThread calls put device threads on the others.
/// With SCHED_FIFO granted and `period_s` > 0 (a loop with that period), it
/// then asks for SCHED_DEADLINE (above), and stays at SCHED_FIFO if refused,
/// and holds the CPUs' wake-up latency at 0 (above).
/// Throws std::invalid_argument for a priority outside 0..99.
RealtimeGrant RequestRealtime(int priority, bool keep_cpu = false, double period_s = 0);

/// The priority asked for by the SCHED_DEADLINE loop of this process (its
/// device threads run one below it, at SCHED_FIFO); 0 when there is none.
/// Threads a SCHED_DEADLINE thread makes start at normal priority, so they
/// ask here instead of reading their own.
int DeadlineLoopPriority();

/// Where a device thread runs while a loop keeps a CPU.
struct DeviceCpus {
  std::vector<int> device;   ///< the CPUs it is bound to (empty: no CPU is kept, nothing bound)
  std::vector<int> allowed;  ///< every CPU the loop was allowed (for threads given back)
};
/// Binds the calling thread (a device's worker) to the device CPUs of the
/// last grant of this process that kept a CPU, and says which; nothing, and
/// empty lists, when no CPU is kept.
DeviceCpus BindDeviceThread();

/// Holds /dev/cpu_dma_latency at 0 us (above) while any holder of this process
/// holds it: true when held (the first holder opens the file), false with
/// *error set when refused. Each true is paired with one ReleaseWakeLatency.
bool HoldWakeLatency(std::string* error);
void ReleaseWakeLatency();

/// The CPUs the calling thread may run on, ascending.
std::vector<int> ThreadCpus();

/// Binds thread `tid` (0: the calling thread) to `cpus`; false when refused.
/// Threads and processes it starts later inherit the binding.
bool BindThread(int tid, const std::vector<int>& cpus);

/// "0,1".
std::string CpuListText(const std::vector<int>& cpus);

/// Puts the calling thread on SCHED_FIFO at `priority` (1..99), nothing else;
/// false (errno kept) when refused. For the threads that serve a realtime loop.
bool SetThreadRealtime(int priority);

/// Back to SCHED_OTHER for the calling thread (its nice value kept), nothing else: the
/// counterpart of SetThreadRealtime.
void SetThreadNormal();

/// Back to SCHED_OTHER with the default slice for the calling thread, and
/// unlocks memory if `grant` locked it; a kept CPU is given back (the thread
/// may run on its allowed CPUs again, and device threads bound later stay
/// where they are); the CPUs' wake-up latency is let go when no other grant of
/// the process holds it. Nothing when nothing was granted.
void DropRealtime(const RealtimeGrant& grant);

/// Asks the fair scheduler for a slice of `ns` (0: the default) for the calling
/// thread, keeping its nice value; returns the slice now in force (ns), read
/// back from the kernel: 0 where it keeps no per-thread slice (before 6.12).
std::uint64_t SetThreadSlice(std::uint64_t ns);

/// The calling thread's fair-scheduler slice (ns), 0 where the kernel has none.
std::uint64_t ThreadSlice();

/// The scheduling of a process that vlab started (after its exec): its
/// SCHED_FIFO priority, 0 when it runs at normal priority, -1 when it cannot
/// be read (gone).
int ProcessRealtimePriority(int pid);

/// Why a SCHED_FIFO request at `priority` failed with `error` (an errno), for
/// people: what would grant it.
std::string RealtimeRefusal(int priority, int error);

}  // namespace vlab
