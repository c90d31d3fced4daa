// Tests bridge/bridge_client.cc: the real client against a real device
// endpoint on loopback (a server thread), and against a scripted peer for the
// faults (garbage, other versions, silence, stray datagrams). Timeouts are
// seconds, never tight: the tests must pass on a loaded machine.
#include "bridge/bridge_client.h"

#include <atomic>
#include <chrono>
#include <cmath>
#include <future>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bridge/bridge_describe.h"
#include "bridge/bridge_endpoint.h"
#include "bridge/bridge_session.h"
#include "wire_session.h"

namespace vlab::bridge::client_test {
namespace {

using Bytes = std::vector<unsigned char>;
using std::chrono::steady_clock;
constexpr double kPeriod_s = 0.002;
constexpr double kPatience_s = 5.0;  // how long a test waits for something that must happen

ArmDescription Pa10Description() {
  ArmDescription d;
  d.name = "pa10";
  d.server = "client_test";
  d.clock = "realtime";
  d.address = "127.0.0.1";
  d.control_hz = 1.0 / kPeriod_s;
  d.joints = {"S1", "S2", "S3", "E1", "E2", "W1", "W2"};
  const double deg = M_PI / 180;
  d.position_max = {177 * deg, 94 * deg, 174 * deg, 137 * deg, 255 * deg, 165 * deg, 255 * deg};
  for (double m : d.position_max) d.position_min.push_back(-m);
  d.velocity_max = {1, 1, 2, 2, 6, 6, 6};
  d.torque_max = {200, 200, 80, 80, 15, 15, 10};
  return d;
}

// the scripted state of period k: joint i at 0.1 i + 0.001 k
ArmStateMsg ScriptedState(long k) {
  ArmStateMsg m;
  for (int i = 0; i < 7; ++i) {
    m.q.push_back(0.1 * i + 0.001 * static_cast<double>(k));
    m.qd.push_back(-0.5 * i);
    m.tau.push_back(10.0 * i);
  }
  return m;
}

struct ReceivedCommand {
  double seq;
  int mode;
  std::vector<double> value;
};

// An arm device as a server runs it: a DeviceEndpoint on 127.0.0.1, one period
// every 2 ms (handle what arrived, publish the state of the period).
class ArmServer {
 public:
  explicit ArmServer(std::string describe_json = DescribeJson(Pa10Description()))
      : socket_(UdpSocket::Bind("127.0.0.1", 0)), endpoint_(Config(std::move(describe_json))) {
    thread_ = std::thread([this] { Run(); });
  }
  ~ArmServer() {
    stop_ = true;
    thread_.join();
  }
  int port() const { return socket_->local_port(); }
  std::vector<ReceivedCommand> commands() {
    std::lock_guard<std::mutex> lock(mutex_);
    return commands_;
  }
  EndpointCounters counters() {
    std::lock_guard<std::mutex> lock(mutex_);
    return endpoint_.counters();
  }

 private:
  static EndpointConfig Config(std::string describe_json) {
    const ArmDescription d = Pa10Description();
    EndpointConfig c;
    c.name = d.name;
    c.kind = DeviceKind::kArm;
    c.describe_json = std::move(describe_json);
    c.joints = 7;
    c.position_min = d.position_min;
    c.position_max = d.position_max;
    c.velocity_max = d.velocity_max;
    c.torque_max = d.torque_max;
    c.watchdog_periods = 0;
    return c;
  }

  void Run() {
    Bytes buffer(65536), state;
    ArmCommandMsg command;
    for (long k = 0; !stop_; ++k) {
      const auto end = steady_clock::now() + std::chrono::duration<double>(kPeriod_s);
      std::lock_guard<std::mutex> lock(mutex_);
      for (;;) {
        const double left = std::chrono::duration<double>(end - steady_clock::now()).count();
        Endpoint from;
        const long n = socket_->Receive(buffer.data(), buffer.size(), &from, left > 0 ? left : 0);
        if (n < 0) break;
        if (endpoint_.Handle(buffer.data(), static_cast<std::size_t>(n), from, k, *socket_) ==
                DeviceEndpoint::Received::kCommand &&
            endpoint_.TakeArmCommand(&command)) {
          commands_.push_back({endpoint_.last_accepted_seq(), command.mode, command.value});
        }
      }
      endpoint_.BeginPeriod(k);
      ArmStateMsg m = ScriptedState(k);
      m.status = endpoint_.status_bits();
      EncodeArmState(static_cast<double>(k), static_cast<double>(k) * kPeriod_s, m, &state);
      endpoint_.Publish(state, *socket_);
    }
  }

  std::unique_ptr<UdpSocket> socket_;
  DeviceEndpoint endpoint_;
  std::mutex mutex_;
  std::vector<ReceivedCommand> commands_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// A scripted peer: the test itself plays the device, datagram by datagram.
using Peer = testing::FakeDevice;

Bytes StatePacket(long k, int joints = 7) {
  ArmStateMsg m = ScriptedState(k);
  m.q.resize(joints);
  m.qd.resize(joints);
  m.tau.resize(joints);
  Bytes out;
  EncodeArmState(static_cast<double>(k), static_cast<double>(k) * kPeriod_s, m, &out);
  return out;
}

// connects an Arm to the peer in the background; the peer plays the device's
// side of the handshake: the describe reply is the test's to send
std::future<Arm> ConnectToPeer(Peer& peer) {
  auto future =
      std::async(std::launch::async, [port = peer.port()] { return Arm::Connect("127.0.0.1", port, kPatience_s); });
  EXPECT_EQ(peer.Handshake(DeviceKind::kArm), 3) << "describe, then describe and subscribe with the cookie";
  return future;
}

template <typename Error, typename F>
std::string ThrownMessage(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "nothing thrown";
  return "";
}

bool Contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

TEST(ClientTest, ConnectDescribesTheArm) {
  ArmServer server;
  Arm arm = Arm::Connect("127.0.0.1", server.port(), kPatience_s);
  EXPECT_EQ(arm.name(), "pa10");
  EXPECT_EQ(arm.kind(), DeviceKind::kArm);
  EXPECT_EQ(arm.joints(), 7);
  EXPECT_EQ(arm.joint_names().front(), "S1");
  EXPECT_EQ(arm.joint_names().back(), "W2");
  ASSERT_EQ(arm.velocity_max().size(), 7u);
  EXPECT_EQ(arm.velocity_max()[2], 2.0);
  EXPECT_NEAR(arm.position_max()[1], 94 * M_PI / 180, 1e-12);
  EXPECT_EQ(arm.describe()["protocol"], 2);
  EXPECT_TRUE(Contains(arm.Label(), "arm 'pa10' at 127.0.0.1:" + std::to_string(server.port())));
  EXPECT_GT(arm.local_port(), 0);
}

TEST(ClientTest, ReadGivesConsecutiveDecodedStates) {
  ArmServer server;
  Arm arm = Arm::Connect("127.0.0.1", server.port(), kPatience_s);
  Arm::State previous = arm.Read(kPatience_s);
  for (int i = 0; i < 20; ++i) {
    Arm::State s = arm.Read(kPatience_s);
    EXPECT_GT(s.seq, previous.seq);  // in order (+1 each, unless a loaded machine overflowed the socket)
    previous.seq = s.seq;
    EXPECT_DOUBLE_EQ(s.time, static_cast<double>(s.seq) * kPeriod_s);
    ASSERT_EQ(s.q.size(), 7);
    for (int j = 0; j < 7; ++j) {
      EXPECT_DOUBLE_EQ(s.q[j], 0.1 * j + 0.001 * static_cast<double>(s.seq));
      EXPECT_DOUBLE_EQ(s.qd[j], -0.5 * j);
      EXPECT_DOUBLE_EQ(s.tau[j], 10.0 * j);
    }
    EXPECT_EQ(s.status, 0u);
  }
}

TEST(ClientTest, WriteReachesTheEndpointWithSeqModeAndValues) {
  ArmServer server;
  Arm arm = Arm::Connect("127.0.0.1", server.port(), kPatience_s);
  const Arm::State s = arm.ReadLatest(kPatience_s);
  Eigen::VectorXd qd_cmd(7);
  qd_cmd << 0.1, -0.2, 0.3, -0.4, 0.5, -0.6, 0.7;
  ASSERT_TRUE(arm.Write(ArmMode::kVelocity, qd_cmd, s.seq));
  ASSERT_TRUE(arm.Write(ArmMode::kVelocity, qd_cmd, s.seq));  // a duplicate: ignored
  const Arm::State s2 = arm.Read(kPatience_s);
  ASSERT_TRUE(arm.Write(ArmMode::kHold, Eigen::VectorXd(), s2.seq));  // hold needs no values

  const auto give_up = steady_clock::now() + std::chrono::duration<double>(kPatience_s);
  while (server.commands().size() < 2 && steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  const std::vector<ReceivedCommand> commands = server.commands();
  ASSERT_EQ(commands.size(), 2u);
  EXPECT_EQ(commands[0].seq, static_cast<double>(s.seq));
  EXPECT_EQ(commands[0].mode, 2);
  ASSERT_EQ(commands[0].value.size(), 7u);
  for (int j = 0; j < 7; ++j) EXPECT_EQ(commands[0].value[j], qd_cmd[j]);
  EXPECT_EQ(commands[1].seq, static_cast<double>(s2.seq));
  EXPECT_EQ(commands[1].mode, 0);
  EXPECT_EQ(server.counters().duplicate, 1);
}

TEST(ClientTest, RefusedAndNotOwnerShowInTheStatus) {
  ArmServer server;
  Arm owner = Arm::Connect("127.0.0.1", server.port(), kPatience_s);
  Arm other = Arm::Connect("127.0.0.1", server.port(), kPatience_s);
  Arm::State s = owner.ReadLatest(kPatience_s);
  Eigen::VectorXd too_fast = Eigen::VectorXd::Constant(7, 0.1);
  owner.Write(ArmMode::kVelocity, too_fast, s.seq);  // accepted: the client owns the arm
  too_fast[0] = 5;                                   // beyond S1's 1 rad/s
  owner.Write(ArmMode::kVelocity, too_fast, owner.Read(kPatience_s).seq);
  other.Write(ArmMode::kVelocity, Eigen::VectorXd::Zero(7), other.ReadLatest(kPatience_s).seq);

  auto wait_for_bit = [](Arm& arm, std::uint32_t bit) {
    const auto give_up = steady_clock::now() + std::chrono::duration<double>(kPatience_s);
    while (steady_clock::now() < give_up) {
      if (arm.Read(kPatience_s).status & bit) return true;
    }
    return false;
  };
  EXPECT_TRUE(wait_for_bit(owner, kStatusRefused));
  EXPECT_TRUE(wait_for_bit(other, kStatusNotOwner));
  EXPECT_EQ(server.counters().refused_limits, 1);
  EXPECT_EQ(server.counters().refused_not_owner, 1);
}

TEST(ClientTest, WriteRefusesTheCallersMistakes) {
  ArmServer server;
  Arm arm = Arm::Connect("127.0.0.1", server.port(), kPatience_s);
  EXPECT_TRUE(Contains(
      ThrownMessage<std::invalid_argument>([&] { arm.Write(ArmMode::kPosition, Eigen::VectorXd::Zero(6), 0); }),
      "6 values, the arm has 7 joints"));
  Eigen::VectorXd nan = Eigen::VectorXd::Zero(7);
  nan[3] = std::nan("");
  EXPECT_THROW(arm.Write(ArmMode::kTorque, nan, 0), std::invalid_argument);
  EXPECT_THROW(arm.Write(ArmMode::kTorque, Eigen::VectorXd::Zero(7), -1), std::invalid_argument);
}

TEST(ClientTest, ReadLatestDrainsTheQueue) {
  Peer peer;
  std::future<Arm> connecting = ConnectToPeer(peer);
  peer.Send(StatePacket(3));  // a state before the reply is skipped
  peer.Send(DescribeJson(Pa10Description()));
  Arm arm = connecting.get();
  peer.Send(StatePacket(5));
  peer.Send(DescribeJson(Pa10Description()));  // a keep-alive reply among the states
  peer.Send(StatePacket(6));
  peer.Send(StatePacket(7));
  // ReadLatest waits for the first and takes what has come after it: drain until 7 (a datagram
  // sent on loopback is queued as it is sent, unless the kernel defers its delivery)
  Arm::State s;
  for (int tries = 0; tries < 10 && s.seq != 7; ++tries) arm.ReadLatest(kPatience_s, &s);
  EXPECT_EQ(s.seq, 7);
  EXPECT_DOUBLE_EQ(s.q[6], 0.6 + 0.007);
  EXPECT_THROW(arm.Read(0.05), TimeoutError);
  peer.Send(StatePacket(8));
  EXPECT_EQ(arm.Read(kPatience_s).seq, 8);
}

TEST(ClientTest, DatagramsFromOtherPortsAreSkipped) {
  Peer peer;
  std::future<Arm> connecting = ConnectToPeer(peer);
  peer.Send(DescribeJson(Pa10Description()));
  Arm arm = connecting.get();
  auto stranger = UdpSocket::Bind("127.0.0.1", 0);
  const Bytes state = StatePacket(1);
  stranger->SendTo(state.data(), state.size(), peer.client());
  EXPECT_THROW(arm.Read(0.2), TimeoutError);
  EXPECT_EQ(arm.skipped(), 1);
}

TEST(ClientTest, MalformedStatesAreProtocolErrors) {
  Peer peer;
  std::future<Arm> connecting = ConnectToPeer(peer);
  peer.Send(DescribeJson(Pa10Description()));
  Arm arm = connecting.get();
  peer.Send(StatePacket(1, 6));  // 6 joints for a 7-joint arm
  EXPECT_TRUE(Contains(ThrownMessage<ProtocolError>([&] { arm.Read(kPatience_s); }), "bad length"));
  Bytes bad = StatePacket(2);
  PutDouble(std::nan(""), bad.data() + 8 * 9);
  peer.Send(bad);
  EXPECT_TRUE(Contains(ThrownMessage<ProtocolError>([&] { arm.Read(kPatience_s); }), "non-finite"));
  Bytes wrench;
  EncodeWrenchState(3, 0, WrenchStateMsg{}, &wrench);
  peer.Send(wrench);
  EXPECT_TRUE(Contains(ThrownMessage<ProtocolError>([&] { arm.Read(kPatience_s); }), "wrong device kind"));
  peer.Send(StatePacket(4));  // the client is still usable
  EXPECT_EQ(arm.Read(kPatience_s).seq, 4);
}

TEST(ClientTest, GarbageReplyIsAProtocolError) {
  {
    Peer peer;
    std::future<Arm> connecting = ConnectToPeer(peer);
    peer.Send(std::string("{\"kind\": \"arm\", \"protocol\": 1,"));
    EXPECT_TRUE(Contains(ThrownMessage<ProtocolError>([&] { connecting.get(); }), "not valid JSON"));
  }
  {
    Peer peer;
    std::future<Arm> connecting = ConnectToPeer(peer);
    peer.Send(Bytes(64, 0xab));
    EXPECT_TRUE(Contains(ThrownMessage<ProtocolError>([&] { connecting.get(); }), "bad magic"));
  }
  {
    Peer peer;
    std::future<Arm> connecting = ConnectToPeer(peer);
    nlohmann::json j = nlohmann::json::parse(DescribeJson(Pa10Description()));
    j["kind"] = "wrench";
    peer.Send(j.dump());
    EXPECT_TRUE(Contains(ThrownMessage<ProtocolError>([&] { connecting.get(); }), "not \"arm\""));
  }
  {
    Peer peer;
    std::future<Arm> connecting = ConnectToPeer(peer);
    nlohmann::json j = nlohmann::json::parse(DescribeJson(Pa10Description()));
    j.erase("joints");
    peer.Send(j.dump());
    EXPECT_TRUE(Contains(ThrownMessage<ProtocolError>([&] { connecting.get(); }), "\"joints\""));
  }
}

TEST(ClientTest, OtherProtocolVersionIsAVersionMismatch) {
  nlohmann::json j = nlohmann::json::parse(DescribeJson(Pa10Description()));
  j["protocol"] = 3;
  ArmServer server(j.dump());
  const std::string message =
      ThrownMessage<VersionMismatch>([&] { Arm::Connect("127.0.0.1", server.port(), kPatience_s); });
  EXPECT_TRUE(Contains(message, "protocol version 3")) << message;
  EXPECT_TRUE(Contains(message, "version 2")) << message;

  // a version-1 binary packet while connecting
  Peer peer;
  std::future<Arm> connecting = ConnectToPeer(peer);
  Bytes v1 = StatePacket(0);
  PutDouble(1.0, v1.data() + 8);
  peer.Send(v1);
  EXPECT_THROW(connecting.get(), VersionMismatch);
}

TEST(ClientTest, SilenceIsATimeoutNamingTheEndpoint) {
  auto silent = UdpSocket::Bind("127.0.0.1", 0);  // bound, never answers
  const auto begin = steady_clock::now();
  const std::string message =
      ThrownMessage<TimeoutError>([&] { Arm::Connect("127.0.0.1", silent->local_port(), 0.3); });
  EXPECT_TRUE(Contains(message, "127.0.0.1:" + std::to_string(silent->local_port()))) << message;
  EXPECT_TRUE(Contains(message, "no answer")) << message;
  EXPECT_GE(std::chrono::duration<double>(steady_clock::now() - begin).count(), 0.29);
}

TEST(ClientTest, AnotherKindsDeviceDoesNotConnect) {
  // every device answers a describe request: a wrench handle on an arm's port learns it is an arm
  ArmServer server;
  const std::string message = ThrownMessage<ProtocolError>([&] { Wrench::Connect("127.0.0.1", server.port(), 1.0); });
  EXPECT_TRUE(Contains(message, "arm")) << message;
  EXPECT_TRUE(Contains(message, "127.0.0.1:" + std::to_string(server.port()))) << message;
}

TEST(ClientTest, BadAddressIsANetworkError) {
  EXPECT_TRUE(Contains(ThrownMessage<NetworkError>([] { Arm::Connect("300.1.2.3", 50010); }), "300.1.2.3"));
  EXPECT_THROW(Arm::Connect("no such host!", 50010), NetworkError);
  EXPECT_THROW(Arm::Connect("127.0.0.1", 70000), NetworkError);
  EXPECT_THROW(Arm::Connect("127.0.0.1", 0), NetworkError);
}

TEST(FixedRateLoopTest, KeepsItsAverageRate) {
  FixedRateLoop loop(200);  // 5 ms
  EXPECT_DOUBLE_EQ(loop.period_s(), 0.005);
  const auto begin = steady_clock::now();
  for (int i = 0; i < 40; ++i) loop.Wait();
  const double elapsed = std::chrono::duration<double>(steady_clock::now() - begin).count();
  EXPECT_EQ(loop.iterations(), 40);
  // never early: deadline 40 is 0.2 s after the start
  EXPECT_GE(elapsed, 0.2 - 1e-3);
  // and not late unless the machine made it overrun (then deadlines were skipped):
  // with every deadline met, only the last wake-up's latency is added, so 1.5x
  // the interval is far from the bound
  if (loop.overruns() == 0) {
    EXPECT_LT(elapsed, 1.5 * 0.2);
  }
}

TEST(FixedRateLoopTest, CountsOverrunsAndKeepsThePhase) {
  FixedRateLoop loop(100);  // 10 ms
  for (int i = 0; i < 5; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(25));  // a body slower than the period
    EXPECT_FALSE(loop.Wait());
  }
  EXPECT_EQ(loop.overruns(), 5);
  EXPECT_EQ(loop.iterations(), 5);
  EXPECT_THROW({ FixedRateLoop bad(0); }, std::invalid_argument);
  EXPECT_THROW({ FixedRateLoop bad(-5); }, std::invalid_argument);
}

}  // namespace
}  // namespace vlab::bridge::client_test
