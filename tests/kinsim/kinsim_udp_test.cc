// vlab-kinsim end to end over loopback: the real executable, a test client made
// of bridge/ only (protocol + UdpSocket). Timeouts are seconds; the kinematic
// arm makes the motion checks exact, so only the wall clock is loose.
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bridge/bridge_client.h"
#include "bridge/bridge_protocol.h"
#include "bridge/bridge_udp.h"
#include "kinsim_process.h"
#include "test_util.h"
#include "wire_session.h"

namespace vlab::bridge {
namespace {

using Clock = std::chrono::steady_clock;
constexpr int kJoints = 7;

double Seconds(Clock::time_point since) { return std::chrono::duration<double>(Clock::now() - since).count(); }

/// A test client: one socket, the device's endpoint, the newest state read.
struct Client {
  explicit Client(int port)
      : socket(UdpSocket::Bind("127.0.0.1", 0)), device(UdpSocket::MakeEndpoint("127.0.0.1", port)) {}

  void SendRaw(const std::vector<unsigned char>& packet) { socket->SendTo(packet.data(), packet.size(), device); }
  void Send(double seq, int mode, const std::vector<double>& value) {
    std::vector<unsigned char> packet;
    EncodeArmCommand(seq, 0.0, ArmCommandMsg{mode, value}, &packet);
    SendRaw(packet);
  }
  /// Subscribes (the cookie handshake), then asks for the describe reply.
  void Subscribe() {
    const double cookie = vlab::testing::WireSubscribe(*socket, device, DeviceKind::kArm);
    std::vector<unsigned char> packet;
    EncodeDescribeRequest(static_cast<int>(DeviceKind::kArm), cookie, &packet);
    SendRaw(packet);
  }
  /// Next datagram that is JSON (a describe reply), within timeout_s; "" if none.
  std::string NextJson(double timeout_s) {
    const Clock::time_point start = Clock::now();
    unsigned char buffer[65536];
    while (Seconds(start) < timeout_s) {
      const long n = socket->Receive(buffer, sizeof(buffer), nullptr, 0.1);
      if (n > 0 && buffer[0] == '{') return std::string(reinterpret_cast<char*>(buffer), static_cast<std::size_t>(n));
    }
    return "";
  }
  /// Next arm state (JSON replies skipped) into `state` and `header`, within timeout_s.
  bool NextState(double timeout_s = 5) {
    const Clock::time_point start = Clock::now();
    unsigned char buffer[8192];
    std::vector<double> payload;
    while (Seconds(start) < timeout_s) {
      const long n = socket->Receive(buffer, sizeof(buffer), nullptr, 0.1);
      if (n <= 0 || buffer[0] == '{') continue;
      if (DecodePacket(buffer, static_cast<std::size_t>(n), &header, &payload) != DecodeError::kNone) continue;
      if (ParseArmState(header, payload, kJoints, &state) == DecodeError::kNone) return true;
    }
    return false;
  }
  /// Answers every state with the same command for `seconds` (seq = the state's seq).
  bool Stream(int mode, const std::vector<double>& value, double seconds) {
    const Clock::time_point start = Clock::now();
    while (Seconds(start) < seconds) {
      if (!NextState()) return false;
      Send(header.seq, mode, value);
      last_sent_seq = header.seq;
    }
    return true;
  }

  /// Returns once the device has handled every datagram sent so far: the
  /// states queued here are dropped; the first state read after that closes a
  /// period that may have begun before the send, the one after it cannot have.
  bool Settle() {
    unsigned char buffer[8192];
    while (socket->Receive(buffer, sizeof(buffer), nullptr, 0.0) >= 0) {
    }
    if (!NextState()) return false;
    const double first = header.seq;
    while (header.seq < first + 1) {
      if (!NextState()) return false;
    }
    return true;
  }

  std::unique_ptr<UdpSocket> socket;
  Endpoint device;
  Header header;
  ArmStateMsg state;
  double last_sent_seq = -1;
};

class KinsimUdpTest : public ::testing::Test {
 protected:
  void Start(std::vector<std::string> args = {}) {
    process_ = std::make_unique<testing::KinsimProcess>(std::move(args));
    ASSERT_TRUE(process_->ok()) << "no start line; stdout: " << process_->output();
  }
  /// Stops the server (SIGINT), expects exit 0, returns its report.
  std::string StopReport() {
    EXPECT_EQ(process_->Stop(), 0) << process_->output();
    return process_->output();
  }
  std::unique_ptr<testing::KinsimProcess> process_;
  const std::vector<double> v_ = {0.2, -0.1, 0.3, 0.0, 0.25, -0.2, 0.5};  // rad/s, within pi
};

bool Has(std::uint32_t status, std::uint32_t bit) { return (status & bit) != 0; }

TEST_F(KinsimUdpTest, StartLineAndDescribe) {
  Start({"--rate", "500"});
  EXPECT_EQ(process_->start_line(),
            "vlab-kinsim: arm 'pa10' (7 joints) on 127.0.0.1:" + std::to_string(process_->port()) + ", 500 Hz");
  Client c(process_->port());
  c.Subscribe();
  const std::string text = c.NextJson(5);
  ASSERT_FALSE(text.empty()) << "no describe reply";
  const nlohmann::json j = nlohmann::json::parse(text);
  EXPECT_EQ(j["kind"], "arm");
  EXPECT_EQ(j["protocol"], 2);
  EXPECT_EQ(j["name"], "pa10");
  EXPECT_EQ(j["server"], "vlab-kinsim");
  EXPECT_EQ(j["clock"], "realtime");
  EXPECT_EQ(j["endpoint"]["port"], process_->port());
  EXPECT_EQ(j["rates"]["control_hz"], 500.0);
  EXPECT_EQ(j["joints"], (std::vector<std::string>{"S1", "S2", "S3", "E1", "E2", "W1", "W2"}));
  EXPECT_EQ(j["layout"]["state"], (std::vector<std::string>{"status", "q[7]", "qd[7]", "tau[7]"}));
  const double degrees[kJoints] = {177, 94, 174, 137, 255, 165, 255};
  ASSERT_EQ(j["limits"]["position_min"].size(), 7u);
  ASSERT_EQ(j["limits"]["velocity_max"].size(), 7u);
  for (int i = 0; i < kJoints; ++i) {
    EXPECT_NEAR(j["limits"]["position_max"][i].get<double>(), degrees[i] * M_PI / 180, 1e-9);
    EXPECT_NEAR(j["limits"]["position_min"][i].get<double>(), -degrees[i] * M_PI / 180, 1e-9);
    EXPECT_DOUBLE_EQ(j["limits"]["velocity_max"][i].get<double>(), M_PI);
  }
  EXPECT_TRUE(j["limits"]["torque_max"].empty());
  EXPECT_EQ(j["watchdog_periods"], 3);
  EXPECT_EQ(j["owner_timeout_s"], 1.0);
  const std::string report = StopReport();
  EXPECT_NE(report.find("describes 1"), std::string::npos) << report;
}

TEST_F(KinsimUdpTest, StatesArriveWithIncreasingSeqHoldingTheReadyPose) {
  Start();
  Client c(process_->port());
  c.Subscribe();
  ASSERT_TRUE(c.NextState());
  double seq = c.header.seq;
  for (int i = 0; i < 100; ++i) {
    ASSERT_TRUE(c.NextState());
    EXPECT_GT(c.header.seq, seq);
    EXPECT_DOUBLE_EQ(c.header.time, c.header.seq / 500.0);
    seq = c.header.seq;
  }
  EXPECT_EQ(c.state.status, kStatusHolding);  // no command yet
  EXPECT_EQ(c.state.q, (std::vector<double>{0, 0.523599, 0, 1.047198, 0, 1.570796, 0}));
  EXPECT_EQ(c.state.tau, std::vector<double>(kJoints, 0.0));
  StopReport();
}

TEST_F(KinsimUdpTest, VelocityCommandMovesTheJointsAtTheCommandedRate) {
  Start({"--watchdog-periods", "50"});  // 0.1 s: a busy test machine must not trip it
  Client c(process_->port());
  c.Subscribe();
  // stream until the command is in force, then measure over ~0.5 s
  ASSERT_TRUE(c.Stream(2, v_, 0.05));
  ASSERT_TRUE(c.Stream(2, v_, 0.05));
  ASSERT_EQ(c.state.qd, v_);
  const ArmStateMsg first = c.state;
  const double t0 = c.header.time;
  const Clock::time_point wall0 = Clock::now();
  ASSERT_TRUE(c.Stream(2, v_, 0.5));
  const double dt = c.header.time - t0;
  const double wall = Seconds(wall0);
  // a realtime server: its state clock keeps the wall clock's pace over 0.5 s
  // within 1.5x either way (the two ends differ by a receive latency of about
  // a period; only stalls of a third of the interval would reach the bound)
  EXPECT_GT(dt, wall / 1.5) << "the state clock fell behind the wall clock";
  EXPECT_LT(dt, 1.5 * wall) << "the state clock ran ahead of the wall clock";
  for (int i = 0; i < kJoints; ++i) {
    EXPECT_NEAR((c.state.q[i] - first.q[i]) / dt, v_[i], 0.05 * std::abs(v_[i]) + 1e-9) << "joint " << i;
  }
  EXPECT_EQ(c.state.qd, v_);
  EXPECT_FALSE(Has(c.state.status, kStatusHolding | kStatusRefused | kStatusNotOwner));
  StopReport();
}

// after a refused command: the refused bit in the next states, the velocity command still in force
void ExpectRefusedKeepsVelocity(Client& c, const std::vector<double>& v, const char* what) {
  bool seen = false;
  for (int i = 0; i < 20 && c.NextState(); ++i) {
    if (!Has(c.state.status, kStatusRefused)) continue;
    seen = true;
    EXPECT_EQ(c.state.qd, v) << what;
  }
  EXPECT_TRUE(seen) << what << ": no state with the refused bit";
}

TEST_F(KinsimUdpTest, NanOutOfLimitAndTorqueCommandsAreRefused) {
  Start({"--watchdog-periods", "200"});  // the checks read 20 states without commanding
  Client c(process_->port());
  c.Subscribe();
  ASSERT_TRUE(c.Stream(2, v_, 0.1));
  ASSERT_TRUE(c.NextState());
  ASSERT_EQ(c.state.qd, v_);

  std::vector<double> nan = v_;
  nan[3] = std::numeric_limits<double>::quiet_NaN();
  c.Send(c.header.seq, 2, nan);
  ExpectRefusedKeepsVelocity(c, v_, "NaN");

  ASSERT_TRUE(c.Stream(2, v_, 0.05));
  ASSERT_TRUE(c.NextState());
  EXPECT_FALSE(Has(c.state.status, kStatusRefused)) << "an accepted command clears the bit";
  std::vector<double> fast = v_;
  fast[0] = 4.0;  // rad/s, beyond pi
  c.Send(c.header.seq, 2, fast);
  ExpectRefusedKeepsVelocity(c, v_, "velocity beyond the limit");

  ASSERT_TRUE(c.Stream(2, v_, 0.05));
  ASSERT_TRUE(c.NextState());
  std::vector<double> far = {0, 2.0, 0, 0, 0, 0, 0};  // S2 beyond 94 deg
  c.Send(c.header.seq, 1, far);
  ExpectRefusedKeepsVelocity(c, v_, "position beyond the limit");

  ASSERT_TRUE(c.Stream(2, v_, 0.05));
  ASSERT_TRUE(c.NextState());
  c.Send(c.header.seq, 3, std::vector<double>(kJoints, 1.0));
  ExpectRefusedKeepsVelocity(c, v_, "torque");

  const std::string report = StopReport();
  EXPECT_NE(report.find("malformed 1, limits 2, not owner 0, torque mode 1"), std::string::npos) << report;
}

TEST_F(KinsimUdpTest, SilenceTripsTheWatchdog) {
  constexpr int kWatchdog = 5;
  Start({"--watchdog-periods", std::to_string(kWatchdog)});
  Client c(process_->port());
  c.Subscribe();
  ASSERT_TRUE(c.Stream(2, v_, 0.1));
  // the last command differs from the stream's, so the state that first carries
  // it names the period that took it: the watchdog is timed on the state clock,
  // whatever the machine's load did to the wall clock
  std::vector<double> last_v = v_;
  for (double& v : last_v) v *= 0.5;
  ASSERT_TRUE(c.NextState());  // a seq the stream has not used: a repeated one is refused
  c.Send(c.header.seq, 2, last_v);
  double taken = -1;
  const Clock::time_point start = Clock::now();
  bool held = false;
  while (!held && Seconds(start) < 5 && c.NextState()) {
    if (taken < 0 && c.state.qd == last_v) taken = c.header.seq;
    held = taken >= 0 && Has(c.state.status, kStatusWatchdog);
  }
  ASSERT_GE(taken, 0) << "the last command never showed in a state";
  ASSERT_TRUE(held) << "no watchdog bit within 5 s of silence";
  // the rule (protocol.md): hold once more than watchdog_periods periods passed
  // without a command, i.e. in period taken + watchdog_periods + 1 exactly
  EXPECT_EQ(c.header.seq - taken, kWatchdog + 1);
  EXPECT_TRUE(Has(c.state.status, kStatusHolding));
  EXPECT_EQ(c.state.qd, std::vector<double>(kJoints, 0.0));
  const std::vector<double> q = c.state.q;
  for (int i = 0; i < 20; ++i) {
    ASSERT_TRUE(c.NextState());
    EXPECT_TRUE(Has(c.state.status, kStatusWatchdog | kStatusHolding));
    EXPECT_EQ(c.state.q, q);
  }
  const std::string report = StopReport();
  EXPECT_EQ(report.find("watchdog holds 0"), std::string::npos) << report;
}

// torque commands pass the endpoint's checks and are refused by the kinematic
// arm; they must not keep the owner's last velocity command alive
TEST_F(KinsimUdpTest, AnOwnerSendingOnlyTorquesIsHeldByTheWatchdog) {
  Start({"--watchdog-periods", "10"});
  Client c(process_->port());
  c.Subscribe();
  ASSERT_TRUE(c.Stream(2, v_, 0.1));
  const Clock::time_point start = Clock::now();
  bool held = false;
  while (!held && Seconds(start) < 5) {
    ASSERT_TRUE(c.NextState());
    c.Send(c.header.seq, 3, std::vector<double>(kJoints, 0.5));
    held = Has(c.state.status, kStatusWatchdog);
  }
  ASSERT_TRUE(held) << "the arm kept moving under refused torque commands";
  EXPECT_TRUE(Has(c.state.status, kStatusHolding | kStatusRefused));
  EXPECT_EQ(c.state.qd, std::vector<double>(kJoints, 0.0));
  const std::string report = StopReport();
  EXPECT_EQ(report.find("watchdog holds 0"), std::string::npos) << report;
}

TEST_F(KinsimUdpTest, SecondClientIsNotTheOwner) {
  Start({"--watchdog-periods", "50"});
  Client owner(process_->port());
  Client other(process_->port());
  owner.Subscribe();
  ASSERT_TRUE(owner.Stream(2, v_, 0.05));
  other.Subscribe();  // (a non-subscriber's commands are refused as such, before ownership counts)
  // the other client commands while the owner streams
  const std::vector<double> v_other(kJoints, -0.3);
  const Clock::time_point start = Clock::now();
  int sent = 0;
  while (Seconds(start) < 0.3) {
    ASSERT_TRUE(owner.NextState());
    owner.Send(owner.header.seq, 2, v_);
    if (owner.header.seq > 0 && static_cast<long>(owner.header.seq) % 10 == 0) {
      other.Send(owner.header.seq, 2, v_other);
      ++sent;
    }
    EXPECT_FALSE(Has(owner.state.status, kStatusNotOwner));
  }
  EXPECT_EQ(owner.state.qd, v_) << "the other client's commands changed the motion";
  ASSERT_GT(sent, 0);
  int states = 0;
  for (; states < 20 && other.NextState(); ++states) {
    EXPECT_TRUE(Has(other.state.status, kStatusNotOwner));
    EXPECT_EQ(other.state.qd, v_);
  }
  EXPECT_GT(states, 0) << "the other client received no states";
  ASSERT_TRUE(other.Settle());
  const std::string report = StopReport();
  EXPECT_NE(report.find("not owner " + std::to_string(sent)), std::string::npos) << report;
}

// the payload (type 6) through the C++ client: the owner's are taken (two in a row: the handle's
// payload counter grows) and reported (no dynamics: "feedforward": "none"), another client's is
// refused with result 7
TEST_F(KinsimUdpTest, APayloadIsTakenFromTheOwnerAndReported) {
  Start({"--watchdog-periods", "0"});
  vlab::bridge::Arm owner = vlab::bridge::Arm::Connect("127.0.0.1", process_->port(), 5.0);
  EXPECT_EQ(owner.describe()["feedforward"], "none");
  EXPECT_EQ(owner.payload().mass_kg, 0.0);
  ArmPayloadMsg load;
  load.mass_kg = 2.5;
  load.com_m = {0, 0, 0.1};
  load.inertia_kgm2 = {0.02, 0.02, 0.01, 0, 0, 0};
  ArmPayloadMsg lighter = load;
  lighter.mass_kg = 1.0;
  owner.SetPayload(lighter, 5.0);  // seq 1
  owner.SetPayload(load, 5.0);     // seq 2: the handle's counter grows, both are taken
  vlab::bridge::Arm other = vlab::bridge::Arm::Connect("127.0.0.1", process_->port(), 5.0);
  EXPECT_EQ(other.payload(), load);  // its describe reply at connect reports the owner's
  EXPECT_THROW(other.SetPayload(lighter, 5.0), vlab::bridge::RefusedError);
  load.inertia_kgm2 = {0.01, 0.01, 0.03, 0, 0, 0};  // no rigid body: the client says so before sending
  EXPECT_THROW(owner.SetPayload(load, 5.0), std::invalid_argument);
  const std::string report = StopReport();
  EXPECT_NE(report.find("payloads 2"), std::string::npos) << report;
  EXPECT_NE(report.find("not owner 1"), std::string::npos) << report;
}

TEST_F(KinsimUdpTest, StaleAndDuplicateSeqAreIgnored) {
  Start({"--watchdog-periods", "200"});
  Client c(process_->port());
  c.Subscribe();
  ASSERT_TRUE(c.Stream(2, v_, 0.1));
  const double last = c.last_sent_seq;
  const std::vector<double> v2(kJoints, 0.1);
  c.Send(last - 5, 2, v2);  // stale
  c.Send(last, 2, v2);      // duplicate
  ASSERT_TRUE(c.Settle());
  for (int i = 0; i < 20; ++i) {
    ASSERT_TRUE(c.NextState());
    EXPECT_EQ(c.state.qd, v_) << "a stale or duplicate command was applied";
    EXPECT_FALSE(Has(c.state.status, kStatusRefused));
  }
  const std::string report = StopReport();
  EXPECT_NE(report.find("stale 1, duplicate 1"), std::string::npos) << report;
}

// bad input: one line on stderr naming the cause, exit 2
struct Outcome {
  int exit_code;
  std::string err;
};
Outcome RunKinsim(const std::string& args) {
  testing::TempDir tmp;
  const std::string cmd = "cd '" VLAB_SOURCE_DIR "' && timeout 30 '" VLAB_BINARY_DIR "/vlab-kinsim' " + args +
                          " --duration 0.05 >/dev/null 2>'" + (tmp / "err") + "' </dev/null";
  const int status = std::system(cmd.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, testing::ReadFile(tmp / "err")};
}

void ExpectBadInput(const std::string& args, const std::string& cause) {
  const Outcome o = RunKinsim(args);
  EXPECT_EQ(o.exit_code, 2) << args << ": " << o.err;
  EXPECT_EQ(testing::Lines(o.err).size(), 1u) << o.err;
  EXPECT_NE(o.err.find(cause), std::string::npos) << o.err;
}

TEST(KinsimCliTest, BadInputIsOneLineAndExitTwo) {
  ExpectBadInput("--scene no_such_scene.xml", "scene 'no_such_scene.xml': cannot open file");
  ExpectBadInput("--joints S1,S2,elbow --initial 0,0,0", "no joint 'elbow'");
  ExpectBadInput("--rate fast", "--rate");
  ExpectBadInput("--no-such-option", "--no-such-option");
  ExpectBadInput("--initial 0,0,0,0,0,0,9", "joint 'W2': initial position 9 rad is outside");
  auto taken = UdpSocket::Bind("127.0.0.1", 0);
  ExpectBadInput("--port " + std::to_string(taken->local_port()),
                 "cannot bind UDP 127.0.0.1:" + std::to_string(taken->local_port()));
}

}  // namespace
}  // namespace vlab::bridge
