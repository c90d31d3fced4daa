// Tests an arm endpoint's payload (type 6, bridge_payload.h): the owner sets
// it and the describe reply reports it; anyone else, a wrong length, NaN, a
// negative mass or an inertia no rigid body has is refused, counted, and
// answered with result 7; a device of another kind answers nothing. Its seq
// rule: endpoint_payload_seq_test.cc.
#include "bridge/bridge_payload.h"

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bridge/bridge_endpoint.h"
#include "bridge/endpoint_fixture.h"
#include "bridge/payload_fixture.h"

namespace vlab::bridge::endpoint_payload_test {
namespace {

EndpointConfig ArmConfig() { return PayloadArmConfig(); }

TEST_F(PayloadTest, TheOwnerSetsItAndTheDescribeReplyReportsIt) {
  DeviceEndpoint e(ArmConfig());
  const double cookie = Subscribe(e, *client_);
  EXPECT_EQ(Described(e, *client_, cookie)["payload"]["mass"], 0.25);  // the configured one
  Own(e, *client_);
  EXPECT_EQ(Answer(e, *client_, Encoded(Load())), SessionResult::kPayloadSet);
  EXPECT_EQ(e.counters().payloads, 1);
  EXPECT_EQ(e.counters().refused, 0);
  ArmPayloadMsg taken;
  ASSERT_TRUE(e.TakePayload(&taken));
  EXPECT_EQ(taken, Load());
  EXPECT_FALSE(e.TakePayload(&taken));  // once
  const nlohmann::json d = Described(e, *client_, cookie);
  EXPECT_EQ(d["payload"]["mass"], 1.5);
  EXPECT_EQ(d["payload"]["com"], nlohmann::json({0.1, 0, 0.05}));
  EXPECT_EQ(d["payload"]["inertia"], nlohmann::json({0.01, 0.012, 0.008, 0.001, 0, 0}));
  EXPECT_EQ(d["name"], "arm");
  EXPECT_EQ(e.last_accepted_seq(), 0);  // not a period's command: the seq history is the commands'
}

TEST_F(PayloadTest, ANonOwnerIsRefusedAndThePayloadStays) {
  DeviceEndpoint e(ArmConfig());
  Subscribe(e, *client_);
  Subscribe(e, *other_);
  Own(e, *client_);
  EXPECT_EQ(Answer(e, *other_, Encoded(Load())), SessionResult::kPayloadRefused);
  EXPECT_EQ(e.counters().refused_not_owner, 1);
  EXPECT_EQ(e.counters().refused, 1);
  EXPECT_EQ(e.counters().payloads, 0);
  ArmPayloadMsg taken;
  EXPECT_FALSE(e.TakePayload(&taken));
  EXPECT_EQ(e.payload().mass_kg, 0.25);
  EXPECT_EQ(e.status_bits() & kStatusRefused, 0u);  // the owner did nothing wrong
}

TEST_F(PayloadTest, BadValuesAreRefusedCountedAndAnswered) {
  DeviceEndpoint e(ArmConfig());
  Subscribe(e, *client_);
  Own(e, *client_);
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  const std::vector<std::pair<const char*, Bytes>> bad = {
      {"9 values", Raw({1, 0, 0, 0, 0, 0, 0, 0, 0})},
      {"11 values", Raw({1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0})},
      {"no values", Raw({})},
      {"a NaN mass", Raw({nan, 0, 0, 0, 0, 0, 0, 0, 0, 0})},
      {"an infinite com", Raw({1, inf, 0, 0, 0, 0, 0, 0, 0, 0})},
      {"a negative mass", Raw({-1, 0, 0, 0, 0, 0, 0, 0, 0, 0})},
      {"a negative moment", Raw({1, 0, 0, 0, -0.01, 0.01, 0.01, 0, 0, 0})},
      {"the triangle inequality broken", Raw({1, 0, 0, 0, 0.01, 0.01, 0.03, 0, 0, 0})},
  };
  long refused = 0;
  for (const auto& [what, datagram] : bad) {
    EXPECT_EQ(Answer(e, *client_, datagram), SessionResult::kPayloadRefused) << what;
    EXPECT_EQ(e.counters().refused_malformed, ++refused) << what;
  }
  EXPECT_EQ(e.counters().refused, refused);
  EXPECT_EQ(e.counters().payloads, 0);
  ArmPayloadMsg taken;
  EXPECT_FALSE(e.TakePayload(&taken));
  EXPECT_EQ(e.payload().mass_kg, 0.25);
  EXPECT_NE(e.status_bits() & kStatusRefused, 0u);  // the owner is told in its states too
}

TEST_F(PayloadTest, TheDevicesOwnCheckDecides) {
  EndpointConfig c = ArmConfig();
  c.check_payload = [](const ArmPayloadMsg& p) { return p.mass_kg <= 1; };  // a 1 kg arm
  DeviceEndpoint e(c);
  Subscribe(e, *client_);
  Own(e, *client_);
  EXPECT_EQ(Answer(e, *client_, Encoded(Load(), 1)), SessionResult::kPayloadRefused);
  EXPECT_EQ(Answer(e, *client_, Encoded(Load(0.5), 2)), SessionResult::kPayloadSet);
}

TEST_F(PayloadTest, AFirstPayloadTakesAnArmThatHasNoOwner) {
  DeviceEndpoint e(ArmConfig());
  Subscribe(e, *client_);
  Subscribe(e, *other_);
  PublishArm(e, 0);
  EXPECT_EQ(Answer(e, *client_, Encoded(Load())), SessionResult::kPayloadSet);
  ASSERT_TRUE(e.has_owner());
  EXPECT_EQ(*e.owner(), client_->local_endpoint());
  EXPECT_EQ(e.last_accepted_seq(), -1);  // no period answered yet
  EXPECT_FALSE(Send(e, *other_, static_cast<int>(DeviceKind::kArm), 0, {0, 0, 0}, 0));
  EXPECT_EQ(e.counters().refused_not_owner, 1);
}

TEST_F(PayloadTest, NonSubscribersAndOtherKindsGetNoAnswer) {
  DeviceEndpoint arm(ArmConfig());
  EXPECT_EQ(Answer(arm, *client_, Encoded(Load())), SessionResult::kChallenge);  // none came
  EXPECT_EQ(arm.counters().refused_not_subscribed, 1);
  DeviceEndpoint base(BaseConfig());
  Subscribe(base, *client_);
  const int kind = static_cast<int>(DeviceKind::kBase);
  EXPECT_EQ(Answer(base, *client_, Raw({1, 0, 0, 0, 0, 0, 0, 0, 0, 0}, kind)), SessionResult::kChallenge);
  EXPECT_EQ(Answer(base, *client_, Encoded(Load())), SessionResult::kChallenge);  // (kind arm)
  EXPECT_EQ(base.counters().refused_malformed, 2);
  EXPECT_EQ(base.counters().refused, 2);
}

TEST(PayloadCodecTest, RoundTripsAndChecksLikeARigidBody) {
  Bytes b = Encoded(Load());
  EXPECT_EQ(b.size(), (7u + 10u) * 8u);
  Header h;
  std::vector<double> v;
  ASSERT_EQ(DecodePacket(b.data(), b.size(), &h, &v), DecodeError::kNone);
  ArmPayloadMsg p;
  ASSERT_EQ(ParseArmPayload(h, v, &p), DecodeError::kNone);
  EXPECT_EQ(p, Load());
  const char* field = nullptr;
  const char* reason = nullptr;
  EXPECT_TRUE(CheckArmPayload(p, &field, &reason));
  p.inertia_kgm2 = {0.01, 0.01, 0.01, 0.02, 0, 0};  // a product larger than the moments: not PSD
  EXPECT_FALSE(CheckArmPayload(p, &field, &reason));
  EXPECT_STREQ(field, "inertia");
  // a NaN in the payload only: the header is still read, so the device can answer
  b = Raw({std::numeric_limits<double>::quiet_NaN(), 0, 0, 0, 0, 0, 0, 0, 0, 0});
  h = Header();
  EXPECT_EQ(DecodePacket(b.data(), b.size(), &h, &v), DecodeError::kNotFinite);
  EXPECT_EQ(h.type, static_cast<int>(MessageType::kPayload));
}

}  // namespace
}  // namespace vlab::bridge::endpoint_payload_test
