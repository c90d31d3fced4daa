// Who controls a run served by `vlab serve`, over real loopback sockets on
// ports the lab picks itself (--port NAME=0, read back from its start line):
// a pause ends when its pauser unsubscribes (or, stay_paused, waits for the
// next owner's op); a bystander's pause, step and
// reset are refused (answered with result 5) and counted while a controller
// drives, and the driver's own op is taken; the state a new subscriber gets at
// once carries not_owner; a table full of subscribers that never command does
// not lock the controller out. Bounds: the waits below are patience only (a
// missing datagram fails the test when it runs out); nothing is timed.
#include <gtest/gtest.h>

#include <map>
#include <regex>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bridge/bridge_layouts.h"
#include "serve/serve_process.h"
#include "test_util.h"

namespace vlab::testing {
namespace {

using bridge::DeviceKind;
using Bytes = std::vector<unsigned char>;

constexpr double kPatience_s = 20;  // for a datagram that must come (a loaded CI machine)

// the PA10 and the sim device, in `clock`, with the sim's extra keys
std::string Scenario(const std::string& clock, double duration_s, const std::string& sim_keys) {
  return std::string("name: ownership\nscene: ") + VLAB_SOURCE_DIR + "/scenes/pa10.xml\n" +
         "duration: " + std::to_string(duration_s) + "\ncontrol_period: 0.002\nclock: " + clock + "\n" +
         "lockstep: {timeout: 1.0, start_timeout: 60, on_timeout: hold}\n"
         "devices:\n"
         "  - {name: pa10, kind: arm, port: 1, joints: [S1, S2, S3, E1, E2, W1, W2],\n"
         "     initial: [0, 0.523599, 0, 1.047198, 0, 1.570796, 0]}\n"
         "  - {name: sim, kind: sim, port: 1" +
         sim_keys + "}\n";
}

// `vlab serve` of a scenario on free ports; the ports from its start line
struct Served {
  Served(const TempDir& tmp, const std::string& scenario, const std::string& options = "")
      : process("'" + (tmp / "s.yaml") + "' --port pa10=0 --port sim=0 --out '" + (tmp / "out") + "'" + options,
                tmp.path()) {
    WriteFile(tmp / "s.yaml", scenario);
  }
  bool Start() {
    if (!process.WaitStarted()) return false;
    const std::string out = process.Output();
    static const std::regex device(R"((\w+) \(\w+\) [^ ]+:(\d+);)");
    for (auto it = std::sregex_iterator(out.begin(), out.end(), device); it != std::sregex_iterator(); ++it) {
      ports[(*it)[1]] = bridge::UdpSocket::MakeEndpoint("127.0.0.1", std::stoi((*it)[2]));
    }
    return ports.count("pa10") && ports.count("sim");
  }
  ServeProcess process;
  std::map<std::string, bridge::Endpoint> ports;
};

std::unique_ptr<bridge::UdpSocket> Socket() { return bridge::UdpSocket::Bind("127.0.0.1", 0); }

// the next datagram from `device`'s port that is a state of `kind` (false: none within the patience)
bool ReadState(bridge::UdpSocket& s, const bridge::Endpoint& device, DeviceKind kind, bridge::Header* h,
               std::vector<double>* payload) {
  unsigned char buf[65536];
  for (;;) {
    bridge::Endpoint from;
    const long n = s.Receive(buf, sizeof buf, &from, kPatience_s);
    if (n < 0) return false;
    if (from.port() != device.port() || buf[0] == '{') continue;
    if (bridge::DecodePacket(buf, static_cast<std::size_t>(n), h, payload) != bridge::DecodeError::kNone) continue;
    if (h->type == static_cast<int>(bridge::MessageType::kState) && h->kind == static_cast<int>(kind)) return true;
  }
}

// the result of the next session reply from `device` (-1: none within the patience)
int ReadResult(bridge::UdpSocket& s, const bridge::Endpoint& device) {
  unsigned char buf[65536];
  for (;;) {
    bridge::Endpoint from;
    const long n = s.Receive(buf, sizeof buf, &from, kPatience_s);
    if (n < 0) return -1;
    if (from.port() != device.port() || !bridge::IsSessionReply(buf, static_cast<std::size_t>(n))) continue;
    return static_cast<int>(bridge::GetDouble(buf + bridge::kHeaderBytes + sizeof(double)));
  }
}

void SendOp(bridge::UdpSocket& s, const bridge::Endpoint& sim, double seq, bridge::SimOp op, double arg) {
  Bytes p;
  bridge::EncodeSimCommand(seq, 0, {static_cast<int>(op), arg}, &p);
  s.SendTo(p.data(), p.size(), sim);
}

void SendHold(bridge::UdpSocket& s, const bridge::Endpoint& arm, double seq) {
  Bytes p;
  bridge::EncodeArmCommand(seq, 0, {0, std::vector<double>(7, 0.0)}, &p);
  s.SendTo(p.data(), p.size(), arm);
}

// the sim's mode in a sim state's payload
int Mode(const std::vector<double>& payload) {
  return static_cast<int>(payload[bridge::StateIndex(DeviceKind::kSim, "mode")]);
}

// the controller, on one socket for its arm and for the sim (so that it may operate the sim):
// answers period 0, pauses the run and reads sim states until one shows it paused (in h, p)
void DriveAndPause(bridge::UdpSocket& ctl, const bridge::Endpoint& arm, const bridge::Endpoint& sim, bridge::Header* h,
                   std::vector<double>* p) {
  // (the sim first: a handshake drops the other datagrams, and the arm's latest state is awaited)
  ASSERT_NE(WireSubscribe(ctl, sim, DeviceKind::kSim), 0);
  ASSERT_NE(WireSubscribe(ctl, arm, DeviceKind::kArm), 0);
  ASSERT_TRUE(ReadState(ctl, arm, DeviceKind::kArm, h, p));
  SendHold(ctl, arm, h->seq);  // period 0 waits for it
  ASSERT_TRUE(ReadState(ctl, sim, DeviceKind::kSim, h, p));
  SendOp(ctl, sim, h->seq, bridge::SimOp::kPause, 0);
  int states = 0;
  do {
    ASSERT_TRUE(ReadState(ctl, sim, DeviceKind::kSim, h, p)) << "no sim state";
    ASSERT_LT(++states, 100000) << "never paused";
  } while (Mode(*p) != 1);
}

const nlohmann::json& DeviceCounters(const nlohmann::json& summary, const std::string& name) {
  for (const nlohmann::json& d : summary.at("bridge").at("devices")) {
    if (d.at("name") == name) return d;
  }
  throw std::runtime_error("summary.json: no device " + name);
}

TEST(SimOwnership, APauseEndsWhenItsPauserUnsubscribes) {
  TempDir tmp;
  // an owner timeout of an hour: only the unsubscription can end the pause within the test
  Served lab(tmp, Scenario("realtime", 600, ", owner_timeout: 3600, on_owner_lost: resume"));
  ASSERT_TRUE(lab.Start()) << lab.process.Output() << lab.process.Errors();
  const bridge::Endpoint arm = lab.ports["pa10"], sim = lab.ports["sim"];
  auto ctl = Socket();
  bridge::Header h;
  std::vector<double> p;
  ASSERT_NO_FATAL_FAILURE(DriveAndPause(*ctl, arm, sim, &h, &p));
  const double paused_periods = p[bridge::StateIndex(DeviceKind::kSim, "periods")];
  auto observer = Socket();
  ASSERT_NE(WireSubscribe(*observer, sim, DeviceKind::kSim), 0);
  ASSERT_TRUE(ReadState(*observer, sim, DeviceKind::kSim, &h, &p));
  EXPECT_EQ(Mode(p), 1) << "the latest state, sent at once";
  ASSERT_NE(WireSubscribe(*ctl, sim, DeviceKind::kSim, 0), 0);  // the pauser leaves the sim
  ASSERT_TRUE(ReadState(*observer, sim, DeviceKind::kSim, &h, &p)) << "still paused";
  EXPECT_EQ(Mode(p), 0);
  EXPECT_EQ(p[bridge::StateIndex(DeviceKind::kSim, "periods")], paused_periods);  // no period ran while paused
}

// on_owner_lost: stay_paused: the pauser's unsubscription frees the sim but no period runs
// until the next owner's op: a step of 3 then runs exactly 3 periods from where it paused
TEST(SimOwnership, StayPausedWaitsForTheNextOwnersOp) {
  TempDir tmp;
  Served lab(tmp, Scenario("realtime", 600, ", owner_timeout: 3600, on_owner_lost: stay_paused"));
  ASSERT_TRUE(lab.Start()) << lab.process.Output() << lab.process.Errors();
  const bridge::Endpoint arm = lab.ports["pa10"], sim = lab.ports["sim"];
  auto ctl = Socket();
  bridge::Header h;
  std::vector<double> p;
  ASSERT_NO_FATAL_FAILURE(DriveAndPause(*ctl, arm, sim, &h, &p));
  const int periods = bridge::StateIndex(DeviceKind::kSim, "periods");
  const double paused_periods = p[periods];
  ASSERT_NE(WireSubscribe(*ctl, sim, DeviceKind::kSim, 0), 0);  // the pauser leaves: no owner now
  ASSERT_NE(WireSubscribe(*ctl, sim, DeviceKind::kSim), 0);     // and comes back
  ASSERT_TRUE(ReadState(*ctl, sim, DeviceKind::kSim, &h, &p));  // the latest, sent at once
  EXPECT_EQ(Mode(p), 1);
  EXPECT_EQ(p[periods], paused_periods);
  SendOp(*ctl, sim, h.seq, bridge::SimOp::kStep, 3);
  do {
    ASSERT_TRUE(ReadState(*ctl, sim, DeviceKind::kSim, &h, &p)) << "the step did not end";
  } while (Mode(p) != 1 || p[periods] == paused_periods);
  EXPECT_EQ(p[periods], paused_periods + 3) << "periods ran before the step";
}

TEST(SimOwnership, ABystandersOpsAreRefusedWhileAControllerDrives) {
  TempDir tmp;
  const long periods = 50;
  Served lab(tmp, Scenario("lockstep", periods * 0.002, ""));
  ASSERT_TRUE(lab.Start()) << lab.process.Output() << lab.process.Errors();
  const bridge::Endpoint arm = lab.ports["pa10"], sim = lab.ports["sim"];
  auto ctl = Socket(), bystander = Socket();
  // (the sim first: a handshake drops the other datagrams, and the arm's latest state is awaited)
  ASSERT_NE(WireSubscribe(*ctl, sim, DeviceKind::kSim), 0);
  ASSERT_NE(WireSubscribe(*ctl, arm, DeviceKind::kArm), 0);
  ASSERT_NE(WireSubscribe(*bystander, sim, DeviceKind::kSim), 0);
  const std::map<double, bridge::SimOp> ops = {
      {5, bridge::SimOp::kPause}, {6, bridge::SimOp::kStep}, {7, bridge::SimOp::kReset}};
  bridge::Header h;
  std::vector<double> p;
  double answered = -1;
  while (answered < periods - 1) {
    ASSERT_TRUE(ReadState(*ctl, arm, DeviceKind::kArm, &h, &p)) << "after state " << answered;
    if (h.seq <= answered) continue;  // (sent again after an op)
    // the lab waits for this state's answer: the bystander's op arrives meanwhile
    if (auto op = ops.find(h.seq); op != ops.end()) {
      SendOp(*bystander, sim, 0, op->second, op->second == bridge::SimOp::kStep ? 1 : 0);
      EXPECT_EQ(ReadResult(*bystander, sim), static_cast<int>(bridge::SessionResult::kRefused)) << h.seq;
    }
    // the driver's own op (set the realtime factor: nothing changes in lockstep) is taken
    if (h.seq == 8) SendOp(*ctl, sim, 0, bridge::SimOp::kSetRealtimeFactor, 1);
    SendHold(*ctl, arm, h.seq);
    answered = h.seq;
  }
  ASSERT_EQ(lab.process.Wait(60), 0) << lab.process.Output() << lab.process.Errors();
  const nlohmann::json summary = nlohmann::json::parse(ReadFile(tmp / "out/summary.json"));
  EXPECT_EQ(summary.at("timings").at("control_periods").get<long>(), periods);
  const nlohmann::json& s = DeviceCounters(summary, "sim");
  EXPECT_EQ(s.at("refused_not_owner").get<long>(), 3);
  EXPECT_EQ(s.at("accepted").get<long>(), 1);
}

TEST(SimOwnership, TheFirstStateOfANewSubscriberCarriesNotOwner) {
  TempDir tmp;
  Served lab(tmp, Scenario("lockstep", 10, ""));
  ASSERT_TRUE(lab.Start()) << lab.process.Output() << lab.process.Errors();
  const bridge::Endpoint arm = lab.ports["pa10"];
  auto ctl = Socket(), observer = Socket();
  ASSERT_NE(WireSubscribe(*ctl, arm, DeviceKind::kArm), 0);
  bridge::Header h;
  std::vector<double> p;
  ASSERT_TRUE(ReadState(*ctl, arm, DeviceKind::kArm, &h, &p));
  SendHold(*ctl, arm, h.seq);  // the owner; the lab runs period 0 and waits for state 1's answer
  ASSERT_NE(WireSubscribe(*observer, arm, DeviceKind::kArm), 0);
  ASSERT_TRUE(ReadState(*observer, arm, DeviceKind::kArm, &h, &p));  // the latest, sent at once
  EXPECT_LE(h.seq, 1);  // (state 0 if the subscription came before period 0 ran)
  EXPECT_TRUE(static_cast<std::uint32_t>(p[0]) & bridge::kStatusNotOwner) << "status " << p[0];
  ASSERT_TRUE(ReadState(*ctl, arm, DeviceKind::kArm, &h, &p));
  EXPECT_FALSE(static_cast<std::uint32_t>(p[0]) & bridge::kStatusNotOwner) << "the owner's status " << p[0];
}

TEST(SimOwnership, ATableFullOfSubscribersDoesNotLockTheControllerOut) {
  TempDir tmp;
  const long periods = 5;
  Served lab(tmp, Scenario("lockstep", periods * 0.002, ""));
  ASSERT_TRUE(lab.Start()) << lab.process.Output() << lab.process.Errors();
  const bridge::Endpoint arm = lab.ports["pa10"];
  std::vector<std::unique_ptr<bridge::UdpSocket>> crowd;
  for (int i = 0; i < bridge::kDefaultMaxSubscribers; ++i) {  // they fill the table, and never command
    crowd.push_back(Socket());
    ASSERT_NE(WireSubscribe(*crowd.back(), arm, DeviceKind::kArm), 0) << i;
  }
  auto ctl = Socket();
  ASSERT_NE(WireSubscribe(*ctl, arm, DeviceKind::kArm), 0) << "the controller was refused";
  bridge::Header h;
  std::vector<double> p;
  double answered = -1;
  while (answered < periods - 1) {
    ASSERT_TRUE(ReadState(*ctl, arm, DeviceKind::kArm, &h, &p)) << "after state " << answered;
    if (answered >= 0) {
      EXPECT_FALSE(static_cast<std::uint32_t>(p[0]) & bridge::kStatusNotOwner) << h.seq;
    }
    SendHold(*ctl, arm, h.seq);
    answered = h.seq;
  }
  ASSERT_EQ(lab.process.Wait(60), 0) << lab.process.Output() << lab.process.Errors();
  const nlohmann::json summary = nlohmann::json::parse(ReadFile(tmp / "out/summary.json"));
  const nlohmann::json& sessions = DeviceCounters(summary, "pa10").at("sessions");
  EXPECT_EQ(sessions.at("evicted").get<long>(), 1);
  EXPECT_EQ(sessions.at("refused_full").get<long>(), 0);
  EXPECT_EQ(DeviceCounters(summary, "pa10").at("accepted").get<long>(), periods);
}

}  // namespace
}  // namespace vlab::testing
