// The markers device over real loopback sockets: MarkersServer (device side)
// against MarkersClient and a raw socket for faults: describe, subscription,
// marker descriptions applied whole or refused whole, states, timeouts.
#include <atomic>
#include <functional>
#include <optional>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bridge/bridge_errors.h"
#include "bridge/bridge_markers.h"
#include "vision/vision_server.h"
#include "wire_session.h"

namespace vlab::vision::server_test {
namespace {

using bridge::MarkerDescriptionMsg;
using bridge::MarkersClient;

// runs `body` while a thread serves the device (the client's calls block)
void WhileServing(MarkersServer& server, double now_s, const std::function<void()>& body) {
  std::atomic<bool> done{false};
  std::thread serve([&] {
    while (!done) {
      server.Poll(now_s);
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  });
  try {
    body();
  } catch (...) {
    done = true;
    serve.join();
    throw;
  }
  done = true;
  serve.join();
}

// polls until the server has received `count` datagrams in all (or 2 s passed)
void PollUntilReceived(MarkersServer& server, long count, double now_s) {
  for (int i = 0; i < 2000 && server.counters().received < count; ++i) {
    server.Poll(now_s);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

class MarkersServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    MarkersServerConfig config;
    config.name = "eyes";
    config.port = 0;
    config.max_markers = 4;
    config.subscriber_timeout_s = 10;
    config.describe_extra = {{"camera", {{"name", "webcam"}}}};
    server_ = MarkersServer::Create(config);
    ASSERT_TRUE(server_->Describe({{0, 3, 0.025}, {20, 100, 0.1}}));
  }
  MarkersClient Connect() {
    std::optional<MarkersClient> client;
    WhileServing(*server_, 0, [&] { client.emplace(MarkersClient::Connect("127.0.0.1", server_->local_port(), 2.0)); });
    return std::move(*client);
  }
  // a raw datagram from another socket
  void SendRaw(const std::vector<unsigned char>& bytes) {
    raw_->SendTo(bytes.data(), bytes.size(), bridge::UdpSocket::MakeEndpoint("127.0.0.1", server_->local_port()));
  }

  std::unique_ptr<MarkersServer> server_;
  std::unique_ptr<bridge::UdpSocket> raw_ = bridge::UdpSocket::Bind("127.0.0.1", 0);
};

TEST_F(MarkersServerTest, DescribeNamesTheTableAndTheLayout) {
  MarkersClient client = Connect();
  EXPECT_EQ(client.name(), "eyes");
  EXPECT_EQ(client.kind(), bridge::DeviceKind::kMarkers);
  const nlohmann::json& d = client.describe();
  EXPECT_EQ(d["protocol"], 2);
  EXPECT_EQ(d["camera"]["name"], "webcam");  // the extra facts are merged in
  EXPECT_EQ(d["layout"]["marker"].size(), 7u);
  EXPECT_EQ(d["max_markers_per_state"], 27);
  EXPECT_EQ(d["dictionaries"]["APRILTAG_36h11"]["code"], 20);
  ASSERT_EQ(client.described_at_connect().size(), 2u);
  EXPECT_EQ(client.described_at_connect()[1].dictionary, 20);
  EXPECT_EQ(client.described_at_connect()[1].id, 100);
  EXPECT_EQ(client.described_at_connect()[1].side_m, 0.1);
  EXPECT_EQ(server_->subscribers(), 1);
  EXPECT_GE(server_->counters().describes, 1);
}

TEST_F(MarkersServerTest, DescriptionsAppliedWholeOrRefusedWhole) {
  MarkersClient client = Connect();
  ASSERT_TRUE(client.AddMarkers({{0, 7, 0.03}, {0, 3, 0.0}}));  // add 7, remove 3
  PollUntilReceived(*server_, server_->counters().received + 1, 0);
  EXPECT_EQ(server_->counters().accepted, 1);
  EXPECT_EQ(server_->table().size(), 2u);
  EXPECT_EQ(server_->table().SideOf(0, 7), 0.03);
  EXPECT_EQ(server_->table().SideOf(0, 3), 0.0);
  EXPECT_NE(server_->describe_json().find("\"id\":7"), std::string::npos);

  // three more would make 5 > 4: refused, nothing changes
  ASSERT_TRUE(client.AddMarkers({{0, 8, 0.03}, {0, 9, 0.03}, {0, 10, 0.03}}));
  PollUntilReceived(*server_, server_->counters().received + 1, 0);
  EXPECT_EQ(server_->counters().refused_limits, 1);
  EXPECT_EQ(server_->table().size(), 2u);

  // the client checks what it sends
  EXPECT_THROW(client.AddMarkers({{0, 50, 0.03}}), std::invalid_argument);
  EXPECT_THROW(client.AddMarkers({{0, 1, -1}}), std::invalid_argument);
  EXPECT_THROW(client.AddMarkers({{25, 1, 0.03}}), std::invalid_argument);
}

TEST_F(MarkersServerTest, MalformedDatagramsChangeNothing) {
  const bridge::Endpoint device = bridge::UdpSocket::MakeEndpoint("127.0.0.1", server_->local_port());
  std::vector<unsigned char> packet;
  bridge::EncodeMarkersCommand(0, 0, {{0, 1, 0.02}}, &packet);
  SendRaw(packet);  // a valid command from a non-subscriber: refused, and it subscribes nobody
  PollUntilReceived(*server_, server_->counters().received + 1, 0);
  EXPECT_EQ(server_->counters().refused_not_subscribed, 1);
  EXPECT_EQ(server_->subscribers(), 0);
  WhileServing(*server_, 0, [&] { EXPECT_GT(testing::WireSubscribe(*raw_, device, bridge::DeviceKind::kMarkers), 0); });
  const long before = server_->counters().received;
  bridge::EncodeMarkersCommand(0, 0, {{0, 1, 0.02}, {0, 50, 0.02}}, &packet);  // one bad id: all refused
  SendRaw(packet);
  bridge::EncodeMarkersCommand(0, 0, {{0, 1, 0.02}}, &packet);
  bridge::PutDouble(std::nan(""), packet.data() + packet.size() - 8);  // NaN side
  SendRaw(packet);
  bridge::EncodeMarkersState(0, 0, {}, &packet);  // a state, sent to the device
  SendRaw(packet);
  bridge::EncodeMarkersCommand(0, 0, {{0, 1, 0.02}}, &packet);
  bridge::PutDouble(1.0, packet.data() + 16);  // kind arm
  SendRaw(packet);
  SendRaw({'h', 'e', 'l', 'l', 'o'});
  PollUntilReceived(*server_, before + 5, 0);
  EXPECT_EQ(server_->counters().received, before + 5);
  EXPECT_EQ(server_->counters().refused_malformed, 5);
  EXPECT_EQ(server_->counters().accepted, 0);
  EXPECT_EQ(server_->table().size(), 2u);
  EXPECT_EQ(server_->table().SideOf(0, 1), 0.0);
  EXPECT_EQ(server_->subscribers(), 1);  // the raw socket, subscribed above: nothing dropped it
}

TEST_F(MarkersServerTest, StatesReachSubscribersUntilTheyFallSilent) {
  MarkersClient client = Connect();
  bridge::MarkersStateMsg state;
  state.described = 2;
  state.unknown = 1;
  bridge::MarkerRecordMsg r;
  r.dictionary = 0;
  r.id = 3;
  r.valid = true;
  r.reprojection_error_px = 0.02;
  const double T[16] = {1, 0, 0, 0.01, 0, 1, 0, 0.02, 0, 0, 1, 0.35, 0, 0, 0, 1};
  std::copy(T, T + 16, r.T_camera);
  r.world_valid = true;
  std::copy(T, T + 16, r.T_world);
  r.T_world[3] = 0.8;
  state.markers = {r};
  server_->Publish(41, 1.25, state, 1.0);
  const MarkersClient::State s = client.Read(1.0);
  EXPECT_EQ(s.seq, 41);
  EXPECT_EQ(s.time, 1.25);
  EXPECT_EQ(s.described, 2);
  EXPECT_EQ(s.unknown, 1);
  ASSERT_EQ(s.markers.size(), 1u);
  EXPECT_EQ(s.markers[0].id, 3);
  EXPECT_TRUE(s.markers[0].valid);
  EXPECT_EQ(s.markers[0].T_camera_marker(2, 3), 0.35);
  EXPECT_EQ(s.markers[0].T_world_marker(0, 3), 0.8);
  EXPECT_EQ(server_->counters().states, 1);

  // 11 s later with no word from the client: dropped, nothing sent
  server_->Publish(42, 1.3, state, 11.5);
  EXPECT_EQ(server_->subscribers(), 0);
  EXPECT_THROW(client.Read(0.2), bridge::TimeoutError);
  // a keep-alive subscribes it again
  ASSERT_TRUE(client.KeepAlive());
  PollUntilReceived(*server_, server_->counters().received + 1, 11.6);
  server_->Publish(43, 1.35, state, 11.7);
  EXPECT_EQ(client.Read(1.0).seq, 43);
}

}  // namespace
}  // namespace vlab::vision::server_test
