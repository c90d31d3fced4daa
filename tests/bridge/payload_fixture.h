// The fixture of the arm payload tests (endpoint_payload_test.cc,
// endpoint_payload_seq_test.cc): a 2-joint arm's config, a load, payload
// datagrams of any seq and values, and a test class that publishes states,
// takes the arm and reads the session reply a payload gets.
#pragma once

#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bridge/bridge_endpoint.h"
#include "bridge/bridge_payload.h"
#include "bridge/endpoint_fixture.h"

namespace vlab::bridge {

inline constexpr int kPayloadTestJoints = 2;

// an arm whose configured payload is 0.25 kg (the scenario's)
inline EndpointConfig PayloadArmConfig() {
  EndpointConfig c;
  c.name = "arm";
  c.kind = DeviceKind::kArm;
  c.describe_json = R"({"name":"arm","kind":"arm"})";
  c.joints = kPayloadTestJoints;
  c.payload.mass_kg = 0.25;
  return c;
}

// a rigid body of 1.5 kg, or of `mass_kg`
inline ArmPayloadMsg Load(double mass_kg = 1.5) {
  ArmPayloadMsg p;
  p.mass_kg = mass_kg;
  p.com_m = {0.1, 0, 0.05};
  p.inertia_kgm2 = {0.01, 0.012, 0.008, 0.001, 0, 0};
  return p;
}

// a payload datagram of seq `seq` (the sender's payload counter)
inline Bytes Encoded(const ArmPayloadMsg& p, double seq = 1) {
  Bytes b;
  EncodeArmPayload(seq, 0, p, &b);
  return b;
}

// a payload datagram of any values (a wrong count, NaN), kind and seq
inline Bytes Raw(std::vector<double> values, int kind = static_cast<int>(DeviceKind::kArm), double seq = 1) {
  Header h;
  h.kind = kind;
  h.type = static_cast<int>(MessageType::kPayload);
  h.seq = seq;
  Bytes b;
  EncodePacket(h, values.data(), static_cast<int>(values.size()), &b);
  return b;
}

class PayloadTest : public EndpointTest {
 protected:
  void PublishArm(DeviceEndpoint& e, double seq) {
    ArmStateMsg s;
    s.q.assign(kPayloadTestJoints, 0);
    s.qd.assign(kPayloadTestJoints, 0);
    s.tau.assign(kPayloadTestJoints, 0);
    Bytes packet;
    EncodeArmState(seq, 0, s, &packet);
    e.Publish(packet, *device_);
  }
  // `from` takes the arm with a hold command answering state 0
  void Own(DeviceEndpoint& e, UdpSocket& from) {
    PublishArm(e, 0);
    ASSERT_TRUE(Send(e, from, static_cast<int>(DeviceKind::kArm), 0, {0, 0, 0}, 0));
  }
  // the result of the session reply a payload got; kChallenge when none came
  SessionResult Answer(DeviceEndpoint& e, UdpSocket& from, const Bytes& payload) {
    const long n = Request(e, from, payload);
    return n < 0 ? SessionResult::kChallenge : Reply(n).second;
  }
  nlohmann::json Described(DeviceEndpoint& e, UdpSocket& from, double cookie) {
    Bytes request;
    EncodeDescribeRequest(static_cast<int>(DeviceKind::kArm), cookie, &request);
    const long n = Request(e, from, request);
    EXPECT_GT(n, 0);
    return nlohmann::json::parse(std::string(reinterpret_cast<char*>(buffer_), n > 0 ? n : 0), nullptr, false);
  }
};

}  // namespace vlab::bridge
