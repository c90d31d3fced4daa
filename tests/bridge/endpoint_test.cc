// Tests the DeviceEndpoint rules for the kinds that take commands through the
// generic path (base, gripper, point: EndpointConfig::command_length and
// check_command), and for output-only kinds, over real loopback sockets.
#include "bridge/bridge_endpoint.h"

#include <cmath>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "bridge/bridge_layouts.h"

namespace vlab::bridge {
namespace {

using Bytes = std::vector<unsigned char>;

// A base: [frame, vx, vy, wz], frame 0 or 1, |v| <= 1 m/s, |wz| <= 2 rad/s.
EndpointConfig BaseConfig() {
  EndpointConfig c;
  c.name = "nomad";
  c.kind = DeviceKind::kBase;
  c.describe_json = R"({"name":"nomad","kind":"base"})";
  c.command_length = CommandLength(DeviceKind::kBase);
  c.status_first = true;
  c.watchdog_periods = 3;
  c.check_command = [](const std::vector<double>& p) {
    const auto at = [&p](const char* field) { return p[CommandIndex(DeviceKind::kBase, field)]; };
    if (at("frame") != 0 && at("frame") != 1) return CommandCheck::kMalformed;
    if (std::abs(at("vx")) > 1 || std::abs(at("vy")) > 1 || std::abs(at("wz")) > 2) return CommandCheck::kLimits;
    return CommandCheck::kAccept;
  };
  return c;
}

class EndpointTest : public ::testing::Test {
 protected:
  std::unique_ptr<UdpSocket> device_ = UdpSocket::Bind("127.0.0.1", 0);
  std::unique_ptr<UdpSocket> client_ = UdpSocket::Bind("127.0.0.1", 0);
  std::unique_ptr<UdpSocket> other_ = UdpSocket::Bind("127.0.0.1", 0);

  bool Send(DeviceEndpoint& e, UdpSocket& from, int kind, double seq, std::vector<double> payload, long period) {
    Header h;
    h.kind = kind;
    h.type = static_cast<int>(MessageType::kCommand);
    h.seq = seq;
    h.length = static_cast<int>(payload.size());
    Bytes packet;
    EncodePacket(h, payload.data(), h.length, &packet);
    return e.Handle(packet.data(), packet.size(), from.local_endpoint(), period, *device_);
  }
};

TEST_F(EndpointTest, BaseCommandsAreCheckedAndTaken) {
  DeviceEndpoint e(BaseConfig());
  const int base = static_cast<int>(DeviceKind::kBase);
  std::vector<double> taken;
  EXPECT_FALSE(e.TakeCommand(&taken));
  EXPECT_TRUE(Send(e, *client_, base, 1, {0, 0.5, -0.2, 0.1}, 1));
  ASSERT_TRUE(e.TakeCommand(&taken));
  EXPECT_EQ(taken, (std::vector<double>{0, 0.5, -0.2, 0.1}));
  EXPECT_FALSE(e.TakeCommand(&taken));  // taken once

  EXPECT_FALSE(Send(e, *client_, base, 2, {2, 0, 0, 0}, 2));        // unknown frame
  EXPECT_FALSE(Send(e, *client_, base, 3, {0, 1.5, 0, 0}, 3));      // beyond a limit
  EXPECT_FALSE(Send(e, *client_, base, 4, {0, 0, 0}, 4));           // wrong length
  EXPECT_FALSE(Send(e, *client_, static_cast<int>(DeviceKind::kArm), 5, {0, 0}, 5));  // wrong kind
  EXPECT_FALSE(Send(e, *client_, base, 0, {0, 0, 0, 0}, 6));        // stale
  EXPECT_FALSE(Send(e, *other_, base, 9, {0, 0, 0, 0}, 6));         // not the owner
  const EndpointCounters& n = e.counters();
  EXPECT_EQ(n.accepted, 1);
  EXPECT_EQ(n.refused_malformed, 3);
  EXPECT_EQ(n.refused_limits, 1);
  EXPECT_EQ(n.refused_not_owner, 1);
  EXPECT_EQ(n.stale, 1);
  EXPECT_TRUE(e.status_bits() & kStatusRefused);  // the owner's last command was refused
  EXPECT_FALSE(e.TakeCommand(&taken));  // refusals leave nothing to take

  EXPECT_TRUE(Send(e, *client_, base, 10, {1, 0, 0, 2}, 7));
  EXPECT_EQ(e.status_bits(), 0u);
}

TEST_F(EndpointTest, WatchdogHoldsABaseWhoseCommandsStop) {
  DeviceEndpoint e(BaseConfig());
  EXPECT_FALSE(e.BeginPeriod(5));  // never commanded: no watchdog
  EXPECT_TRUE(Send(e, *client_, static_cast<int>(DeviceKind::kBase), 0, {0, 0.1, 0, 0}, 10));
  for (long k = 11; k <= 13; ++k) EXPECT_FALSE(e.BeginPeriod(k)) << k;
  EXPECT_TRUE(e.BeginPeriod(14));  // the 4th period without a command
  EXPECT_EQ(e.status_bits() & (kStatusWatchdog | kStatusHolding), kStatusWatchdog | kStatusHolding);
  EXPECT_EQ(e.counters().watchdog_holds, 1);
  EXPECT_TRUE(Send(e, *client_, static_cast<int>(DeviceKind::kBase), 1, {0, 0, 0, 0}, 15));
  EXPECT_FALSE(e.BeginPeriod(15));
}

TEST_F(EndpointTest, OutputOnlyKindsRefuseCommandsButAnswerDescribe) {
  EndpointConfig c;
  c.kind = DeviceKind::kFeet;
  c.describe_json = R"({"kind":"feet"})";
  DeviceEndpoint e(c);
  EXPECT_FALSE(Send(e, *client_, static_cast<int>(DeviceKind::kFeet), 0, {1, 2}, 0));
  EXPECT_EQ(e.counters().refused_malformed, 1);
  Bytes request;
  EncodeDescribeRequest(DeviceKind::kFeet, &request);
  e.Handle(request.data(), request.size(), client_->local_endpoint(), 1, *device_);
  unsigned char reply[256];
  Endpoint from;
  const long n = client_->Receive(reply, sizeof reply, &from, 2.0);
  ASSERT_GT(n, 0);
  EXPECT_EQ(std::string(reinterpret_cast<char*>(reply), static_cast<std::size_t>(n)), c.describe_json);
  EXPECT_FALSE(e.BeginPeriod(100));  // nothing to watch
}

TEST_F(EndpointTest, NonOwnersOfABaseSeeNotOwnerInTheStatus) {
  DeviceEndpoint e(BaseConfig());
  const int base = static_cast<int>(DeviceKind::kBase);
  ASSERT_TRUE(Send(e, *client_, base, 0, {0, 0, 0, 0}, 0));
  Bytes request;
  EncodeDescribeRequest(DeviceKind::kBase, &request);
  e.Handle(request.data(), request.size(), other_->local_endpoint(), 0, *device_);  // subscribes
  unsigned char buffer[512];
  Endpoint from;
  ASSERT_GT(other_->Receive(buffer, sizeof buffer, &from, 2.0), 0);  // the describe reply
  Header h;
  h.kind = base;
  h.type = static_cast<int>(MessageType::kState);
  h.length = 7;
  const double state[7] = {0, 1, 2, 3, 4, 5, 6};
  Bytes packet;
  EncodePacket(h, state, 7, &packet);
  e.Publish(packet, *device_);
  for (UdpSocket* s : {client_.get(), other_.get()}) {
    const long n = s->Receive(buffer, sizeof buffer, &from, 2.0);
    ASSERT_EQ(n, static_cast<long>(packet.size()));
    const double status = GetDouble(buffer + kHeaderBytes + 8 * StateIndex(DeviceKind::kBase, "status"));
    EXPECT_EQ(status, s == other_.get() ? static_cast<double>(kStatusNotOwner) : 0.0);
  }
}

}  // namespace
}  // namespace vlab::bridge
