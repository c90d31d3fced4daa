// vlab bench bridge: what the wire costs, measured in one run, like for like.
//
// The lab and its controller are two processes, and the lab waits for an
// answer as LabBridge::Poll does: it spins 200 us, then sleeps in ppoll; the
// example controller sleeps in ppoll. Where the two run matters as much as the
// wire (a sleeping peer on another core wakes slowly), so every figure below is
// measured in the same layouts: both on one core, each on a core of its own
// (both pinned), and unpinned (where the scheduler puts them).
//
// 0. The CPUs this process may use (sched_getaffinity) and the CPUs online.
// 1. Raw UDP echo round trip over loopback, per layout: a child process
//    echoes 200-byte datagrams, waiting as the client library does (polls
//    kClientSpin_s, then ppoll); this process waits as the lab does. Both
//    sides poll: the busy-poll floor of a request/answer exchange in that layout.
// 2. Lockstep at 1 kHz, per layout: the PA10 served in lockstep, the C++
//    example controller (examples/joint_control, a child process) answering
//    every period over loopback; the period's p50 (timed at each period's
//    end) against that layout's echo p50 (goal: <= 1.5x, judged where both
//    sides are pinned), and the exchange (the period less one bare physics
//    step) against it (goal: <= 2x); the mean period beside it.
// 3. Realtime at 1 kHz for --realtime seconds (default 30), unpinned, with the
//    same controller: missed deadlines (%), period-start lateness, and the
//    latency from a command's arrival to its application (goal: < 0.5 % missed).
#include <sched.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "bridge/bridge_client.h"
#include "bridge/bridge_udp.h"
#include "cli/cli_commands.h"
#include "cli/cli_cpus.h"
#include "core/core_errors.h"
#include "core/core_realtime.h"
#include "lab/outputs/lab_stats.h"
#include "lab/run/lab_runner.h"
#include "lab/scenario/lab_scenario.h"

namespace vlab::cli {

namespace {

namespace fs = std::filesystem;
using lab::Percentile;

// how long the lab spins before it sleeps, s (LabBridge::Poll's kSpinSeconds)
constexpr double kLabSpinSeconds = 200e-6;

// where the lab (this process) and its peer (a child process) run
struct Layout {
  std::string name;
  std::vector<int> lab_cpus;   // empty: unpinned
  std::vector<int> peer_cpus;  // empty: unpinned
  // "same core  (lab cpu 0, peer cpu 0)"; unpinned: the CPUs both may use
  std::string Text(const std::vector<int>& allowed) const {
    std::string text = name + std::string(name.size() < 10 ? 10 - name.size() : 0, ' ');
    if (lab_cpus.empty()) return text + " (lab and peer on cpus " + CpuListText(allowed) + ")";
    return text + " (lab cpu " + CpuListText(lab_cpus) + ", peer cpu " + CpuListText(peer_cpus) + ")";
  }
};

// same core and cross core where there are the cores for them, then unpinned
std::vector<Layout> Layouts(const std::vector<int>& allowed) {
  std::vector<Layout> layouts;
  if (!allowed.empty()) layouts.push_back({"same core", {allowed[0]}, {allowed[0]}});
  if (allowed.size() >= 2) layouts.push_back({"cross core", {allowed[0]}, {allowed[1]}});
  layouts.push_back({"unpinned", {}, {}});
  return layouts;
}

// a forked child: pinned to `cpus`, killed with its parent; runs `body` and exits
template <typename Body>
pid_t ForkPeer(const std::vector<int>& cpus, Body body) {
  const pid_t pid = fork();
  if (pid == 0) {
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    BindThread(0, cpus);
    body();
    _exit(127);
  }
  return pid;
}

void StopPeer(pid_t pid) {
  if (pid <= 0) return;
  kill(pid, SIGTERM);
  waitpid(pid, nullptr, 0);
}

// one datagram on `socket`, waited for as LabBridge::Poll waits: spin, then ppoll
long ReceiveAsLab(bridge::UdpSocket& socket, unsigned char* buf, std::size_t size, double timeout_s) {
  const int fd = socket.fd();
  const double spin_until = vlab::WallNow() + kLabSpinSeconds;
  bool ready = false;
  do {
    ready = bridge::WaitReadable(&fd, 1, 0.0);
    if (!ready) sched_yield();
  } while (!ready && vlab::WallNow() < spin_until);
  if (!ready && !bridge::WaitReadable(&fd, 1, timeout_s - kLabSpinSeconds)) return -1;
  return socket.Receive(buf, size, nullptr, 0.0);
}

// round trips (s) of `count` 200-byte datagrams to an echo peer in a child
// process that blocks in ppoll (as the example controller does), this process
// waiting as the lab does, in `layout`
std::vector<double> EchoRoundTrips(int count, const Layout& layout) {
  auto echo = bridge::UdpSocket::Bind("127.0.0.1", 0);
  auto client = bridge::UdpSocket::Bind("127.0.0.1", 0);
  const bridge::Endpoint to = echo->local_endpoint();
  const pid_t peer = ForkPeer(layout.peer_cpus, [&echo] {
    unsigned char buf[2048];
    bridge::Endpoint from;
    for (;;) {
      // as the client library waits: poll for kClientSpin_s, yielding, then sleep
      const double spin_until = vlab::WallNow() + bridge::kClientSpin_s;
      long n = echo->Receive(buf, sizeof(buf), &from, 0.0);
      while (n < 0 && vlab::WallNow() < spin_until) {
        sched_yield();
        n = echo->Receive(buf, sizeof(buf), &from, 0.0);
      }
      if (n < 0) n = echo->Receive(buf, sizeof(buf), &from, 1.0);
      if (n > 0) echo->SendTo(buf, static_cast<std::size_t>(n), from);
    }
  });
  const std::vector<int> all = ThreadCpus();
  BindThread(0, layout.lab_cpus);
  std::vector<unsigned char> packet(200, 0x5A);
  unsigned char buf[2048];
  std::vector<double> rtt;
  rtt.reserve(count);
  for (int i = 0; i < count + 100; ++i) {
    const double t0 = vlab::WallNow();
    client->SendTo(packet.data(), packet.size(), to);
    if (ReceiveAsLab(*client, buf, sizeof(buf), 1.0) < 0) continue;
    if (i >= 100) rtt.push_back(vlab::WallNow() - t0);  // the first 100 warm up
  }
  BindThread(0, all);
  StopPeer(peer);
  return rtt;
}

// seconds of one bare physics step (p50 of 5000) of the scenario's scene from
// its initial state, the joint motors holding the arm against gravity (ctrl =
// bias force), on `cpus`
double PhysicsStepSeconds(const lab::Scenario& scenario, const std::vector<int>& cpus) {
  std::unique_ptr<lab::Lab> lab = lab::Lab::Create(scenario);
  const mjModel* m = lab->model();
  vlab::DataPtr data = vlab::MakeData(m);
  mjData* d = data.get();
  lab->InitialState(d);
  const std::vector<int> all = ThreadCpus();
  BindThread(0, cpus);
  std::vector<double> steps(5000);
  for (double& step : steps) {
    const double t0 = vlab::WallNow();
    mj_step1(m, d);
    for (int a = 0; a < m->nu; ++a) {
      if (m->actuator_trntype[a] == mjTRN_JOINT) d->ctrl[a] = d->qfrc_bias[m->jnt_dofadr[m->actuator_trnid[2 * a]]];
    }
    mj_step2(m, d);
    step = vlab::WallNow() - t0;
  }
  BindThread(0, all);
  return Percentile(steps, 50);
}

std::string ExampleBinary() {
  const fs::path self = fs::read_symlink("/proc/self/exe");
  const fs::path example = self.parent_path() / "examples" / "joint_control";
  if (!fs::exists(example)) throw vlab::InputError("bench bridge: no example controller at " + example.string());
  return example.string();
}

// the scenario served at 1 kHz for `seconds`, the example controller (a child
// process) driving the arm, in `layout`; `periods_s` (if given) gets the wall
// time of every period but the first
lab::RunResult ServeWithController(lab::Scenario scenario, ClockMode clock, double seconds, const std::string& example,
                                   const Layout& layout, std::vector<double>* periods_s = nullptr) {
  scenario.duration_s = seconds;
  scenario.control_period_s = 0.001;  // 1 kHz: one physics step per period
  const int port = bridge::UdpSocket::Bind("127.0.0.1", 0)->local_port();
  // only the arm is served: the example controller uses nothing else
  for (auto& d : scenario.devices) d.port = 0;
  lab::BridgeOptions options;
  options.ports["pa10"] = port;
  const std::vector<int> all = ThreadCpus();
  BindThread(0, layout.lab_cpus);
  std::unique_ptr<lab::Lab> lab = lab::Lab::Create(scenario);
  // the controller runs a little longer than the lab, so every period has its answer
  const std::string arm = "127.0.0.1:" + std::to_string(port);
  const std::string duration = std::to_string(seconds + 5);
  const pid_t controller = ForkPeer(layout.peer_cpus.empty() ? all : layout.peer_cpus, [&] {
    execl(example.c_str(), example.c_str(), "--arm", arm.c_str(), "--duration", duration.c_str(), "--quiet",
          static_cast<char*>(nullptr));
  });
  lab::RunOptions run;
  run.serve = &options;
  run.clock = clock;
  std::vector<double> ends;  // wall time at the end of each period's step
  ends.reserve(static_cast<std::size_t>(seconds * 1000) + 2);
  if (periods_s) {
    run.observe = [&ends](double, const mjModel*, mjData*) {
      if (ends.size() < ends.capacity()) ends.push_back(vlab::WallNow());
    };
  }
  lab::RunResult result = lab->Run(run);
  if (periods_s) {
    for (std::size_t i = 1; i < ends.size(); ++i) periods_s->push_back(ends[i] - ends[i - 1]);
  }
  StopPeer(controller);
  BindThread(0, all);
  return result;
}

}  // namespace

int BenchBridge(const BenchArgs& args) {
  return WithErrorReport([&args] {
    const std::string example = ExampleBinary();
    const lab::Scenario scenario =
        lab::LoadScenario(lab::ResolveScenarioPath(args.scenario.empty() ? "scenes/pa10_serve" : args.scenario));
    std::printf("vlab bench bridge: scenario %s, 1 kHz, controller %s\n", scenario.name.c_str(), example.c_str());
    const std::vector<int> allowed = ThreadCpus();
    std::printf("  CPUs: %zu allowed (%s) of %ld online\n", allowed.size(), CpuListText(allowed).c_str(),
                sysconf(_SC_NPROCESSORS_ONLN));
    std::printf(
        "  the lab waits as it does when serving (spin %.0f us, then ppoll); its peer, a child process,\n"
        "  waits as the client library does (polls %.0f us, yielding, then ppoll): within the spins both\n"
        "  sides busy-poll, so the echo is the busy-poll round trip\n",
        kLabSpinSeconds * 1e6, bridge::kClientSpin_s * 1e6);
    const std::vector<Layout> layouts = Layouts(allowed);
    if (allowed.size() < 2) std::printf("  cross core: not measured (one CPU allowed)\n");

    std::printf("  raw UDP echo round trip (200 B, loopback), the floor of a request/answer exchange:\n");
    std::vector<double> floors;
    for (const Layout& layout : layouts) {
      const std::vector<double> rtt = EchoRoundTrips(5000, layout);
      floors.push_back(Percentile(rtt, 50));
      std::printf("    %-42s p50 %6.1f us, p99 %7.1f us\n", layout.Text(allowed).c_str(), floors.back() * 1e6,
                  Percentile(rtt, 99) * 1e6);
    }
    const double physics = PhysicsStepSeconds(scenario, layouts.front().lab_cpus);
    std::printf("  physics step: p50 %.1f us (bare mj_step, arm held, cpu %s)\n", physics * 1e6,
                CpuListText(layouts.front().lab_cpus).c_str());

    const double lockstep_s = args.duration_s > 0 ? args.duration_s : 5.0;
    std::printf(
        "  lockstep, %.0f periods: the wall time of a period, p50 and mean; ratio = period p50 / that\n"
        "  layout's echo p50 (goal <= 1.5); the exchange = the period p50 less the physics step, against\n"
        "  the echo p50 (goal <= 2):\n",
        lockstep_s * 1000);
    for (std::size_t i = 0; i < layouts.size(); ++i) {
      std::vector<double> periods;
      const lab::RunResult ls =
          ServeWithController(scenario, ClockMode::kLockstep, lockstep_s, example, layouts[i], &periods);
      const double period = Percentile(periods, 50);
      const double ratio = period / floors[i];
      // unpinned, the echo and the lockstep run may have been placed differently: no verdict
      const char* verdict = layouts[i].lab_cpus.empty() ? "not judged" : ratio <= 1.5 ? "met" : "NOT met";
      const double exchange = (period - physics) / floors[i];
      const char* exchange_verdict = layouts[i].lab_cpus.empty() ? "not judged" : exchange <= 2 ? "met" : "NOT met";
      std::printf("    %-42s p50 %6.1f us, mean %6.1f us; ratio %.2f -> %s; exchange %.1f us = %.2fx -> %s\n",
                  layouts[i].Text(allowed).c_str(), period * 1e6,
                  ls.loop_wall_s / static_cast<double>(std::max(ls.periods, 1L)) * 1e6, ratio, verdict,
                  (period - physics) * 1e6, exchange, exchange_verdict);
      if (ls.clock_stats.timeouts > 0) {
        std::printf("    (%ld periods began without their command)\n", static_cast<long>(ls.clock_stats.timeouts));
      }
      if (ls.exit_code != 0) std::printf("    (lockstep run: %s)\n", ls.failure.c_str());
    }
    if (allowed.size() > 1) {
      std::printf("  (unpinned is not judged: the echo and the lockstep run may each land on one core or on two)\n");
    }

    const double realtime_s = args.realtime_s;
    const lab::RunResult rt = ServeWithController(scenario, ClockMode::kRealtime, realtime_s, example, layouts.back());
    const auto& st = rt.clock_stats;
    const double missed = st.periods ? 100.0 * static_cast<double>(st.missed_deadlines) / st.periods : 0.0;
    std::printf("  realtime %.0f s, unpinned: %ld periods, missed deadlines %ld (%.3f %%, goal < 0.5 %%) -> %s\n",
                realtime_s, static_cast<long>(st.periods), static_cast<long>(st.missed_deadlines), missed,
                missed < 0.5 ? "met" : "NOT met");
    std::printf("  realtime period-start lateness: p50 %.1f us, p99 %.1f us, max %.1f us\n",
                Percentile(st.lateness_s, 50) * 1e6, Percentile(st.lateness_s, 99) * 1e6, st.max_lateness_s * 1e6);
    std::printf("  command arrival-to-apply latency (%zu commands): p50 %.1f us, p99 %.1f us, max %.1f us\n",
                rt.latencies_s.size(), Percentile(rt.latencies_s, 50) * 1e6, Percentile(rt.latencies_s, 99) * 1e6,
                rt.latencies_s.empty() ? NAN : *std::max_element(rt.latencies_s.begin(), rt.latencies_s.end()) * 1e6);
    return 0;
  });
}

}  // namespace vlab::cli
