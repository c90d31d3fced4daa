// The arm's payload from the wire (type 6) into the lab's SimArm: the owner's
// payload reaches the servo at the start of the next period and changes its
// gravity feed-forward by the closed form (a load m at lever c on a
// horizontal link: -m g c at the joint), the describe reply reports it, a
// non-owner is refused (result 7) and changes nothing, and with
// servo.feedforward: world the payload is taken and reported but the torques
// stay the world's.
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bridge/bridge_describe.h"
#include "bridge/bridge_endpoint.h"
#include "bridge/bridge_payload.h"
#include "lab/devices/device_arm.h"
#include "mujoco_fixture.h"

namespace vlab::lab::arm_payload_wire_test {
namespace {

// one horizontal link on a hinge about y, its centre of mass 0.2 m out along x
constexpr const char* kLink = R"(
<mujoco>
  <option gravity="0 0 -9.81" timestep="0.001"/>
  <worldbody>
    <body name="link" pos="0 0 0.5">
      <joint name="j" axis="0 1 0"/>
      <inertial pos="0.2 0 0" mass="1" diaginertia="0.01 0.01 0.01"/>
    </body>
  </worldbody>
  <actuator><motor name="j" joint="j"/></actuator>
</mujoco>)";

class ArmPayloadWireTest : public test::MujocoTest {
 protected:
  std::unique_ptr<bridge::UdpSocket> device_ = bridge::UdpSocket::Bind("127.0.0.1", 0);
  std::unique_ptr<bridge::UdpSocket> owner_ = bridge::UdpSocket::Bind("127.0.0.1", 0);
  std::unique_ptr<bridge::UdpSocket> other_ = bridge::UdpSocket::Bind("127.0.0.1", 0);

  // the arm (servo.feedforward as given), its endpoint as the lab makes it, `owner_` owning it
  void Make(ServoConfig::Feedforward feedforward) {
    model_ = LoadModelFromString(kLink);
    world_ = MakeData(model_);
    DeviceConfig c;
    c.name = "arm";
    c.where = "link.yaml:3";
    auto& p = c.EditParams<ArmParams>();
    p.joints = p.actuators = {"j"};
    p.servo.feedforward = feedforward;
    arm_ = SimArm::Create({model_, 0.002, 1, "link.xml"}, c);
    mj_forward(model_, world_);
    arm_->Start(*world_);
    bridge::EndpointConfig ec;
    arm_->ConfigureEndpoint(500, &ec);
    ec.describe_json = arm_->DescribeJson(bridge::DeviceDescription{"arm", "test", "lockstep", "127.0.0.1", 0, 500});
    endpoint_ = std::make_unique<bridge::DeviceEndpoint>(ec);
    for (bridge::UdpSocket* s : {owner_.get(), other_.get()}) {
      std::vector<unsigned char> request;
      bridge::EncodeSubscribeRequest(bridge::DeviceKind::kArm, endpoint_->cookie(s->local_endpoint()), 1, &request);
      Handle(request, *s);
    }
    std::vector<double> scratch;
    std::vector<unsigned char> state, hold;
    arm_->EncodeState(0, 0, 0, &scratch, &state);
    endpoint_->Publish(state, *device_);
    bridge::ArmCommandMsg command;
    command.value = {0.0};
    bridge::EncodeArmCommand(0, 0, command, &hold);
    ASSERT_EQ(Handle(hold, *owner_), bridge::DeviceEndpoint::Received::kCommand);
  }
  bridge::DeviceEndpoint::Received Handle(const std::vector<unsigned char>& datagram, bridge::UdpSocket& from) {
    return endpoint_->Handle(datagram.data(), datagram.size(), from.local_endpoint(), 0, *device_);
  }
  // sends a payload from `from`; the result of the session reply it gets
  double payload_seq_ = 0;  // the payloads sent so far (docs/protocol.md: seq 1, 2, 3, ...)
  bridge::SessionResult SendPayload(const bridge::ArmPayloadMsg& p, bridge::UdpSocket& from) {
    std::vector<unsigned char> datagram;
    bridge::EncodeArmPayload(++payload_seq_, 0, p, &datagram);  // a sender's own counter: 1, 2, ...
    Handle(datagram, from);
    unsigned char buffer[2048];
    bridge::Endpoint sender;
    bridge::Header h;
    std::vector<double> values;
    double cookie = 0;
    bridge::SessionResult result = bridge::SessionResult::kChallenge;
    for (;;) {  // (skips the states published to it)
      const long n = from.Receive(buffer, sizeof buffer, &sender, 0.5);
      if (n < 0) return bridge::SessionResult::kChallenge;
      if (bridge::IsSessionReply(buffer, static_cast<std::size_t>(n)) &&
          bridge::DecodePacket(buffer, static_cast<std::size_t>(n), &h, &values) == bridge::DecodeError::kNone &&
          bridge::ParseSessionReply(h, values, &cookie, &result) && result != bridge::SessionResult::kSubscribed) {
        return result;
      }
    }
  }
  // the servo's torque at the static pose, after the next period's start took what came
  double Torque() {
    std::vector<double> scratch;
    arm_->TakeCommand(*endpoint_, &scratch);
    arm_->Actuate(*world_, model_->opt.timestep);
    return world_->ctrl[0];
  }

  const mjModel* model_ = nullptr;
  mjData* world_ = nullptr;
  std::unique_ptr<SimArm> arm_;
  std::unique_ptr<bridge::DeviceEndpoint> endpoint_;
};

bridge::ArmPayloadMsg Load(double mass, double lever) {
  bridge::ArmPayloadMsg p;
  p.mass_kg = mass;
  p.com_m = {lever, 0, 0};
  return p;
}

TEST_F(ArmPayloadWireTest, TheOwnersPayloadChangesTheFeedForwardByTheClosedForm) {
  Make(ServoConfig::Feedforward::kModel);
  const double before = Torque();
  EXPECT_NEAR(before, -1.0 * 9.81 * 0.2, 1e-9);  // the link itself: what the servo holds
  ASSERT_EQ(SendPayload(Load(2.0, 0.4), *owner_), bridge::SessionResult::kPayloadSet);
  EXPECT_EQ(arm_->payload().mass_kg, 0.0);  // not before the next period's start
  const double after = Torque();
  EXPECT_NEAR(after - before, -2.0 * 9.81 * 0.4, 1e-9);  // -m g c
  EXPECT_EQ(arm_->payload().mass_kg, 2.0);
  const nlohmann::json d = nlohmann::json::parse(endpoint_->describe_json());
  EXPECT_EQ(d["payload"]["mass"], 2.0);
  EXPECT_EQ(d["payload"]["com"], nlohmann::json({0.4, 0.0, 0.0}));
  EXPECT_EQ(d["feedforward"], "model");
}

TEST_F(ArmPayloadWireTest, ANonOwnerIsRefusedAndNothingChanges) {
  Make(ServoConfig::Feedforward::kModel);
  const double before = Torque();
  EXPECT_EQ(SendPayload(Load(2.0, 0.4), *other_), bridge::SessionResult::kPayloadRefused);
  EXPECT_EQ(endpoint_->counters().refused_not_owner, 1);
  EXPECT_EQ(Torque(), before);
  EXPECT_EQ(arm_->payload().mass_kg, 0.0);
  EXPECT_EQ(nlohmann::json::parse(endpoint_->describe_json())["payload"]["mass"], 0.0);
  // the servo model's own check: an inertia no rigid body has
  bridge::ArmPayloadMsg flat = Load(1.0, 0.1);
  flat.inertia_kgm2 = {0.01, 0.01, 0.03, 0, 0, 0};
  EXPECT_EQ(SendPayload(flat, *owner_), bridge::SessionResult::kPayloadRefused);
  EXPECT_EQ(endpoint_->counters().refused_malformed, 1);
  EXPECT_EQ(Torque(), before);
}

TEST_F(ArmPayloadWireTest, WithTheWorldsFeedForwardItIsReportedButMovesNothing) {
  Make(ServoConfig::Feedforward::kWorld);
  const double before = Torque();
  ASSERT_EQ(SendPayload(Load(2.0, 0.4), *owner_), bridge::SessionResult::kPayloadSet);
  EXPECT_EQ(Torque(), before);
  EXPECT_EQ(arm_->payload().mass_kg, 2.0);
  const nlohmann::json d = nlohmann::json::parse(endpoint_->describe_json());
  EXPECT_EQ(d["payload"]["mass"], 2.0);
  EXPECT_EQ(d["feedforward"], "world");
}

}  // namespace
}  // namespace vlab::lab::arm_payload_wire_test
