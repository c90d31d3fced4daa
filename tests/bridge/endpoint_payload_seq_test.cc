// Tests the seq rule of an arm's payload (type 6, docs/protocol.md "Arm
// payload"): the seq is the sender's own payload counter (1, 2, 3, ...); the
// owner's payload whose seq is not above its last accepted one (a late or
// replayed copy) is refused with result 7, counted as stale, sets the refused
// bit and changes nothing; the record starts afresh with a new owner; seq 0
// and a seq that is not a whole number are malformed.
#include <vector>

#include <gtest/gtest.h>

#include "bridge/bridge_endpoint.h"
#include "bridge/bridge_payload.h"
#include "bridge/payload_fixture.h"

namespace vlab::bridge::endpoint_payload_seq_test {
namespace {

using PayloadSeqTest = PayloadTest;

TEST_F(PayloadSeqTest, ASeqNotAboveTheLastIsRefusedAndTheNewerPayloadStays) {
  DeviceEndpoint e(PayloadArmConfig());
  const double cookie = Subscribe(e, *client_);
  Own(e, *client_);
  EXPECT_EQ(Answer(e, *client_, Encoded(Load(1.0), 1)), SessionResult::kPayloadSet);
  EXPECT_EQ(Answer(e, *client_, Encoded(Load(2.0), 2)), SessionResult::kPayloadSet);  // the counter grows
  EXPECT_EQ(e.last_payload_seq(), 2);
  ArmPayloadMsg taken;
  ASSERT_TRUE(e.TakePayload(&taken));
  EXPECT_EQ(taken.mass_kg, 2.0);
  EXPECT_EQ(e.status_bits() & kStatusRefused, 0u);
  // the same seq again (a duplicate), then a lower one
  EXPECT_EQ(Answer(e, *client_, Encoded(Load(3.0), 2)), SessionResult::kPayloadRefused);
  EXPECT_EQ(Answer(e, *client_, Encoded(Load(1.0), 1)), SessionResult::kPayloadRefused);
  EXPECT_EQ(e.counters().stale, 2);
  EXPECT_EQ(e.counters().payloads, 2);
  EXPECT_EQ(e.counters().refused, 0);               // stale apart, as for commands
  EXPECT_NE(e.status_bits() & kStatusRefused, 0u);  // the owner is told in its states
  EXPECT_FALSE(e.TakePayload(&taken));              // nothing new for the next period
  EXPECT_EQ(e.payload().mass_kg, 2.0);
  EXPECT_EQ(Described(e, *client_, cookie)["payload"]["mass"], 2.0);
  EXPECT_EQ(e.last_payload_seq(), 2);
  // the next one is taken again
  EXPECT_EQ(Answer(e, *client_, Encoded(Load(0.5), 3)), SessionResult::kPayloadSet);
  EXPECT_EQ(Described(e, *client_, cookie)["payload"]["mass"], 0.5);
}

TEST_F(PayloadSeqTest, ALateCopyArrivingAfterANewerOneChangesNothing) {
  DeviceEndpoint e(PayloadArmConfig());
  const double cookie = Subscribe(e, *client_);
  Own(e, *client_);
  const Bytes first = Encoded(Load(1.0), 1), second = Encoded(Load(2.0), 2);
  // sent 1 then 2; the network delivers 2 first, then the late copy of 1, then 2 twice more
  EXPECT_EQ(Answer(e, *client_, second), SessionResult::kPayloadSet);
  EXPECT_EQ(Answer(e, *client_, first), SessionResult::kPayloadRefused);
  EXPECT_EQ(Answer(e, *client_, second), SessionResult::kPayloadRefused);
  EXPECT_EQ(Answer(e, *client_, first), SessionResult::kPayloadRefused);
  ArmPayloadMsg taken;
  ASSERT_TRUE(e.TakePayload(&taken));
  EXPECT_EQ(taken.mass_kg, 2.0);
  EXPECT_EQ(Described(e, *client_, cookie)["payload"]["mass"], 2.0);
  EXPECT_EQ(e.counters().payloads, 1);
  EXPECT_EQ(e.counters().stale, 3);
}

TEST_F(PayloadSeqTest, ANewOwnerStartsFromItsOwnOne) {
  DeviceEndpoint e(PayloadArmConfig());
  Subscribe(e, *client_);
  Subscribe(e, *other_);
  Own(e, *client_);
  EXPECT_EQ(Answer(e, *client_, Encoded(Load(1.0), 5)), SessionResult::kPayloadSet);
  // another subscriber's seq is not compared: it is refused as not the owner
  EXPECT_EQ(Answer(e, *other_, Encoded(Load(2.0), 9)), SessionResult::kPayloadRefused);
  EXPECT_EQ(e.counters().refused_not_owner, 1);
  EXPECT_EQ(e.counters().stale, 0);
  e.ReleaseOwner();
  EXPECT_EQ(e.last_payload_seq(), 0);
  // the other takes the arm with its first payload, seq 1, below the old owner's 5
  EXPECT_EQ(Answer(e, *other_, Encoded(Load(2.0), 1)), SessionResult::kPayloadSet);
  ASSERT_TRUE(e.has_owner());
  EXPECT_EQ(*e.owner(), other_->local_endpoint());
  EXPECT_EQ(e.payload().mass_kg, 2.0);
  // taken over by a command: the new owner's counter starts afresh too
  e.ReleaseOwner();
  PublishArm(e, 1);
  ASSERT_TRUE(Send(e, *client_, static_cast<int>(DeviceKind::kArm), 1, {0, 0, 0}, 1));
  EXPECT_EQ(e.last_payload_seq(), 0);
  EXPECT_EQ(Answer(e, *client_, Encoded(Load(3.0), 1)), SessionResult::kPayloadSet);
  EXPECT_EQ(e.counters().payloads, 3);
}

TEST_F(PayloadSeqTest, SeqZeroOrNotWholeIsMalformed) {
  DeviceEndpoint e(PayloadArmConfig());
  Subscribe(e, *client_);
  Own(e, *client_);
  EXPECT_EQ(Answer(e, *client_, Encoded(Load(), 0)), SessionResult::kPayloadRefused);
  EXPECT_EQ(e.counters().refused_malformed, 1);
  // a seq that is not a whole number: a malformed header, refused unanswered like any
  EXPECT_EQ(Answer(e, *client_, Encoded(Load(), 1.5)), SessionResult::kChallenge);  // (none came)
  EXPECT_EQ(e.counters().refused_malformed, 2);
  EXPECT_EQ(e.counters().refused, 2);
  EXPECT_EQ(e.counters().payloads, 0);
  EXPECT_EQ(e.payload().mass_kg, 0.25);
  EXPECT_EQ(e.last_payload_seq(), 0);
  EXPECT_NE(e.status_bits() & kStatusRefused, 0u);
  // neither advanced the record: seq 1 is still taken
  EXPECT_EQ(Answer(e, *client_, Encoded(Load(), 1)), SessionResult::kPayloadSet);
}

TEST_F(PayloadSeqTest, AFirstPayloadThatTakesTheArmStartsTheRecord) {
  // no owner: no record to be stale against, any seq >= 1 is fresh and then the owner's last
  DeviceEndpoint e(PayloadArmConfig());
  Subscribe(e, *client_);
  PublishArm(e, 0);
  EXPECT_EQ(Answer(e, *client_, Encoded(Load(1.0), 7)), SessionResult::kPayloadSet);
  EXPECT_EQ(e.last_payload_seq(), 7);
  EXPECT_EQ(Answer(e, *client_, Encoded(Load(2.0), 7)), SessionResult::kPayloadRefused);
  EXPECT_EQ(e.payload().mass_kg, 1.0);
}

}  // namespace
}  // namespace vlab::bridge::endpoint_payload_seq_test
