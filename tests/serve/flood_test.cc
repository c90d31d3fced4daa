// vlab serve under a flood: 64 source ports send describe requests,
// subscribe requests with wrong cookies and valid-looking commands to the
// arm while a lockstep controller runs 3000 periods. The controller keeps the
// arm: it answers every period, and its log is byte for byte the log of an
// unflooded run. Every flood datagram is accounted for in the arm's counters,
// and the flood's sources get nothing back but challenges no larger than
// their requests: no state, no describe reply (what a spoofed source address
// would make a victim receive).
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <fstream>
#include <memory>
#include <sstream>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "bridge/bridge_client.h"
#include "bridge/bridge_session.h"
#include "serve/serve_process.h"
#include "test_util.h"

namespace vlab::testing {
namespace {

constexpr long kPeriods = 3000;  // scenes/pa10_serve.yaml: 500 Hz, 6 s
constexpr int kFloodPorts = 64;
constexpr double kFloodRound_s = 0.004;  // each flood port sends one datagram per round: up to 16000 per second

// drops the kernel counted for a UDP socket bound to 127.0.0.1:port (/proc/net/udp), -1 if not found
long KernelDrops(int port) {
  std::ifstream in("/proc/net/udp");
  std::string line;
  std::getline(in, line);  // header
  char local[64];
  std::snprintf(local, sizeof local, "0100007F:%04X", port);
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::vector<std::string> f;
    for (std::string x; fields >> x;) f.push_back(x);
    if (f.size() >= 13 && f[1] == local) return std::stol(f.back());
  }
  return -1;
}

struct Flood {
  long sent = 0, sent_bytes = 0, commands = 0, requests = 0;
  long received = 0, received_bytes = 0, not_challenges = 0;
  std::vector<std::unique_ptr<bridge::UdpSocket>> ports;  // the 64 source ports, read once the lab has ended
};

// reads what has come back to the flood's ports (without waiting): a port's queue holds only
// about 256 datagrams, so the flood reads its replies every round and once the lab has ended
void ReadFloodReplies(Flood* out) {
  std::vector<unsigned char> buffer(65536);
  for (auto& p : out->ports) {
    for (long n; (n = p->Receive(buffer.data(), buffer.size(), nullptr, 0.0)) >= 0;) {
      ++out->received;
      out->received_bytes += n;
      if (!bridge::IsSessionReply(buffer.data(), static_cast<std::size_t>(n))) ++out->not_challenges;
    }
  }
}

// what the flood's 64 ports send, round after round, until `stop`
void RunFlood(int arm_port, const std::atomic<bool>& stop, Flood* out) {
  const bridge::Endpoint arm = bridge::UdpSocket::MakeEndpoint("127.0.0.1", arm_port);
  std::vector<std::unique_ptr<bridge::UdpSocket>>& ports = out->ports;
  for (int i = 0; i < kFloodPorts; ++i) ports.push_back(bridge::UdpSocket::Bind("127.0.0.1", 0));
  std::vector<unsigned char> packet;
  bridge::ArmCommandMsg command{2, std::vector<double>(7, 0.1)};
  for (long round = 0; !stop; ++round) {
    for (int i = 0; i < kFloodPorts; ++i) {
      switch ((round + i) % 3) {
        case 0:
          bridge::EncodeDescribeRequest(static_cast<int>(bridge::DeviceKind::kArm), 0, &packet);
          break;
        case 1:
          bridge::EncodeSubscribeRequest(bridge::DeviceKind::kArm, 1000 + round, 1, &packet);
          break;
        default:
          bridge::EncodeArmCommand(static_cast<double>(round), 0, command, &packet);
          break;
      }
      ((round + i) % 3 == 2 ? out->commands : out->requests) += 1;
      ++out->sent;
      out->sent_bytes += static_cast<long>(packet.size());
      ports[static_cast<std::size_t>(i)]->SendTo(packet.data(), packet.size(), arm);
    }
    ReadFloodReplies(out);
    std::this_thread::sleep_for(std::chrono::duration<double>(kFloodRound_s));  // pacing the sender
  }
}

struct LabRun {
  std::string log;
  nlohmann::json arm;  // the arm's entry of summary.json's bridge.devices
  nlohmann::json summary;
  Flood flood;
  long drops = -1;
};

// one lockstep run with a controller holding the arm near its start pose (a
// velocity servo), with or without the flood
LabRun RunLab(bool flooded) {
  TempDir tmp;
  const int arm_port = FreeUdpPort();
  ServeProcess serve("scenes/pa10_serve --duration 6 --port pa10=" + std::to_string(arm_port) +
                         " --port jr3=0 --port sim=0 --out '" + (tmp / "out") + "'",
                     tmp.path());
  LabRun run;
  EXPECT_TRUE(serve.WaitStarted()) << serve.Output() << serve.Errors();
  std::atomic<bool> stop{false};
  std::thread flood;
  if (flooded) flood = std::thread(RunFlood, arm_port, std::cref(stop), &run.flood);
  {  // (the controller leaves after the lab has ended: its unsubscribe is not counted)
    bridge::Arm arm = bridge::Arm::Connect("127.0.0.1", arm_port, 10.0);
    bridge::Arm::State s;
    Eigen::VectorXd q0, qd;
    for (long k = 0; k < kPeriods; ++k) {
      arm.Read(10.0, &s);
      EXPECT_EQ(s.seq, k) << "one state per period, in order";
      if (s.seq != k) break;
      if (k == 0) q0 = s.q;
      qd = (-5.0 * (s.q - q0)).cwiseMax(-0.5).cwiseMin(0.5);
      if (k == 100) arm.Write(bridge::ArmMode::kVelocity, qd, std::int64_t{1} << 53);  // from the future
      arm.Write(bridge::ArmMode::kVelocity, qd, s.seq);
      if (flooded && k == kPeriods - 100) {  // the flood ends: count what the kernel dropped
        stop = true;
        flood.join();
        run.drops = KernelDrops(arm_port);
      }
    }
    EXPECT_EQ(serve.Wait(), 0) << serve.Output() << serve.Errors();
  }
  // the last replies: once the lab has exited, every one it sent is queued on the flood's ports
  // (loopback delivers a datagram as it is sent)
  if (flooded) ReadFloodReplies(&run.flood);
  run.log = ReadFile(tmp / "out/log.csv");
  run.summary = nlohmann::json::parse(ReadFile(tmp / "out/summary.json"));
  for (const auto& d : run.summary.at("bridge").at("devices")) {
    if (d.at("name") == "pa10") run.arm = d;
  }
  return run;
}

TEST(ServeFloodTest, AControllerKeepsItsArmThroughAFloodOf64Ports) {
  const LabRun quiet = RunLab(false);
  const LabRun flooded = RunLab(true);
  const Flood& f = flooded.flood;
  ASSERT_GT(f.sent, 2 * kFloodPorts);
  ASSERT_GE(flooded.drops, 0) << "no socket of the arm in /proc/net/udp";

  // the controller kept the arm: every period answered, the same log byte for byte
  EXPECT_EQ(Lines(flooded.log).size(), 1u + kPeriods + 1);
  EXPECT_EQ(flooded.log, quiet.log) << "the flood changed the run";
  for (const LabRun* r : {&quiet, &flooded}) {
    EXPECT_EQ(r->summary.at("result"), "pass");
    EXPECT_EQ(r->summary.at("clock_stats").at("timeouts"), 0);
    EXPECT_EQ(r->arm.at("accepted"), kPeriods);
    EXPECT_EQ(r->arm.at("future"), 1) << "seq 2^53 is from the future: ignored and counted";
    EXPECT_EQ(r->arm.at("owners_released"), 0);
  }

  // every flood datagram is accounted for: commands refused as not subscribed,
  // requests answered with a challenge; nothing else changed
  const nlohmann::json& a = flooded.arm;
  const nlohmann::json& q = quiet.arm;
  // (less what the kernel dropped before the lab could read it, on a busy machine)
  const long refused = a.at("refused_not_subscribed").get<long>();
  const long challenged = a.at("sessions").at("challenges").get<long>() - q.at("sessions").at("challenges").get<long>();
  EXPECT_EQ(a.at("received").get<long>() - q.at("received").get<long>() + flooded.drops, f.sent);
  EXPECT_EQ(refused + challenged + flooded.drops, f.sent);
  EXPECT_LE(refused, f.commands);
  EXPECT_LE(challenged, f.requests);
  EXPECT_EQ(a.at("describes"), q.at("describes")) << "no describe reply to an unproven source";
  EXPECT_EQ(a.at("sessions").at("subscribed"), 1) << "only the controller subscribed";
  EXPECT_EQ(a.at("received").get<long>(), a.at("accepted").get<long>() + a.at("requests").get<long>() +
                                              a.at("refused").get<long>() + a.at("stale").get<long>() +
                                              a.at("duplicate").get<long>() + a.at("future").get<long>());

  // the flood's sources got back challenges only, as large as their requests: amplification 1
  EXPECT_EQ(f.not_challenges, 0) << "a flood source received a state or a describe reply";
  EXPECT_EQ(f.received, challenged);
  EXPECT_EQ(f.received_bytes, 72 * challenged);
  EXPECT_LE(f.received_bytes, f.sent_bytes);
  std::printf(
      "flood: %ld datagrams (%ld bytes) from %d ports, %ld commands, %ld requests, %ld dropped by the "
      "kernel; back: %ld datagrams (%ld bytes), amplification %.3f (requests alone: %.3f)\n",
      f.sent, f.sent_bytes, kFloodPorts, f.commands, f.requests, flooded.drops, f.received, f.received_bytes,
      static_cast<double>(f.received_bytes) / static_cast<double>(f.sent_bytes),
      static_cast<double>(f.received_bytes) / (72.0 * static_cast<double>(challenged)));
}

}  // namespace
}  // namespace vlab::testing
