// Tests bridge/bridge_client_device.cc: the generic Device client against a
// scripted device on loopback (the test plays a gripper and a feet device,
// datagram by datagram): values by name and by the table's compile-time
// indices, commands by field name, and the layout checks at connect.
#include "bridge/bridge_client_device.h"

#include <cmath>
#include <future>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bridge/bridge_describe.h"
#include "bridge/bridge_layouts.h"
#include "bridge/bridge_udp.h"
#include "wire_session.h"

namespace vlab::bridge::client_device_test {
namespace {

using Bytes = std::vector<unsigned char>;
using nlohmann::json;
constexpr double kPatience_s = 5.0;  // how long a test waits for something that must happen
constexpr int kGrasped = StateIndex(DeviceKind::kGripper, "grasped");
constexpr int kOpening = StateIndex(DeviceKind::kGripper, "opening");

// a device played by the test: answers the describe request, sends states, reads commands
using Peer = testing::FakeDevice;

void SendState(Peer& peer, DeviceKind kind, double seq, const std::vector<double>& values) {
  Bytes packet;
  EncodePacket(Header{static_cast<int>(kind), static_cast<int>(MessageType::kState), seq, 0.01 * seq,
                      static_cast<int>(values.size())},
               values.data(), static_cast<int>(values.size()), &packet);
  peer.Send(packet);
}

std::string Describe(const std::string& kind, const json& layout) {
  DeviceDescription d;
  d.name = "g";
  d.server = "client_device_test";
  d.clock = "realtime";
  d.address = "127.0.0.1";
  d.control_hz = 100;
  return DescribeJson(d, kind, json({{"layout", layout}}).dump());
}

// connects a Device of `kind` to the peer, which answers with `describe`
std::future<Device> Connect(Peer& peer, DeviceKind kind, const std::string& describe) {
  auto future = std::async(
      std::launch::async, [kind, port = peer.port()] { return Device::Connect(kind, "127.0.0.1", port, kPatience_s); });
  EXPECT_EQ(peer.Handshake(kind), 3) << "describe, then describe and subscribe with the cookie";
  peer.Send(describe);
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

TEST(ClientDeviceTest, AGrippersValuesByNameAndByTheTablesIndices) {
  Peer peer;
  Device gripper = Connect(peer, DeviceKind::kGripper, Describe("gripper", LayoutJson(DeviceKind::kGripper))).get();
  EXPECT_EQ(gripper.state_length(), 5);
  EXPECT_EQ(gripper.command_names(), (std::vector<std::string>{"mode", "value"}));
  SendState(peer, DeviceKind::kGripper, 7, {0, 0.05, -0.01, 3.5, 1});
  const Device::State s = gripper.Read(kPatience_s);
  EXPECT_EQ(s.seq, 7);
  EXPECT_EQ(s.values[kGrasped], 1.0);
  EXPECT_EQ(s.values[kOpening], 0.05);
  EXPECT_EQ(gripper.Field(s, "force"), 3.5);
  EXPECT_EQ(gripper.Field(s, "opening_velocity"), -0.01);
  EXPECT_EQ(gripper.StateIndex("grasped"), kGrasped);
  EXPECT_EQ(gripper.StateIndex("grasp"), -1);
  const std::string label = "gripper 'g' at 127.0.0.1:" + std::to_string(peer.port());
  EXPECT_EQ(ThrownMessage<std::invalid_argument>([&] { gripper.Field(s, "grasp"); }),
            label + ": no state field 'grasp'");
  EXPECT_TRUE(Contains(ThrownMessage<std::invalid_argument>([&] { gripper.Field(Device::State{}, "force"); }),
                       "field 'force' of a state with 0 values, not 5"));
}

TEST(ClientDeviceTest, CommandsByFieldNameGoOutInTheLayoutsOrder) {
  Peer peer;
  Device gripper = Connect(peer, DeviceKind::kGripper, Describe("gripper", LayoutJson(DeviceKind::kGripper))).get();
  ASSERT_TRUE(gripper.WriteFields({{"value", 0.02}, {"mode", 0}}, 3));
  const Bytes command = peer.Receive();
  Header h;
  std::vector<double> p;
  ASSERT_EQ(DecodePacket(command.data(), command.size(), &h, &p), DecodeError::kNone);
  EXPECT_EQ(h.kind, static_cast<int>(DeviceKind::kGripper));
  EXPECT_EQ(h.type, static_cast<int>(MessageType::kCommand));
  EXPECT_EQ(h.seq, 3);
  EXPECT_EQ(p, (std::vector<double>{0, 0.02}));
  EXPECT_EQ(p[CommandIndex(DeviceKind::kGripper, "value")], 0.02);

  const auto error = [&](std::initializer_list<Device::FieldValue> values) {
    return ThrownMessage<std::invalid_argument>([&] { gripper.WriteFields(values, 4); });
  };
  EXPECT_TRUE(Contains(error({{"mode", 0}}), ": command field 'value' not given"));
  EXPECT_TRUE(Contains(error({{"mode", 0}, {"value", 0.01}, {"speed", 1}}), ": no command field 'speed'"));
  EXPECT_TRUE(Contains(error({{"mode", 0}, {"mode", 1}, {"value", 0.01}}), ": command field 'mode' given twice"));
  EXPECT_TRUE(Contains(error({{"mode", 0}, {"value", NAN}}), "not finite"));
}

TEST(ClientDeviceTest, AFixedKindWithAnotherLayoutIsAProtocolError) {
  Peer peer;
  json layout = LayoutJson(DeviceKind::kGripper);
  layout["state"][4] = "grasp";
  auto future = Connect(peer, DeviceKind::kGripper, Describe("gripper", layout));
  const std::string message = ThrownMessage<ProtocolError>([&] { future.get(); });
  EXPECT_TRUE(Contains(message,
                       R"(: describe layout.state is ["status","opening","opening_velocity","force","grasp"], )"
                       R"(the protocol's gripper layout is ["status","opening","opening_velocity","force",)"
                       R"("grasped"])"))
      << message;
}

TEST(ClientDeviceTest, FeetValuesAreNamedAfterTheirSensors) {
  Peer peer;
  const std::vector<std::string> sensors = {"rf_front", "rf_back", "lf_front", "lf_back"};
  Device feet = Connect(peer, DeviceKind::kFeet, Describe("feet", LayoutJson(DeviceKind::kFeet, sensors))).get();
  EXPECT_EQ(feet.state_names(), sensors);
  EXPECT_EQ(feet.command_length(), 0);
  SendState(peer, DeviceKind::kFeet, 0, {10, 20, 30, 40});
  const Device::State s = feet.Read(kPatience_s);
  EXPECT_EQ(feet.Field(s, "lf_front"), 30.0);
  EXPECT_TRUE(Contains(ThrownMessage<std::invalid_argument>([&] {
                         feet.WriteFields({{"x", 1}}, 0);
                       }),
                       "this device takes no commands"));
}

TEST(ClientDeviceTest, CameraAndMarkersHaveTheirOwnClients) {
  EXPECT_EQ(ThrownMessage<std::invalid_argument>([] { Device::Connect(DeviceKind::kCamera, "127.0.0.1", 50013); }),
            "camera devices are not float64 arrays (frames in chunks: docs/protocol_camera.md): use their own client");
  EXPECT_TRUE(
      Contains(ThrownMessage<std::invalid_argument>([] { Device::Connect(DeviceKind::kMarkers, "127.0.0.1", 50013); }),
               "markers devices are not float64 arrays"));
}

}  // namespace
}  // namespace vlab::bridge::client_device_test
