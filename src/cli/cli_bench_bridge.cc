// vlab bench bridge: what the wire costs, measured in one run.
//
// 1. Raw UDP echo round trip over loopback (a thread echoes 200-byte
//    datagrams back): the floor of any request/answer exchange.
// 2. Lockstep at 1 kHz: the PA10 served in lockstep, the C++ example
//    controller (examples/joint_control, a separate process) answering every
//    period over loopback; control periods per second, and the cost of one
//    period against the raw round trip (goal: <= 1.5x).
// 3. Realtime at 1 kHz for --realtime seconds (default 30) with the same
//    controller: missed deadlines (%), period-start lateness, and the latency
//    from a command's arrival to its application (goal: < 0.5 % missed).
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <thread>
#include <vector>

#include "bridge/bridge_udp.h"
#include "cli/cli_commands.h"
#include "core/core_errors.h"
#include "lab/lab_runner.h"
#include "lab/lab_scenario.h"
#include "lab/lab_stats.h"

namespace vlab::cli {

namespace {

namespace fs = std::filesystem;
using lab::Percentile;

// round trips (s) of `count` 200-byte datagrams to an echo thread on loopback
std::vector<double> EchoRoundTrips(int count) {
  auto echo = bridge::UdpSocket::Bind("127.0.0.1", 0);
  auto client = bridge::UdpSocket::Bind("127.0.0.1", 0);
  const bridge::Endpoint to = echo->local_endpoint();
  std::atomic<bool> stop{false};
  std::thread server([&] {
    unsigned char buf[2048];
    bridge::Endpoint from;
    while (!stop) {
      const long n = echo->Receive(buf, sizeof(buf), &from, 0.1);
      if (n > 0) echo->SendTo(buf, static_cast<std::size_t>(n), from);
    }
  });
  std::vector<unsigned char> packet(200, 0x5A);
  unsigned char buf[2048];
  std::vector<double> rtt;
  rtt.reserve(count);
  for (int i = 0; i < count + 100; ++i) {
    const double t0 = vlab::WallNow();
    client->SendTo(packet.data(), packet.size(), to);
    if (client->Receive(buf, sizeof(buf), nullptr, 1.0) < 0) continue;
    if (i >= 100) rtt.push_back(vlab::WallNow() - t0);  // the first 100 warm up
  }
  stop = true;
  server.join();
  return rtt;
}

// seconds of one bare physics step of the scenario's scene from its initial
// state, the joint motors holding the arm against gravity (ctrl = bias force)
double PhysicsStepSeconds(const lab::Scenario& scenario) {
  std::unique_ptr<lab::Lab> lab = lab::Lab::Create(scenario);
  const mjModel* m = lab->model();
  vlab::DataPtr data = vlab::MakeData(m);
  mjData* d = data.get();
  lab->InitialState(d);
  const int steps = 5000;
  const double t0 = vlab::WallNow();
  for (int i = 0; i < steps; ++i) {
    mj_step1(m, d);
    for (int a = 0; a < m->nu; ++a) {
      if (m->actuator_trntype[a] == mjTRN_JOINT) d->ctrl[a] = d->qfrc_bias[m->jnt_dofadr[m->actuator_trnid[2 * a]]];
    }
    mj_step2(m, d);
  }
  return (vlab::WallNow() - t0) / steps;
}

// the example controller, started as a child process
class Controller {
 public:
  Controller(const std::string& binary, int port, double seconds) {
    pid_ = fork();
    if (pid_ == 0) {
      const std::string arm = "127.0.0.1:" + std::to_string(port);
      const std::string duration = std::to_string(seconds);
      execl(binary.c_str(), binary.c_str(), "--arm", arm.c_str(), "--duration", duration.c_str(), "--quiet",
            static_cast<char*>(nullptr));
      _exit(127);
    }
  }
  ~Controller() {
    if (pid_ > 0) {
      kill(pid_, SIGTERM);
      waitpid(pid_, nullptr, 0);
    }
  }

 private:
  pid_t pid_ = -1;
};

std::string ExampleBinary() {
  const fs::path self = fs::read_symlink("/proc/self/exe");
  const fs::path example = self.parent_path() / "examples" / "joint_control";
  if (!fs::exists(example)) throw vlab::InputError("bench bridge: no example controller at " + example.string());
  return example.string();
}

lab::RunResult ServeWithController(lab::Scenario scenario, ClockMode clock, double seconds,
                                   const std::string& example) {
  scenario.duration_s = seconds;
  scenario.control_period_s = 0.001;  // 1 kHz: one physics step per period
  const int port = bridge::UdpSocket::Bind("127.0.0.1", 0)->local_port();
  // only the arm is served: the example controller uses nothing else
  for (auto& d : scenario.devices) d.port = 0;
  lab::BridgeOptions options;
  options.ports["pa10"] = port;
  std::unique_ptr<lab::Lab> lab = lab::Lab::Create(scenario);
  // the controller runs a little longer than the lab, so every period has its answer
  Controller controller(example, port, seconds + 5);
  lab::RunOptions run;
  run.serve = &options;
  run.clock = clock;
  return lab->Run(run);
}

}  // namespace

int BenchBridge(const BenchArgs& args) {
  return WithErrorReport([&args] {
    const std::string example = ExampleBinary();
    const lab::Scenario scenario =
        lab::LoadScenario(lab::ResolveScenarioPath(args.scenario.empty() ? "scenes/pa10_serve" : args.scenario));
    std::printf("vlab bench bridge: scenario %s, 1 kHz, controller %s\n", scenario.name.c_str(), example.c_str());

    const std::vector<double> rtt = EchoRoundTrips(5000);
    const double rtt_p50 = Percentile(rtt, 50);
    std::printf("  raw UDP echo round trip (200 B, loopback): p50 %.1f us, p99 %.1f us\n", rtt_p50 * 1e6,
                Percentile(rtt, 99) * 1e6);

    const double lockstep_s = args.duration_s > 0 ? args.duration_s : 5.0;
    const lab::RunResult ls = ServeWithController(scenario, ClockMode::kLockstep, lockstep_s, example);
    const double rate = ls.periods / ls.loop_wall_s;
    std::printf("  lockstep: %ld periods in %.2f s = %.0f periods/s, %.1f us a period (incl. 1 physics step)\n",
                ls.periods, ls.loop_wall_s, rate, 1e6 / rate);
    std::printf("  lockstep period / raw round trip = %.2f (goal <= 1.5) -> %s\n", (1.0 / rate) / rtt_p50,
                (1.0 / rate) / rtt_p50 <= 1.5 ? "met" : "NOT met");
    const double physics = PhysicsStepSeconds(scenario);
    std::printf("  of a period: physics step %.1f us (bare mj_step, arm held), the rest %.1f us = %.2f x the raw round trip\n",
                physics * 1e6, (1.0 / rate - physics) * 1e6, (1.0 / rate - physics) / rtt_p50);
    if (ls.exit_code != 0) std::printf("  (lockstep run: %s)\n", ls.failure.c_str());

    const double realtime_s = args.realtime_s;
    const lab::RunResult rt = ServeWithController(scenario, ClockMode::kRealtime, realtime_s, example);
    const auto& st = rt.clock_stats;
    const double missed = st.periods ? 100.0 * static_cast<double>(st.missed_deadlines) / st.periods : 0.0;
    std::printf("  realtime %.0f s: %ld periods, missed deadlines %ld (%.3f %%, goal < 0.5 %%) -> %s\n", realtime_s,
                static_cast<long>(st.periods), static_cast<long>(st.missed_deadlines), missed,
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
