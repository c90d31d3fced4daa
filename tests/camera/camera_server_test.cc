// Tests bridge/bridge_camera_server.cc and bridge/bridge_camera_client.cc on
// loopback: the describe reply, subscription rules (the same as every device
// kind's), refusals, poses, ReceiveLatest, and the client's typed errors
// against scripted peers.
#include <atomic>
#include <chrono>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bridge/bridge_camera_client.h"
#include "bridge/bridge_camera_server.h"
#include "bridge/bridge_protocol.h"
#include "bridge/bridge_session.h"
#include "camera_test_util.h"
#include "wait_until.h"

namespace vlab::bridge::camera_server_test {
namespace {

using testing::FirstPatternMismatch;
using testing::PatternFrame;
using Bytes = std::vector<unsigned char>;

CameraServerConfig SmallConfig() {
  CameraServerConfig c;
  c.description.name = "webcam";
  c.description.server = "camera_server_test";
  c.description.source = "test pattern";
  c.description.width = 64;
  c.description.height = 48;
  c.description.fps = 25;
  c.description.encoding = CameraEncoding::kRaw;
  c.description.fx = 80;
  c.description.fy = 81;
  c.description.cx = 31.5;
  c.description.cy = 23.5;
  c.description.intrinsics_source = "fovy";
  c.description.distortion = {0.1097, -0.5567, -0.0019, 0.0002};
  c.description.latency_s = 0.03;
  c.description.pose = "fixed";
  c.chunk_bytes = 1000;  // 9216-byte frames: 10 chunks
  return c;
}

// a scripted peer: raw datagrams, no client library
struct Peer {
  explicit Peer(int port) : socket(UdpSocket::Bind("127.0.0.1", 0)), to(UdpSocket::MakeEndpoint("127.0.0.1", port)) {}
  void Send(const Bytes& b) { socket->SendTo(b.data(), b.size(), to); }
  // one request answered by the server (pumped by `poll`): the reply, or empty
  Bytes Ask(const Bytes& request, const std::function<void()>& poll) {
    Send(request);
    poll();
    Bytes buf(65536);
    const long n = socket->Receive(buf.data(), buf.size(), nullptr, 0.5);
    return n < 0 ? Bytes() : Bytes(buf.begin(), buf.begin() + n);
  }
  // the session reply's result, or -1
  static int Result(const Bytes& reply, double* cookie = nullptr) {
    Header h;
    std::vector<double> p;
    SessionResult r;
    double c = 0;
    if (!IsSessionReply(reply.data(), reply.size()) ||
        DecodePacket(reply.data(), reply.size(), &h, &p) != DecodeError::kNone || !ParseSessionReply(h, p, &c, &r)) {
      return -1;
    }
    if (cookie) *cookie = c;
    return static_cast<int>(r);
  }
  // the handshake, then a subscribe request (action 1) or a describe request (action -1); the last reply
  Bytes Session(CameraServer& server, int action = 1) {
    const auto poll = [&server] { server.Poll(0.2); };
    Bytes request;
    EncodeSubscribeRequest(DeviceKind::kCamera, 0, 1, &request);
    EXPECT_EQ(Result(Ask(request, poll), &cookie), static_cast<int>(SessionResult::kChallenge));
    if (action < 0) {
      EncodeDescribeRequest(static_cast<int>(DeviceKind::kCamera), cookie, &request);
    } else {
      EncodeSubscribeRequest(DeviceKind::kCamera, cookie, action, &request);
    }
    return Ask(request, poll);
  }
  double cookie = 0;
  // datagrams that arrive within timeout_s
  std::vector<Bytes> Drain(double timeout_s = 0.2) {
    std::vector<Bytes> out;
    Bytes buf(65536);
    for (long n; (n = socket->Receive(buf.data(), buf.size(), nullptr, timeout_s)) >= 0;) {
      out.emplace_back(buf.begin(), buf.begin() + n);
    }
    return out;
  }
  std::unique_ptr<UdpSocket> socket;
  Endpoint to;
};

long Chunks(const std::vector<Bytes>& datagrams) {
  long n = 0;
  for (const Bytes& d : datagrams) n += !d.empty() && d[0] != '{';
  return n;
}

TEST(CameraServerTest, DescribeReplyHasTheCameraFacts) {
  auto server = CameraServer::Create(SmallConfig());
  std::atomic<bool> stop{false};
  std::thread poll([&] {
    while (!stop) server->Poll(0.01);
  });
  CameraClient client = CameraClient::Connect("127.0.0.1", server->port());
  stop = true;
  poll.join();
  const nlohmann::json& j = client.describe();
  EXPECT_EQ(j["kind"], "camera");
  EXPECT_EQ(j["protocol"], 2);
  EXPECT_EQ(j["name"], "webcam");
  EXPECT_EQ(j["server"], "camera_server_test");
  EXPECT_EQ(j["source"], "test pattern");
  EXPECT_EQ(j["endpoint"]["port"], server->port());
  EXPECT_EQ(j["encoding"], "raw");
  EXPECT_EQ(j["chunk_bytes"], 1000);
  EXPECT_EQ(j["layout"]["state"].size(), 17u);
  EXPECT_EQ(j["latency_s"], 0.03);
  EXPECT_EQ(j["pose"], "fixed");
  EXPECT_EQ(client.name(), "webcam");
  EXPECT_EQ(client.width(), 64);
  EXPECT_EQ(client.height(), 48);
  EXPECT_EQ(client.fps(), 25);
  EXPECT_EQ(client.encoding(), CameraEncoding::kRaw);
  const CameraCalibration& k = client.calibration();
  EXPECT_EQ(k.fx, 80);
  EXPECT_EQ(k.fy, 81);
  EXPECT_EQ(k.cx, 31.5);
  EXPECT_EQ(k.cy, 23.5);
  EXPECT_EQ(k.source, "fovy");
  EXPECT_EQ(k.distortion[1], -0.5567);
  EXPECT_EQ(server->counters().endpoint.describes, 1);
  EXPECT_EQ(server->subscribers(), 1);
  EXPECT_EQ(client.Label(), "camera 'webcam' at 127.0.0.1:" + std::to_string(server->port()));
}

TEST(CameraServerTest, OnlyAProvenSubscribeRequestSubscribes) {
  CameraServerConfig config = SmallConfig();
  config.subscriber_timeout_s = 1.0;
  auto server = CameraServer::Create(config);
  const auto poll = [&server] { server->Poll(0.2); };
  Peer describer(server->port()), commander(server->port()), garbage(server->port());
  Bytes request;
  EncodeDescribeRequest(static_cast<int>(DeviceKind::kArm), 0, &request);  // answered whatever kind it names
  const Bytes challenge = describer.Ask(request, poll);
  EXPECT_EQ(challenge.size(), request.size());  // no larger than the request
  EXPECT_EQ(Peer::Result(challenge), static_cast<int>(SessionResult::kChallenge));
  Bytes command;
  EncodeSimCommand(0, 0, {1, 0}, &command);
  PutDouble(4, command.data() + 16);  // a camera "command": refused, and no subscription
  commander.Send(command);
  garbage.Send({1, 2, 3});
  Bytes state;
  EncodeWrenchState(0, 0, {}, &state);
  PutDouble(4, state.data() + 16);  // a camera state sent to the camera: refused
  garbage.Send(state);
  server->Poll(0.2);
  server->Poll(0.05);
  const EndpointCounters& c = server->counters().endpoint;
  EXPECT_EQ(c.received, 4);
  EXPECT_EQ(c.describes, 0);
  EXPECT_EQ(c.refused, 3);
  EXPECT_EQ(c.refused_malformed, 3);
  EXPECT_EQ(c.sessions.challenges, 1);
  EXPECT_EQ(server->subscribers(), 0);
  ASSERT_FALSE(server->Send(PatternFrame(0, 64, 48)));  // nobody to send to
  EXPECT_EQ(Chunks(commander.Drain(0.05)), 0);

  // the describe reply with the cookie; then a subscription
  const Bytes json = describer.Session(*server, -1);
  ASSERT_FALSE(json.empty());
  EXPECT_EQ(json[0], '{');
  EXPECT_EQ(server->subscribers(), 0);  // a describe does not subscribe
  EXPECT_EQ(Peer::Result(describer.Session(*server)), static_cast<int>(SessionResult::kSubscribed));
  const auto commander_heard = std::chrono::steady_clock::now();  // at the latest: its last request
  EXPECT_EQ(Peer::Result(commander.Session(*server)), static_cast<int>(SessionResult::kSubscribed));
  EXPECT_EQ(server->subscribers(), 2);
  ASSERT_TRUE(server->Send(PatternFrame(1, 64, 48)));
  EXPECT_EQ(Chunks(describer.Drain()), 10);
  EXPECT_EQ(Chunks(commander.Drain()), 10);
  EXPECT_EQ(Chunks(garbage.Drain(0.05)), 0);
  EXPECT_EQ(server->counters().chunks_sent, 20);

  // silent subscribers are dropped after subscriber_timeout_s of the wall clock; a renewal keeps
  // one. The describer renews every 20 ms while the test waits for the silent commander's drop,
  // which cannot come before the timeout (it can come later on a busy machine).
  Bytes renew;
  EncodeSubscribeRequest(DeviceKind::kCamera, describer.cookie, 1, &renew);
  std::int64_t id = 2;
  const bool dropped = vlab::testing::WaitUntil([&] {
    describer.Drain(0.0);  // the frames before: the reply must come first
    EXPECT_EQ(Peer::Result(describer.Ask(renew, poll)), static_cast<int>(SessionResult::kSubscribed));
    server->Send(PatternFrame(id++, 64, 48));  // a send drops the silent ones
    if (server->subscribers() == 1) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));  // pacing the renewals
    return false;
  });
  const double silent_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - commander_heard).count();
  ASSERT_TRUE(dropped) << "the silent commander was not dropped within 20 s";
  EXPECT_GE(silent_s, config.subscriber_timeout_s) << "dropped before its timeout";
  EXPECT_EQ(server->counters().subscribers_dropped, 1);
  // the renewed describer gets the next frame whole, the dropped commander nothing
  describer.Drain(0.0);
  commander.Drain(0.0);
  server->Send(PatternFrame(id, 64, 48));
  EXPECT_EQ(server->subscribers(), 1);
  EXPECT_EQ(server->counters().subscribers_dropped, 1);
  EXPECT_EQ(Chunks(describer.Drain()), 10);
  EXPECT_EQ(Chunks(commander.Drain(0.05)), 0);
}

TEST(CameraServerTest, AFullTableRefusesNewcomersAndKeepsItsSubscribers) {
  CameraServerConfig config = SmallConfig();
  config.max_subscribers = 2;
  auto server = CameraServer::Create(config);
  Peer a(server->port()), b(server->port()), c(server->port());
  EXPECT_EQ(Peer::Result(a.Session(*server)), static_cast<int>(SessionResult::kSubscribed));
  EXPECT_EQ(Peer::Result(b.Session(*server)), static_cast<int>(SessionResult::kSubscribed));
  EXPECT_EQ(Peer::Result(c.Session(*server)), static_cast<int>(SessionResult::kFull));
  EXPECT_EQ(server->subscribers(), 2);
  EXPECT_EQ(server->counters().endpoint.sessions.refused_full, 1);
  server->Send(PatternFrame(2, 64, 48));
  EXPECT_EQ(Chunks(a.Drain()), 10);  // nobody was evicted
  EXPECT_EQ(Chunks(c.Drain(0.1)), 0);
}

TEST(CameraServerTest, RefusesFramesThatBreakTheLayout) {
  auto server = CameraServer::Create(SmallConfig());
  Peer p(server->port());
  p.Session(*server);
  EXPECT_TRUE(server->Send(PatternFrame(5, 64, 48)));
  EXPECT_FALSE(server->Send(PatternFrame(5, 64, 48)));  // id not increasing
  EXPECT_FALSE(server->Send(PatternFrame(4, 64, 48)));
  CameraFrame short_raw = PatternFrame(6, 64, 48);
  short_raw.data.pop_back();
  EXPECT_FALSE(server->Send(short_raw));
  CameraFrame jpeg = PatternFrame(7, 64, 48);  // any byte count is fine for JPEG
  jpeg.encoding = CameraEncoding::kJpeg;
  jpeg.data.resize(123);
  EXPECT_TRUE(server->Send(jpeg));
  EXPECT_EQ(server->counters().refused_frames, 3);
  EXPECT_EQ(server->counters().frames_sent, 2);
}

TEST(CameraServerTest, NothingIsEncodedWithoutSubscribers) {
  CameraServerConfig config = SmallConfig();
  config.description.encoding = CameraEncoding::kJpeg;
  auto server = CameraServer::Create(config);
  std::vector<std::uint8_t> rgb(64 * 48 * 3, 100);
  EXPECT_FALSE(server->SendImage(0, 0, rgb.data(), CameraPose()));
  EXPECT_EQ(server->counters().frames, 1);
  EXPECT_EQ(server->counters().chunks_sent, 0);
  EXPECT_EQ(server->counters().refused_frames, 0);
}

TEST(CameraServerTest, FramesCarryPoseAndTimeAndReceiveLatestSkipsToTheNewest) {
  auto server = CameraServer::Create(SmallConfig());
  std::atomic<bool> stop{false};
  std::thread poll([&] {
    while (!stop) server->Poll(0.01);
  });
  CameraClient client = CameraClient::Connect("127.0.0.1", server->port());
  stop = true;
  poll.join();
  CameraPose pose;
  pose.valid = true;
  pose.p_WC = Eigen::Vector3d(0.75, -0.1, 1.4);
  pose.q_WC = Eigen::Quaterniond(0, 1, 0, 0);
  std::vector<std::uint8_t> rgb(64 * 48 * 3);
  for (int i = 0; i < 5; ++i) {
    testing::FillPattern(i, &rgb);
    ASSERT_TRUE(server->SendImage(i, 0.04 * i, rgb.data(), pose));
  }
  CameraClient::Frame f;
  client.ReceiveLatest(1.0, &f);
  EXPECT_EQ(f.id, 4);
  EXPECT_DOUBLE_EQ(f.time_s, 0.16);
  EXPECT_EQ(FirstPatternMismatch(4, f.rgb), -1);
  EXPECT_TRUE(f.pose.valid);
  EXPECT_EQ(f.pose.p_WC, pose.p_WC);
  EXPECT_EQ(f.pose.q_WC.coeffs(), pose.q_WC.coeffs());
  EXPECT_EQ(client.frames_skipped(), 4);
  EXPECT_EQ(client.frames_returned(), 1);
  EXPECT_THROW(client.Receive(0.2), TimeoutError);
}

// a scripted device: answers the first datagram with `reply`, then sends `then`
void FakeDevice(UdpSocket* socket, std::string reply, Bytes then) {
  Bytes buf(65536);
  Endpoint from;
  if (socket->Receive(buf.data(), buf.size(), &from, 5.0) < 0) return;
  socket->SendTo(reinterpret_cast<const unsigned char*>(reply.data()), reply.size(), from);
  if (!then.empty()) socket->SendTo(then.data(), then.size(), from);
}

std::string Describe(const std::string& patch_key = "", const nlohmann::json& patch_value = nullptr) {
  CameraDescription d;
  d.fx = d.fy = 500;
  nlohmann::json j = nlohmann::json::parse(CameraDescribeJson(d, "127.0.0.1", 1, 60000));
  if (!patch_key.empty()) {
    if (patch_value.is_null()) {
      j.erase(patch_key);
    } else {
      j[patch_key] = patch_value;
    }
  }
  return j.dump();
}

template <typename Error>
std::string ConnectError(const std::string& reply, Bytes then = {}) {
  auto socket = UdpSocket::Bind("127.0.0.1", 0);
  std::thread device(FakeDevice, socket.get(), reply, then);
  std::string message = "no error";
  try {
    CameraClientOptions options;
    options.timeout_s = 0.5;
    CameraClient client = CameraClient::Connect("127.0.0.1", socket->local_port(), options);
    client.Receive(0.5);
  } catch (const Error& e) {
    message = e.what();
  } catch (const std::exception& e) {
    message = std::string("other error: ") + e.what();
  }
  device.join();
  return message;
}

TEST(CameraClientTest, TypedErrors) {
  EXPECT_NE(ConnectError<VersionMismatch>(Describe("protocol", 1)).find("protocol version 1"), std::string::npos);
  EXPECT_NE(ConnectError<ProtocolError>(Describe("kind", "arm")).find("not \"camera\""), std::string::npos);
  EXPECT_NE(ConnectError<ProtocolError>(Describe("intrinsics")).find("intrinsics.fx"), std::string::npos);
  EXPECT_NE(ConnectError<ProtocolError>(Describe("encoding", "png")).find("encoding"), std::string::npos);
  EXPECT_NE(ConnectError<ProtocolError>("{not json").find("not valid JSON"), std::string::npos);
  // a chunk of another protocol version while connecting
  CameraFrame f = PatternFrame(0, 4, 2);
  Bytes chunk = testing::Chunks(f, 60000)[0];
  PutDouble(1, chunk.data() + 8);
  EXPECT_NE(ConnectError<VersionMismatch>(Describe(), chunk).find("of protocol version 1"), std::string::npos);
  // nothing there
  const int port = UdpSocket::Bind("127.0.0.1", 0)->local_port();
  CameraClientOptions options;
  options.timeout_s = 0.3;
  EXPECT_THROW(CameraClient::Connect("127.0.0.1", port, options), TimeoutError);
  EXPECT_THROW(CameraClient::Connect("127.0.0.1", 0), NetworkError);
  EXPECT_THROW(CameraClient::Connect("300.1.2.3", 5000), NetworkError);
}

TEST(CameraClientTest, TwoClientsReceiveEveryFrame) {
  auto server = CameraServer::Create(SmallConfig());
  std::atomic<bool> stop{false};
  std::thread poll([&] {
    while (!stop) server->Poll(0.01);
  });
  CameraClient a = CameraClient::Connect("127.0.0.1", server->port());
  CameraClient b = CameraClient::Connect("127.0.0.1", server->port());
  stop = true;
  poll.join();
  for (int i = 0; i < 3; ++i) server->Send(PatternFrame(i, 64, 48));
  for (CameraClient* c : {&a, &b}) {
    for (int i = 0; i < 3; ++i) {
      const CameraClient::Frame f = c->Receive(1.0);
      EXPECT_EQ(f.id, i);
      EXPECT_EQ(FirstPatternMismatch(i, f.data), -1);
    }
  }
}

}  // namespace
}  // namespace vlab::bridge::camera_server_test
