// vlab-yoyosim end to end over loopback: the real executable, clients made of bridge/
// only (the generic bridge::Device, and raw UdpSocket packets for the faults).
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bridge/bridge_client_device.h"
#include "bridge/bridge_layouts.h"
#include "bridge/bridge_protocol.h"
#include "bridge/bridge_udp.h"
#include "bridge/bridge_yoyo.h"
#include "wire_session.h"
#include "yoyosim_process.h"

namespace vlab::bridge {
namespace {

using testing::YoyosimProcess;
using Clock = std::chrono::steady_clock;

// positions in the point's and the yo-yo's states
constexpr int kHandZ = StateIndex(DeviceKind::kPoint, "z"), kHandVz = StateIndex(DeviceKind::kPoint, "vz");
constexpr int kPointStatus = StateIndex(DeviceKind::kPoint, "status");
constexpr int kYoyoVz = StateIndex(DeviceKind::kYoyo, "vz"), kYoyoForce = StateIndex(DeviceKind::kYoyo, "string_force");
constexpr int kYoyoValues = ValueCount(LayoutOf(DeviceKind::kYoyo).state);
// RunLockstep's rows: the yo-yo's state, then the hand's z and vz
constexpr int kRow = kYoyoValues + 2, kRowHandZ = kYoyoValues, kRowHandVz = kYoyoValues + 1;

double Seconds(Clock::time_point since) { return std::chrono::duration<double>(Clock::now() - since).count(); }
bool Has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

/// A smooth hand path (world, m) within the speed limit: the same in every run.
std::vector<double> HandAt(double t) { return {0.03 * std::sin(4 * t), 0.0, 1.5 + 0.08 * std::sin(6 * t)}; }

/// Runs a lockstep controller for `periods`: reads state k of both devices, checks
/// each seq comes exactly once in order, commands HandAt(t_k+1) answering k.
/// Returns the yo-yo's values of every state.
std::vector<double> RunLockstep(YoyosimProcess& p, int periods) {
  Device point = Device::Connect(DeviceKind::kPoint, "127.0.0.1", p.point_port(), 5.0);
  Device yoyo = Device::Connect(DeviceKind::kYoyo, "127.0.0.1", p.yoyo_port(), 5.0);
  std::vector<double> values;
  for (int k = 0; k <= periods; ++k) {
    const Device::State hand = point.Read(5.0);
    const Device::State y = yoyo.Read(5.0);
    EXPECT_EQ(hand.seq, k);
    EXPECT_EQ(y.seq, k);
    EXPECT_DOUBLE_EQ(y.time, k * 0.01);
    values.insert(values.end(), y.values.begin(), y.values.end());
    values.push_back(hand.values[kHandZ]);
    values.push_back(hand.values[kHandVz]);
    if (k < periods) point.Write(HandAt((k + 1) * 0.01), k);
  }
  return values;
}

TEST(YoyosimUdp, DescribesBothDevicesWithTheSharedLayouts) {
  YoyosimProcess p({"--clock", "realtime", "--duration", "0"});
  ASSERT_TRUE(p.ok()) << p.output();
  Device point = Device::Connect(DeviceKind::kPoint, "127.0.0.1", p.point_port(), 5.0);
  Device yoyo = Device::Connect(DeviceKind::kYoyo, "127.0.0.1", p.yoyo_port(), 5.0);
  const nlohmann::json& d = point.describe();
  EXPECT_EQ(d["kind"], "point");
  EXPECT_EQ(d["server"], "vlab-yoyosim (MuJoCo 2.2.2)");
  EXPECT_EQ(d["clock"], "realtime");
  EXPECT_DOUBLE_EQ(d["rates"]["control_hz"].get<double>(), 100.0);
  ASSERT_EQ(point.state_length(), 7);
  ASSERT_EQ(point.command_length(), 3);
  for (int i = 0; i < 7; ++i) EXPECT_EQ(point.state_names()[i], kPointStateLayout[i]);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(point.command_names()[i], kPointCommandLayout[i]);
  EXPECT_EQ(d["limits"]["workspace_min"], nlohmann::json({-0.5, -0.5, 1.0}));
  EXPECT_EQ(d["limits"]["workspace_max"], nlohmann::json({0.5, 0.5, 2.0}));
  EXPECT_DOUBLE_EQ(d["limits"]["speed_max"].get<double>(), 2.0);
  EXPECT_EQ(yoyo.describe()["kind"], "yoyo");
  EXPECT_EQ(yoyo.command_length(), 0);
  for (int i = 0; i < 7; ++i) EXPECT_EQ(yoyo.state_names()[i], kYoyoStateLayout[i]);
  EXPECT_DOUBLE_EQ(yoyo.describe()["yoyo"]["axle_radius"].get<double>(), 0.008);
  EXPECT_EQ(p.Stop(), 0);
}

// every period answered exactly once, and the descent seen through the wire is the
// closed form in the hand's frame: (v_hand - vz) grows at (g + a_hand) m r^2 / (m r^2 + J)
TEST(YoyosimUdp, LockstepAnswersEveryPeriodOnceAndKeepsThePhysics) {
  constexpr int kPeriods = 60;
  YoyosimProcess p({"--duration", "0.6", "--start-timeout", "10", "--timeout", "5"});
  ASSERT_TRUE(p.ok()) << p.output();
  const std::vector<double> v = RunLockstep(p, kPeriods);
  EXPECT_EQ(p.Wait(), 0);
  EXPECT_TRUE(Has(p.output(), "60 periods (0.600 s), set-points applied 60, lockstep timeouts 0")) << p.output();
  EXPECT_TRUE(Has(p.output(), "accepted 60, refused 0")) << p.output();
  EXPECT_TRUE(Has(p.output(), "stale 0, duplicate 0")) << p.output();
  // rows: yo-yo [status x y z vz force spin], hand z, hand vz
  ASSERT_EQ(v.size(), static_cast<std::size_t>(kRow * (kPeriods + 1)));
  auto at = [&](int k, int i) { return v[kRow * k + i]; };
  auto relative_rate = [&](int k) { return at(k, kRowHandVz) - at(k, kYoyoVz); };  // d' = v_hand - vz
  const double share = 0.05 * 0.008 * 0.008 / (0.05 * 0.008 * 0.008 + 3.0625e-5);
  const int k1 = 20, k2 = 60;
  const double dt = (k2 - k1) * 0.01;
  const double a_hand = (at(k2, kRowHandVz) - at(k1, kRowHandVz)) / dt;
  const double expected = (9.81 + a_hand) * share;
  EXPECT_NEAR((relative_rate(k2) - relative_rate(k1)) / dt, expected, 1e-4 * expected);
  EXPECT_GT(at(k2, kYoyoForce), 0.0) << "the string is taut";
}

TEST(YoyosimUdp, SameCommandsGiveTheSameYoyoStatesBitForBit) {
  std::vector<double> runs[2];
  for (auto& run : runs) {
    YoyosimProcess p({"--duration", "0.5", "--start-timeout", "10", "--timeout", "5", "--quiet"});
    ASSERT_TRUE(p.ok()) << p.output();
    run = RunLockstep(p, 50);
    EXPECT_EQ(p.Wait(), 0);
  }
  ASSERT_EQ(runs[0].size(), runs[1].size());
  EXPECT_EQ(std::memcmp(runs[0].data(), runs[1].data(), runs[0].size() * sizeof(double)), 0);
}

// Realtime: the periods keep the wall clock's pace. State k is published once period k-1 has
// begun, at its deadline (the clock's anchor, when period 0 was answered, + (k-1) x 10 ms) or
// later, never earlier: so state 100 cannot arrive sooner than 0.99 s after the answer to period
// 0 was sent, and a clock that ran ahead (or did not wait at all) fails. A busy machine only makes
// it later, so there is no upper bound on the wall; that the periods are all there, in order,
// each stamped with its simulated time, is counted instead.
TEST(YoyosimUdp, RealtimeRunsPacedToTheWallClock) {
  YoyosimProcess p({"--clock", "realtime", "--duration", "1.0", "--start-timeout", "10"});
  ASSERT_TRUE(p.ok()) << p.output();
  Device point = Device::Connect(DeviceKind::kPoint, "127.0.0.1", p.point_port(), 5.0);
  Device::State s = point.Read(5.0);
  ASSERT_EQ(s.seq, 0);
  const Clock::time_point answered = Clock::now();
  point.Write(HandAt(0.01), s.seq);  // answers period 0: the wall clock starts
  std::int64_t last = s.seq;
  while (last < 100) {
    s = point.Read(5.0);
    EXPECT_GT(s.seq, last);
    EXPECT_DOUBLE_EQ(s.time, static_cast<double>(s.seq) * 0.01) << "state " << s.seq << ": its simulated time";
    last = s.seq;
    point.Write(HandAt((s.seq + 1) * 0.01), s.seq);
  }
  const double wall = Seconds(answered);  // 99 periods of 10 ms at least
  RecordProperty("wall_to_state_100_s", std::to_string(wall));
  EXPECT_GE(wall, 0.99) << "state 100 came before its period's deadline: the clock ran ahead of the wall";
  EXPECT_EQ(p.Wait(), 0);
  EXPECT_TRUE(Has(p.output(), "100 periods (1.000 s)")) << p.output();
}

/// A raw client of one device port.
struct Raw {
  explicit Raw(int port) : socket(UdpSocket::Bind("127.0.0.1", 0)), to(UdpSocket::MakeEndpoint("127.0.0.1", port)) {}
  void Send(const std::vector<unsigned char>& bytes) { socket->SendTo(bytes.data(), bytes.size(), to); }
  void Send(int kind, int type, double seq, const std::vector<double>& payload) {
    std::vector<unsigned char> bytes;
    EncodePacket(Header{kind, type, seq, 0.0, static_cast<int>(payload.size())}, payload.data(),
                 static_cast<int>(payload.size()), &bytes);
    Send(bytes);
  }
  void Command(double seq, const std::vector<double>& xyz) { Send(10, 2, seq, xyz); }
  /// The next point state (JSON and session replies skipped): fills header and values.
  bool Next(double timeout_s = 5) {
    const Clock::time_point start = Clock::now();
    unsigned char buffer[8192];
    while (Seconds(start) < timeout_s) {
      const long n = socket->Receive(buffer, sizeof(buffer), nullptr, 0.1);
      if (n <= 0 || buffer[0] == '{' || IsSessionReply(buffer, static_cast<std::size_t>(n))) continue;
      if (DecodePacket(buffer, static_cast<std::size_t>(n), &header, &values) == DecodeError::kNone) return true;
    }
    return false;
  }
  std::unique_ptr<UdpSocket> socket;
  Endpoint to;
  Header header;
  std::vector<double> values;
};

TEST(YoyosimUdp, BadPacketsAreRefusedAndCountedWhileTheRunGoesOn) {
  YoyosimProcess p({"--duration", "0.2", "--start-timeout", "10", "--timeout", "0.3"});
  ASSERT_TRUE(p.ok()) << p.output();
  Raw owner(p.point_port()), other(p.point_port()), yoyo(p.yoyo_port());
  // subscribe (the cookie handshake): state 0 follows
  ASSERT_GT(vlab::testing::WireSubscribe(*owner.socket, owner.to, DeviceKind::kPoint), 0);
  ASSERT_GT(vlab::testing::WireSubscribe(*other.socket, other.to, DeviceKind::kPoint), 0);
  ASSERT_GT(vlab::testing::WireSubscribe(*yoyo.socket, yoyo.to, DeviceKind::kYoyo), 0);
  std::vector<double> status(21, -1);
  for (int k = 0; k <= 20; ++k) {
    ASSERT_TRUE(owner.Next()) << "state " << k;
    ASSERT_EQ(owner.header.seq, k);
    status[k] = owner.values[kPointStatus];
    const double z = 1.5 + 0.001 * k;
    if (k == 3) {  // malformed, six ways
      owner.Send({1, 2, 3});
      owner.Send(10, 2, k, {0.0, 0.0});              // wrong length
      owner.Send(10, 2, k, {0.0, std::nan(""), z});  // NaN
      owner.Send(1, 2, k, {0.0, 0.0, z});            // arm kind
      owner.Send(10, 1, k, {0.0, 0.0, z});           // a state
      std::vector<unsigned char> bad;
      EncodePacket(Header{10, 2, double(k), 0.0, 3}, std::vector<double>{0, 0, z}.data(), 3, &bad);
      bad[1] ^= 0xff;  // magic
      owner.Send(bad);
      other.Command(k, {0.0, 0.0, z});  // not the owner
      yoyo.Send(11, 2, k, {0.0});       // the yoyo takes no commands
      yoyo.Send({9, 9});                // nor garbage
    }
    if (k == 5) {  // beyond the workspace: refused, the period times out
      owner.Command(k, {0.0, 0.0, 2.5});
      continue;
    }
    if (k == 8) {  // 10 cm in one period = 10 m/s: accepted, approached at speed_max (2 cm a period)
      owner.Command(k, {0.1, 0.0, z});
      continue;
    }
    if (k < 20) owner.Command(k, {0.0, 0.0, z});
  }
  EXPECT_EQ(status[6], static_cast<double>(kStatusRefused)) << "the state after a refused command says so";
  EXPECT_EQ(status[7], 0.0) << "and the next accepted command clears it";
  EXPECT_EQ(status[9], 0.0) << "a far set-point is not refused";
  EXPECT_EQ(status[0], static_cast<double>(kStatusHolding)) << "holding before the first command";
  // state 0 came before anyone owned the point; the later ones mark a non-owner
  while (other.Next() && other.header.seq < 10) {
  }
  ASSERT_EQ(other.header.seq, 10);
  EXPECT_EQ(static_cast<unsigned>(other.values[kPointStatus]) & kStatusNotOwner, kStatusNotOwner);
  EXPECT_EQ(p.Wait(), 0);
  EXPECT_TRUE(Has(p.output(), "20 periods (0.200 s), set-points applied 19, lockstep timeouts 1, releases 0"))
      << p.output();
  EXPECT_TRUE(Has(p.output(), "accepted 19, refused 8 (malformed 6, limits 1, not owner 1)")) << p.output();
  EXPECT_TRUE(Has(p.output(), "yoyo: received 4, describes 0, refused 2")) << p.output();  // 2: the handshake
}

TEST(YoyosimUdp, ANewSubscriberWhileAnotherOwnsThePointGetsNotOwnerInItsFirstState) {
  YoyosimProcess p({"--duration", "0.03", "--start-timeout", "10", "--timeout", "5"});
  ASSERT_TRUE(p.ok()) << p.output();
  Raw owner(p.point_port()), other(p.point_port());
  ASSERT_GT(vlab::testing::WireSubscribe(*owner.socket, owner.to, DeviceKind::kPoint), 0);
  ASSERT_TRUE(owner.Next());
  ASSERT_EQ(owner.header.seq, 0);
  owner.Command(0, {0.0, 0.0, 1.5});  // the owner now; lockstep runs period 0 and waits for the answer to 1
  ASSERT_TRUE(owner.Next());
  ASSERT_EQ(owner.header.seq, 1);
  EXPECT_EQ(static_cast<unsigned>(owner.values[kPointStatus]) & kStatusNotOwner, 0u);
  // the latest state goes to a newcomer at once, marked like every later one
  ASSERT_GT(vlab::testing::WireSubscribe(*other.socket, other.to, DeviceKind::kPoint), 0);
  ASSERT_TRUE(other.Next());
  EXPECT_EQ(other.header.seq, 1);
  EXPECT_EQ(static_cast<unsigned>(other.values[kPointStatus]) & kStatusNotOwner, kStatusNotOwner);
  for (int k = 1; k < 3; ++k) {
    owner.Command(k, {0.0, 0.0, 1.5});
    ASSERT_TRUE(owner.Next());
    ASSERT_TRUE(other.Next());
    EXPECT_EQ(static_cast<unsigned>(other.values[kPointStatus]) & kStatusNotOwner, kStatusNotOwner);
  }
  EXPECT_EQ(p.Wait(), 0) << p.output();
}

TEST(YoyosimUdp, LockstepReleasesASilentOwnerAfterThreeTimeouts) {
  YoyosimProcess p({"--duration", "0.5", "--start-timeout", "10", "--timeout", "0.1"});
  ASSERT_TRUE(p.ok()) << p.output();
  Device point = Device::Connect(DeviceKind::kPoint, "127.0.0.1", p.point_port(), 5.0);
  for (int k = 0; k < 5; ++k) point.Write(HandAt(0.0), point.Read(5.0).seq);
  const Clock::time_point silent = Clock::now();
  EXPECT_EQ(p.Wait(), 0);
  // three lockstep timeouts of 0.1 s, then the run goes on without waiting: 0.3 s of wall time
  // (the first timeout may start a moment before `silent` is read: 0.29; two would be 0.2)
  const double silent_s = Seconds(silent);
  RecordProperty("silent_to_exit_s", std::to_string(silent_s));
  EXPECT_GE(silent_s, 0.29) << "released before three timeouts";
  EXPECT_LT(silent_s, 0.45) << "after the release the run does not wait";  // 1.5x the 0.3 s
  EXPECT_TRUE(Has(p.output(), "50 periods (0.500 s), set-points applied 5, lockstep timeouts 3, releases 1"))
      << p.output();
  EXPECT_TRUE(Has(p.output(), "watchdog holds 1")) << p.output();
}

}  // namespace
}  // namespace vlab::bridge
