// Tests the DeviceEndpoint rules: sessions (the cookie handshake, explicit
// subscription, the full table, the describe rate limit), ownership on the
// wall clock, the seq window, and the kinds that take commands through the
// generic path (base, gripper, point: EndpointConfig::command_length and
// check_command) and output-only kinds, over real loopback sockets.
#include "bridge/bridge_endpoint.h"

#include <fcntl.h>

#include <cmath>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "bridge/bridge_layouts.h"
#include "bridge/endpoint_fixture.h"

namespace vlab::bridge::endpoint_test {
namespace {

TEST_F(EndpointTest, BaseCommandsAreCheckedAndTaken) {
  DeviceEndpoint e(BaseConfig());
  const int base = static_cast<int>(DeviceKind::kBase);
  Subscribe(e, *client_);
  Subscribe(e, *other_);
  PublishBase(e, 10);
  std::vector<double> taken;
  EXPECT_FALSE(e.TakeCommand(&taken));
  EXPECT_TRUE(Send(e, *client_, base, 1, {0, 0.5, -0.2, 0.1}, 1));
  ASSERT_TRUE(e.TakeCommand(&taken));
  EXPECT_EQ(taken, (std::vector<double>{0, 0.5, -0.2, 0.1}));
  EXPECT_FALSE(e.TakeCommand(&taken));  // taken once

  EXPECT_FALSE(Send(e, *client_, base, 2, {2, 0, 0, 0}, 2));                          // unknown frame
  EXPECT_FALSE(Send(e, *client_, base, 3, {0, 1.5, 0, 0}, 3));                        // beyond a limit
  EXPECT_FALSE(Send(e, *client_, base, 4, {0, 0, 0}, 4));                             // wrong length
  EXPECT_FALSE(Send(e, *client_, static_cast<int>(DeviceKind::kArm), 5, {0, 0}, 5));  // wrong kind
  EXPECT_FALSE(Send(e, *client_, base, 0, {0, 0, 0, 0}, 6));                          // stale
  EXPECT_FALSE(Send(e, *other_, base, 9, {0, 0, 0, 0}, 6));                           // not the owner
  const EndpointCounters& n = e.counters();
  EXPECT_EQ(n.accepted, 1);
  EXPECT_EQ(n.refused_malformed, 3);
  EXPECT_EQ(n.refused_limits, 1);
  EXPECT_EQ(n.refused_not_owner, 1);
  EXPECT_EQ(n.stale, 1);
  EXPECT_EQ(n.stale_window, 0);                   // a late copy, not a reply fallen out of the window
  EXPECT_TRUE(e.status_bits() & kStatusRefused);  // the owner's last command was refused
  EXPECT_FALSE(e.TakeCommand(&taken));            // refusals leave nothing to take

  EXPECT_TRUE(Send(e, *client_, base, 10, {1, 0, 0, 2}, 7));
  EXPECT_EQ(e.status_bits(), 0u);
}

TEST_F(EndpointTest, WatchdogHoldsABaseWhoseCommandsStop) {
  DeviceEndpoint e(BaseConfig());
  Subscribe(e, *client_);
  PublishBase(e, 1);
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
  EncodeDescribeRequest(static_cast<int>(DeviceKind::kFeet), 0, &request);
  const double cookie = Reply(Request(e, *client_, request)).first;
  EncodeDescribeRequest(static_cast<int>(DeviceKind::kFeet), cookie, &request);
  const long n = Request(e, *client_, request);
  ASSERT_GT(n, 0);
  EXPECT_EQ(std::string(reinterpret_cast<char*>(buffer_), static_cast<std::size_t>(n)), c.describe_json);
  EXPECT_FALSE(e.BeginPeriod(100));  // nothing to watch
}

TEST_F(EndpointTest, NonOwnersOfABaseSeeNotOwnerInTheStatus) {
  DeviceEndpoint e(BaseConfig());
  const int base = static_cast<int>(DeviceKind::kBase);
  Subscribe(e, *client_);
  PublishBase(e, 0);
  Drain(*client_);
  ASSERT_TRUE(Send(e, *client_, base, 0, {0, 0, 0, 0}, 0));
  Subscribe(e, *other_);
  unsigned char buffer[512];
  Endpoint from;
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

TEST_F(EndpointTest, AnUnprovenSourceGetsOnlyAChallengeOfItsOwnSize) {
  DeviceEndpoint e(BaseConfig());
  // a describe request without the cookie: a 72-byte challenge back, no JSON, no subscription
  Bytes request;
  EncodeDescribeRequest(0, 0, &request);
  ASSERT_EQ(request.size(), 72u);
  const long n = Request(e, *client_, request);
  EXPECT_EQ(n, 72);
  const auto [cookie, result] = Reply(n);
  EXPECT_EQ(result, SessionResult::kChallenge);
  EXPECT_GE(cookie, 1);
  EXPECT_LT(cookie, 9007199254740992.0);
  EXPECT_EQ(e.counters().describes, 0);
  // a wrong cookie is a challenge again; a subscribe request too
  EncodeSubscribeRequest(DeviceKind::kBase, cookie + 1, 1, &request);
  EXPECT_EQ(Reply(Request(e, *client_, request)).second, SessionResult::kChallenge);
  EXPECT_EQ(e.subscribers(), 0);
  // another source's cookie does not open the door for this one: cookies depend on the port
  EncodeSubscribeRequest(DeviceKind::kBase, cookie, 1, &request);
  EXPECT_EQ(Reply(Request(e, *other_, request)).second, SessionResult::kChallenge);
  EXPECT_EQ(e.subscribers(), 0);
  EXPECT_EQ(e.counters().sessions.challenges, 3);
  // nobody subscribed: a state goes nowhere
  PublishBase(e, 0);
  Endpoint from;
  EXPECT_LT(client_->Receive(buffer_, sizeof buffer_, &from, 0.1), 0);
  EXPECT_LT(other_->Receive(buffer_, sizeof buffer_, &from, 0.1), 0);
  // with the cookie: the JSON
  EncodeDescribeRequest(static_cast<int>(DeviceKind::kBase), cookie, &request);
  const long json = Request(e, *client_, request);
  ASSERT_GT(json, 0);
  EXPECT_EQ(buffer_[0], '{');
  EXPECT_EQ(e.counters().describes, 1);
}

TEST_F(EndpointTest, CommandsFromNonSubscribersAreRefusedAndDoNotSubscribe) {
  DeviceEndpoint e(BaseConfig());
  PublishBase(e, 5);
  EXPECT_FALSE(Send(e, *client_, static_cast<int>(DeviceKind::kBase), 5, {0, 0, 0, 0}, 5));
  EXPECT_EQ(e.counters().refused_not_subscribed, 1);
  EXPECT_EQ(e.subscribers(), 0);
  EXPECT_FALSE(e.has_owner());
}

TEST_F(EndpointTest, AFullTableMakesRoomByDroppingTheLeastRecentlyHeardNonOwner) {
  double now = 100;
  EndpointConfig c = BaseConfig(&now);
  c.max_subscribers = 2;
  c.owner_timeout_s = 10;  // (the owner stays owner over the 2 s below)
  DeviceEndpoint e(c);
  Subscribe(e, *client_);
  PublishBase(e, 1);
  ASSERT_TRUE(Send(e, *client_, static_cast<int>(DeviceKind::kBase), 1, {0, 0, 0, 0}, 1));  // the owner
  now = 101;
  Subscribe(e, *other_);
  now = 102;
  auto third = UdpSocket::Bind("127.0.0.1", 0);
  Bytes request;
  EncodeSubscribeRequest(DeviceKind::kBase, 0, 1, &request);
  const double cookie = Reply(Request(e, *third, request)).first;
  EncodeSubscribeRequest(DeviceKind::kBase, cookie, 1, &request);
  // the owner was heard from least recently, yet it stays: `other` makes room
  EXPECT_EQ(Reply(Request(e, *third, request)).second, SessionResult::kSubscribed);
  EXPECT_EQ(e.subscribers(), 2);
  EXPECT_EQ(e.counters().sessions.evicted, 1);
  EXPECT_EQ(e.counters().sessions.refused_full, 0);
  PublishBase(e, 2);
  EXPECT_TRUE(Send(e, *client_, static_cast<int>(DeviceKind::kBase), 2, {0, 0, 0, 0}, 2));  // still subscribed
  EXPECT_FALSE(Send(e, *other_, static_cast<int>(DeviceKind::kBase), 2, {0, 0, 0, 0}, 2));
  EXPECT_EQ(e.counters().refused_not_subscribed, 1);
  // a table of one that holds the owner refuses newcomers
  c.max_subscribers = 1;
  DeviceEndpoint one(c);
  Subscribe(one, *client_);
  PublishBase(one, 1);
  ASSERT_TRUE(Send(one, *client_, static_cast<int>(DeviceKind::kBase), 1, {0, 0, 0, 0}, 1));
  EncodeSubscribeRequest(DeviceKind::kBase, one.cookie(third->local_endpoint()), 1, &request);
  EXPECT_EQ(Reply(Request(one, *third, request)).second, SessionResult::kFull);
  EXPECT_EQ(one.counters().sessions.refused_full, 1);
}

TEST_F(EndpointTest, DescribeRepliesAreRateLimitedPerSource) {
  double now = 100;
  DeviceEndpoint e(BaseConfig(&now));
  Bytes request;
  EncodeDescribeRequest(0, 0, &request);
  const double cookie = Reply(Request(e, *client_, request)).first;
  EncodeDescribeRequest(0, cookie, &request);
  // a burst of 10, then one per 0.1 s (10 Hz)
  const auto json = [&](long n) { return n > 0 && buffer_[0] == '{'; };
  for (int i = 0; i < 10; ++i) EXPECT_TRUE(json(Request(e, *client_, request))) << i;
  const long limited = Request(e, *client_, request);
  EXPECT_EQ(limited, 72);
  EXPECT_EQ(Reply(limited).second, SessionResult::kLimited);
  EXPECT_EQ(e.counters().sessions.describes_limited, 1);
  now += 0.15;
  EXPECT_TRUE(json(Request(e, *client_, request)));
  EXPECT_EQ(Reply(Request(e, *client_, request)).second, SessionResult::kLimited);
  // another source has a budget of its own
  EncodeDescribeRequest(0, 0, &request);
  const double other_cookie = Reply(Request(e, *other_, request)).first;
  EncodeDescribeRequest(0, other_cookie, &request);
  EXPECT_TRUE(json(Request(e, *other_, request)));
  EXPECT_EQ(e.counters().describes, 12);
}

TEST_F(EndpointTest, ASilentOwnerIsReleasedOnTheWallClockAndARenewingOneIsNot) {
  double now = 0;
  EndpointConfig c = BaseConfig(&now);
  c.owner_timeout_s = 1.0;
  DeviceEndpoint e(c);
  const int base = static_cast<int>(DeviceKind::kBase);
  const double cookie = Subscribe(e, *client_);
  Subscribe(e, *other_);
  PublishBase(e, 0);
  ASSERT_TRUE(Send(e, *client_, base, 0, {0, 0, 0, 0}, 0));
  // no period passes (the lab is paused): the owner renews its subscription and stays owner
  Bytes renew;
  EncodeSubscribeRequest(DeviceKind::kBase, cookie, 1, &renew);
  for (int i = 0; i < 5; ++i) {
    now += 0.6;
    EXPECT_EQ(Reply(Request(e, *client_, renew)).second, SessionResult::kSubscribed);
    EXPECT_FALSE(e.ReleaseSilentOwner());
  }
  EXPECT_FALSE(Send(e, *other_, base, 0, {0, 0, 0, 0}, 0));
  EXPECT_EQ(e.counters().refused_not_owner, 1);
  // silent for 1 s of the wall clock: released, with no period and no datagram needed
  now += 1.01;
  EXPECT_TRUE(e.ReleaseSilentOwner());
  EXPECT_FALSE(e.has_owner());
  EXPECT_EQ(e.counters().owners_released, 1);
  EXPECT_TRUE(Send(e, *other_, base, 0, {0, 0, 0, 0}, 0));  // the other takes over
  EXPECT_TRUE(e.has_owner());
  // the other falls silent too, then comes back: its first command after the timeout
  // makes it the owner afresh (a fresh seq history), as anyone's would
  // (no period in between: the release happens as the command arrives)
  now += 1.01;
  EXPECT_TRUE(Send(e, *other_, base, 0, {0, 0, 0, 0}, 0));
  EXPECT_TRUE(e.has_owner());
  EXPECT_FALSE(Send(e, *client_, base, 0, {0, 0, 0, 0}, 0));  // the first client is not the owner
  EXPECT_EQ(e.counters().refused_not_owner, 2);
  EXPECT_EQ(e.counters().owners_released, 2);
  // an owner that unsubscribes gives its input up at once
  Bytes leave;
  EncodeSubscribeRequest(DeviceKind::kBase, Subscribe(e, *other_), 0, &leave);
  Request(e, *other_, leave);
  EXPECT_FALSE(e.has_owner());
}

TEST_F(EndpointTest, ACommandMustAnswerAPublishedStateWithinTheWindow) {
  DeviceEndpoint e(BaseConfig());
  const int base = static_cast<int>(DeviceKind::kBase);
  Subscribe(e, *client_);
  // nothing published yet: every seq is from the future
  EXPECT_FALSE(Send(e, *client_, base, 0, {0, 0, 0, 0}, 0));
  EXPECT_EQ(e.counters().future, 1);
  PublishBase(e, 200);
  EXPECT_FALSE(Send(e, *client_, base, 9007199254740992.0, {0, 0, 0, 0}, 0));  // 2^53
  EXPECT_FALSE(Send(e, *client_, base, 201, {0, 0, 0, 0}, 0));
  EXPECT_EQ(e.counters().future, 3);
  EXPECT_FALSE(Send(e, *client_, base, 200 - kSeqWindow - 1, {0, 0, 0, 0}, 0));  // older than the window
  EXPECT_EQ(e.counters().stale, 1);
  EXPECT_EQ(e.counters().stale_window, 1);
  EXPECT_TRUE(Send(e, *client_, base, 200 - kSeqWindow, {0, 0, 0, 0}, 0));  // the oldest it takes
  EXPECT_TRUE(Send(e, *client_, base, 200, {0, 0, 0, 0}, 0));
  EXPECT_FALSE(Send(e, *client_, base, 200, {0, 0, 0, 0}, 0));
  EXPECT_EQ(e.counters().duplicate, 1);
  EXPECT_EQ(e.counters().accepted, 2);
}

TEST(UdpSocketTest, IsClosedOnExec) {
  // a program the lab starts must not inherit its ports
  auto socket = UdpSocket::Bind("127.0.0.1", 0);
  EXPECT_NE(::fcntl(socket->fd(), F_GETFD) & FD_CLOEXEC, 0);
}

}  // namespace
}  // namespace vlab::bridge::endpoint_test
