// vlab bench realtime: does a 1 kHz realtime loop hold its deadlines beside
// served cameras, on a quiet machine and on a busy one?
//
// The PA10 of --scenario (default scenes/pa10_serve) holds at 1 kHz on the
// realtime clock, its arm not served (nothing to wait for), with N cameras
// served: MJCF camera `overview`, 640x480, 30 Hz, JPEG q90, fast profile, each rendered and
// encoded on its own worker thread (device_camera.h). N receivers in this
// process, one thread each, subscribe and count every frame. Three ways (four
// for 4 cameras), one after the other, for --duration seconds each (default 10):
//   quiet       nothing else runs;
//   loaded      two CPU-bound processes that the benchmark starts and stops,
//               at normal priority (both cores busy, as on a lab PC that is
//               also compiling), from the lab's first period to its last;
//   loaded, rt  the same load, the control thread at realtime priority 50
//               when permitted (SCHED_DEADLINE, else SCHED_FIFO 50: see
//               core_realtime.h; its workers at SCHED_FIFO 49); not measured,
//               and said so, when not.
//   rt, draft   (4 cameras) the same as loaded, rt, the cameras in the draft
//               profile (renderer.h: no sky, coarser round geoms): what a
//               machine that cannot render four fast frames in time can serve.
// Without priority the loop keeps a CPU (core_realtime.h) and each receiver,
// once its first frame is in, moves to the CPUs the camera workers run on, as a
// user would place a vision program. In the rows at priority a receiver
// subscribes at the workers' priority and then receives at normal priority.
// For each: missed deadlines (count and %), period-start lateness p50, p99,
// max; frames sent by the lab, received whole, lost (ids skipped between the
// first and the last received), torn (incomplete or undecodable), and late
// (sent after their stamp + latency), and how long the slowest receiver took to subscribe.
// Run for 2 cameras and for 4.
// Goals: < 0.5 % missed quiet, and loaded with priority; 0 frames lost or torn.
#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <future>
#include <stdexcept>
#include <thread>
#include <vector>

#include "bridge/bridge_camera_client.h"
#include "bridge/bridge_errors.h"
#include "cli/cli_commands.h"
#include "cli/cli_cpus.h"
#include "core/core_errors.h"
#include "core/core_realtime.h"
#include "lab/devices/device_camera.h"
#include "lab/outputs/lab_stats.h"
#include "lab/run/lab_runner.h"
#include "lab/scenario/lab_scenario.h"

namespace vlab::cli {

namespace {

using lab::Percentile;

constexpr int kPriority = 50;
// In the rows at priority the receivers subscribe at the camera workers' SCHED_FIFO priority (one
// below the loop's), then receive at normal priority. A receiver at normal priority that is not yet
// subscribed when the first cameras render (four fast ones keep both cores) waits for the kernel's
// realtime throttling to let normal threads run, 50 ms of each second
// (/proc/sys/kernel/sched_rt_runtime_us), shared with the load: in a full suite one waited through
// a whole 2 s row. At the workers' priority it waits at most for a worker to finish its frame.
constexpr int kSubscribePriority = kPriority - 1;

// what one receiver saw
struct Received {
  long frames = 0;  // whole frames
  long lost = 0;    // ids skipped between the first and the last whole frame
  long torn = 0;    // incomplete (dropped by the assembler) or undecodable
  bool connected = false;
  double subscribed_s = 0;  // from the lab's serving to the subscription
  std::string error;
};

using BenchClock = std::chrono::steady_clock;

// `at_priority`: the thread was made at kSubscribePriority, and goes to normal priority once subscribed
Received Receive(int port, bool at_priority, BenchClock::time_point serving, const std::atomic<bool>& run_over) {
  Received r;
  try {
    bridge::CameraClientOptions o;
    o.timeout_s = 5;
    o.decode = true;  // a torn JPEG shows as undecodable
    bridge::CameraClient client = bridge::CameraClient::Connect("127.0.0.1", port, o);
    if (at_priority) SetThreadNormal();
    r.connected = true;
    r.subscribed_s = std::chrono::duration<double>(BenchClock::now() - serving).count();
    std::int64_t first = -1, last = -1;
    for (;;) {
      bridge::CameraClient::Frame f;
      try {
        client.Receive(0.1, &f);  // (the run's end is seen within 0.1 s)
      } catch (const bridge::TimeoutError&) {
        if (run_over) break;
        continue;
      }
      if (first < 0) {
        first = f.id;
        // a client decoding frames at normal priority is placed off a CPU the lab's loop
        // keeps (by then it has kept it), as a user places a vision program (taskset)
        BindDeviceThread();
      }
      last = f.id;
      ++r.frames;
    }
    if (first >= 0) r.lost = (last - first + 1) - r.frames;
    r.torn = client.counters().frames_dropped + client.undecodable();
  } catch (const std::exception& e) {
    r.error = r.connected || !run_over ? e.what() : std::string("no subscription before the run's end: ") + e.what();
  }
  return r;
}

struct Way {
  const char* name;
  bool load;
  int priority;
  render::Profile profile = render::Profile::kFast;
};

// what one run measured: plain data, so that a child process can send it up a pipe
struct Figures {
  long periods = 0, missed = 0;
  double p50 = 0, p99 = 0, max = 0;      // period-start lateness, s
  long sent = 0, late = 0, dropped = 0;  // the lab's cameras
  long frames = 0, lost = 0, torn = 0;   // the receivers
  double subscribed_max_s = 0;           // the slowest receiver's subscription
  char note[512] = "";                   // a receiver's error or the run's failure
};

Figures RunOnce(lab::Scenario scenario, int cameras, const Way& way) {
  for (lab::DeviceConfig& d : scenario.devices) {
    if (d.kind == bridge::DeviceKind::kCamera) d.EditParams<lab::CameraParams>().profile = way.profile;
  }
  std::unique_ptr<lab::Lab> lab = lab::Lab::Create(scenario);
  lab::BridgeOptions bo;
  for (int i = 0; i < cameras; ++i) bo.ports["cam" + std::to_string(i)] = 0;  // free ports
  std::promise<std::vector<lab::ServedDevice>> served;
  lab::RunOptions ro;
  ro.serve = &bo;
  ro.clock = ClockMode::kRealtime;
  ro.realtime_priority = way.priority;
  // the load starts once the lab serves (its renderers and workers are up), just before its
  // first period: only the measured periods run beside it. The hogs are forked here, stopped,
  // before the run locks its memory (a fork then would make the loop's pages copy-on-write).
  std::vector<int> hogs;
  if (way.load) hogs = StartCpuHogs(2, true);
  BenchClock::time_point serving;
  ro.on_serving = [&](const std::vector<lab::ServedDevice>& d) {
    ResumeCpuHogs(hogs);
    serving = BenchClock::now();
    served.set_value(d);
  };
  lab::RunResult result;
  std::thread run([&] { result = lab->Run(ro); });
  const std::vector<lab::ServedDevice> devices = served.get_future().get();
  std::atomic<bool> run_over{false};
  std::vector<std::future<Received>> receivers;
  // (a thread starts with its maker's scheduling: this thread's, at priority only while it makes them)
  const bool at_priority = way.priority > 0 && SetThreadRealtime(kSubscribePriority);
  for (const lab::ServedDevice& d : devices) {
    if (d.kind != "camera") continue;
    receivers.push_back(std::async(std::launch::async, [port = d.port, at_priority, serving, &run_over] {
      return Receive(port, at_priority, serving, run_over);
    }));
  }
  if (at_priority) SetThreadNormal();
  run.join();
  run_over = true;
  StopCpuHogs(hogs);
  Figures f;
  std::string note;
  for (auto& r : receivers) {
    const Received got = r.get();
    f.frames += got.frames;
    f.lost += got.lost + (got.connected ? 0 : 1);
    f.torn += got.torn;
    f.subscribed_max_s = std::max(f.subscribed_max_s, got.subscribed_s);
    if (!got.error.empty() && note.empty()) note = "receiver: " + got.error;
  }
  for (const auto& d : result.served) {
    f.sent += d.frames.sent;
    f.late += d.frames.late;
    f.dropped += d.frames.dropped;
  }
  const auto& st = result.clock_stats;
  f.periods = st.periods;
  f.missed = st.missed_deadlines;
  f.p50 = Percentile(st.lateness_s, 50);
  f.p99 = Percentile(st.lateness_s, 99);
  f.max = st.max_lateness_s;
  if (note.empty() && result.exit_code != 0 && !result.interrupted_by) note = "run: " + result.failure;
  std::snprintf(f.note, sizeof(f.note), "%s", note.c_str());
  return f;
}

// each run in a child process of its own: its GL contexts, rasterizer threads and
// scheduling start afresh, as in a separate `vlab serve`
Figures RunInChild(const lab::Scenario& scenario, int cameras, const Way& way) {
  int fds[2];
  if (::pipe(fds) != 0) throw std::runtime_error("bench realtime: pipe failed");
  std::fflush(stdout);
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(fds[0]);
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    // quiet: the renderer's one line per process would repeat for every run (errors come in f.note)
    const int null = ::open("/dev/null", O_WRONLY);
    if (null >= 0) ::dup2(null, 2);
    Figures f;
    try {
      f = RunOnce(scenario, cameras, way);
    } catch (const std::exception& e) {
      std::snprintf(f.note, sizeof(f.note), "error: %s", e.what());
    }
    (void)!::write(fds[1], &f, sizeof(f));
    ::_exit(0);
  }
  ::close(fds[1]);
  Figures f;
  const ssize_t n = pid > 0 ? ::read(fds[0], &f, sizeof(f)) : -1;
  ::close(fds[0]);
  if (pid > 0) ::waitpid(pid, nullptr, 0);
  if (n != static_cast<ssize_t>(sizeof(f))) {
    f = Figures{};
    std::snprintf(f.note, sizeof(f.note), "the run's process ended without its figures");
  }
  return f;
}

double MissedPercent(const Figures& f) { return f.periods ? 100.0 * static_cast<double>(f.missed) / f.periods : 0.0; }

void Print(const char* name, const Figures& f) {
  std::printf("    %-11s missed %5ld of %ld (%6.3f %%); lateness p50 %7.1f us, p99 %8.1f us, max %8.1f us\n", name,
              f.missed, f.periods, MissedPercent(f), f.p50 * 1e6, f.p99 * 1e6, f.max * 1e6);
  std::printf(
      "    %-11s frames: %ld sent, %ld received whole, %ld lost, %ld torn, %ld late, %ld not rendered; "
      "subscribed within %.0f ms%s%s\n",
      "", f.sent, f.frames, f.lost, f.torn, f.late, f.dropped, f.subscribed_max_s * 1e3, f.note[0] ? "; " : "", f.note);
}

}  // namespace

int BenchRealtime(const BenchArgs& args) {
  return WithErrorReport([&args] {
    lab::Scenario base =
        lab::LoadScenario(lab::ResolveScenarioPath(args.scenario.empty() ? "scenes/pa10_serve" : args.scenario));
    const double duration = args.duration_s > 0 ? args.duration_s : 10.0;
    base.duration_s = duration;
    base.control_period_s = 0.001;  // 1 kHz
    base.clock = ClockMode::kRealtime;
    base.lockstep.start_timeout_s = 1.0;
    base.checks.clear();
    base.outputs.plots.clear();
    base.outputs.images.clear();
    base.controller = lab::ControllerConfig{};
    for (lab::DeviceConfig& d : base.devices) d.port = 0;  // nothing else served: nothing to wait for
    const std::vector<int> allowed = ThreadCpus();
    std::printf(
        "vlab bench realtime: scenario %s at 1 kHz (realtime clock, arm holding), cameras 640x480 at 30 Hz\n"
        "  (MJCF camera 'overview', JPEG q90, fast profile unless named, each rendered and encoded on its own\n"
        "  worker), %.0f s each way\n",
        base.name.c_str(), duration);
    std::printf("  CPUs: %zu allowed (%s) of %ld online\n", allowed.size(), CpuListText(allowed).c_str(),
                sysconf(_SC_NPROCESSORS_ONLN));
    // may this process have SCHED_FIFO? asked on a scratch thread, given back at once
    RealtimeGrant probe;
    std::thread([&probe] {
      probe = RequestRealtime(kPriority, false, 0.001);  // (as the loop asks: a 1 ms period)
      DropRealtime(probe);
    }).join();
    std::printf("  load: 2 CPU-bound processes at normal priority, started and stopped here\n");
    std::printf("  priority: %s\n", probe.Line().c_str());
    const Way ways[] = {{"quiet", false, 0},
                        {"loaded", true, 0},
                        {"loaded, rt", true, kPriority},
                        {"rt, draft", true, kPriority, render::Profile::kDraft}};
    for (const int cameras : {2, 4}) {
      lab::Scenario scenario = base;
      for (int i = 0; i < cameras; ++i) {
        lab::DeviceConfig c;
        c.name = "cam" + std::to_string(i);
        c.kind = bridge::DeviceKind::kCamera;
        lab::CameraParams& p = c.EditParams<lab::CameraParams>();
        p.camera = "overview";
        p.width = 640;
        p.height = 480;
        p.fps = 30;
        scenario.devices.push_back(c);
      }
      std::printf("  %d cameras:\n", cameras);
      for (const Way& way : ways) {
        if (way.profile != render::Profile::kFast && cameras < 4) continue;  // (2 fast ones keep up)
        if (way.priority > 0 && !probe.granted) {
          std::printf("    %-11s not measured: %s\n", way.name, probe.reason.c_str());
          continue;
        }
        const Figures f = RunInChild(scenario, cameras, way);
        Print(way.name, f);
        if (!way.load || way.priority > 0) {
          const bool whole = f.lost == 0 && f.torn == 0 && f.dropped == 0 && f.frames > 0;
          std::printf("    %-11s goals: missed < 0.5 %% -> %s; 0 frames lost or torn -> %s\n", "",
                      MissedPercent(f) < 0.5 ? "met" : "NOT met", whole ? "met" : "NOT met");
        }
      }
    }
    return 0;
  });
}

}  // namespace vlab::cli
