// Tests the Foxglove WebSocket protocol's pieces (src/view/view_foxglove.cc)
// and a Foxglove server's upgrade rules (view_server_http.cc): the server's
// JSON messages as the spec lays them out, the message data frame's bytes, a
// client's subscriptions (one per channel, ids unique, bad entries named and
// skipped), every write a read-only server does not offer refused, and an
// upgrade served only with the subprotocol and an allowed Origin
// (--allow-origin: the whole origin); a session that sends serverInfo and
// advertise, the newest message of each channel subscribed (again after a
// new subscription: a /scene sent once), and an error status for each write.
// With Foxglove's own client and a served run: foxglove_test.cc.
#include <sys/socket.h>

#include <chrono>
#include <cstring>
#include <future>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "view/view_access.h"
#include "view/view_foxglove.h"
#include "view/view_server.h"
#include "view_clients.h"
#include "wait_until.h"

namespace vlab::view {
namespace foxglove_protocol_test {

using view_test::Raw;
using view_test::Status;

TEST(FoxgloveProtocolTest, ServerInfoAndAdvertiseAsTheSpecSays) {
  const nlohmann::json info = nlohmann::json::parse(FoxgloveServerInfo());
  EXPECT_EQ(info["op"], "serverInfo");
  EXPECT_EQ(info["capabilities"], nlohmann::json::array()) << "read-only: no clientPublish, parameters, services";
  const nlohmann::json ad =
      nlohmann::json::parse(FoxgloveAdvertise({{"/tf", "tf2_msgs/msg/TFMessage", "T"}, {"/pa10", "a/msg/B", "S"}}));
  EXPECT_EQ(ad["op"], "advertise");
  ASSERT_EQ(ad["channels"].size(), 2u);
  EXPECT_EQ(ad["channels"][1], (nlohmann::json{{"id", 1},
                                               {"topic", "/pa10"},
                                               {"encoding", "cdr"},
                                               {"schemaName", "a/msg/B"},
                                               {"schemaEncoding", "ros2msg"},
                                               {"schema", "S"}}));
  const nlohmann::json status = nlohmann::json::parse(FoxgloveStatus(2, std::string("bad \xff byte")));
  EXPECT_EQ(status["op"], "status");
  EXPECT_EQ(status["level"], 2);
}

TEST(FoxgloveProtocolTest, MessageDataFrameBytes) {
  // opcode 0x01, uint32 subscription id, uint64 log time (ns), payload; little-endian
  char header[5];
  FoxgloveDataHeader(0x04030201u, header);
  EXPECT_EQ(std::string(header, 5), std::string("\x01\x01\x02\x03\x04", 5));
  const std::string record = FoxgloveRecord(1500000000ull, "cdr");
  ASSERT_EQ(record.size(), 11u);
  std::uint64_t ns = 0;
  std::memcpy(&ns, record.data(), 8);
  EXPECT_EQ(ns, 1500000000ull);
  EXPECT_EQ(record.substr(8), "cdr");
}

TEST(FoxgloveProtocolTest, SubscriptionsOnePerChannelAndBadEntriesNamed) {
  FoxgloveSubscriptions s(3);
  bool read_only = false, malformed = false;
  EXPECT_EQ(s.Apply(R"({"op":"subscribe","subscriptions":[{"id":7,"channelId":0},{"id":9,"channelId":2}]})", false,
                    &read_only, &malformed),
            "");
  EXPECT_EQ(s.IdOf(0), 7);
  EXPECT_EQ(s.IdOf(1), -1);
  EXPECT_EQ(s.IdOf(2), 9);
  // an id in use, a channel already subscribed, no such channel, bad types: named, the good one applied
  const std::string why = s.Apply(R"({"op":"subscribe","subscriptions":[{"id":7,"channelId":1},)"
                                  R"({"id":8,"channelId":0},{"id":10,"channelId":3},{"id":-1,"channelId":1},)"
                                  R"({"id":"x","channelId":1},{"id":11,"channelId":1}]})",
                                  false, &read_only, &malformed);
  EXPECT_TRUE(malformed);
  EXPECT_FALSE(read_only);
  EXPECT_NE(why.find("subscription id 7 is in use"), std::string::npos) << why;
  EXPECT_NE(why.find("channel 0 is already subscribed"), std::string::npos) << why;
  EXPECT_NE(why.find("no channel 3"), std::string::npos) << why;
  EXPECT_NE(why.find("integer 'id' and 'channelId'"), std::string::npos) << why;
  EXPECT_EQ(s.IdOf(1), 11);
  // unsubscribe frees the channel and the id
  EXPECT_EQ(s.Apply(R"({"op":"unsubscribe","subscriptionIds":[7]})", false, &read_only, &malformed), "");
  EXPECT_EQ(s.IdOf(0), -1);
  EXPECT_NE(
      s.Apply(R"({"op":"unsubscribe","subscriptionIds":[7]})", false, &read_only, &malformed).find("no subscription 7"),
      std::string::npos);
  EXPECT_EQ(s.Apply(R"({"op":"subscribe","subscriptions":[{"id":7,"channelId":0}]})", false, &read_only, &malformed),
            "");
  EXPECT_EQ(s.IdOf(0), 7);
}

TEST(FoxgloveProtocolTest, WritesAreRefusedAndChangeNothing) {
  FoxgloveSubscriptions s(2);
  bool read_only = false, malformed = false;
  for (const char* op :
       {"advertise", "unadvertise", "getParameters", "setParameters", "subscribeParameterUpdates",
        "unsubscribeParameterUpdates", "subscribeConnectionGraph", "unsubscribeConnectionGraph", "fetchAsset"}) {
    const std::string why =
        s.Apply(std::string(R"({"op":")") + op + R"(","channels":[]})", false, &read_only, &malformed);
    EXPECT_TRUE(read_only) << op;
    EXPECT_NE(why.find("read-only"), std::string::npos) << why;
  }
  // client message data (0x01) and a service call (0x02): refused; another opcode is malformed
  EXPECT_NE(s.Apply(std::string("\x01\x00\x00\x00\x00xyz", 8), true, &read_only, &malformed).find("read-only"),
            std::string::npos);
  EXPECT_TRUE(read_only);
  s.Apply(std::string("\x02", 1), true, &read_only, &malformed);
  EXPECT_TRUE(read_only);
  s.Apply(std::string("\x07", 1), true, &read_only, &malformed);
  EXPECT_TRUE(malformed);
  s.Apply("", true, &read_only, &malformed);
  EXPECT_TRUE(malformed);
  for (const char* bad : {"not json", "[1]", R"({"op":3})", R"({"op":"nothing"})", R"({"op":"subscribe"})",
                          R"({"op":"unsubscribe","subscriptionIds":{}})"}) {
    EXPECT_FALSE(s.Apply(bad, false, &read_only, &malformed).empty()) << bad;
    EXPECT_TRUE(malformed) << bad;
    EXPECT_FALSE(read_only) << bad;
  }
  EXPECT_EQ(s.IdOf(0), -1);
  EXPECT_EQ(s.IdOf(1), -1);
}

// the upgrade request of a Foxglove client, with an Origin line when given
std::string FoxgloveUpgrade(int port, const std::string& protocol, const std::string& origin) {
  return "GET / HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) +
         "\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
         "Sec-WebSocket-Version: 13\r\n" +
         (protocol.empty() ? "" : "Sec-WebSocket-Protocol: " + protocol + "\r\n") +
         (origin.empty() ? "" : "Origin: " + origin + "\r\n") + "\r\n";
}

// what an accepted upgrade gets until the serverInfo message is in it (at most 10 s: a hang guard)
std::string UntilServerInfo(int port, const std::string& request) {
  Raw raw(port);
  raw.Send(request);
  std::string got;
  for (int i = 0; i < 200 && got.find("\"op\":\"serverInfo\"") == std::string::npos && !raw.closed(); ++i) {
    got += raw.ReadAll(0.05);
  }
  return got;
}

TEST(FoxgloveProtocolTest, UpgradeNeedsTheSubprotocolAndAnAllowedOrigin) {
  ViewServerConfig config;
  config.port = 0;
  config.foxglove = true;
  config.foxglove_channels = {{"/tf", "tf2_msgs/msg/TFMessage", "T"}};
  config.allowed_origins = {"https://app.foxglove.dev"};
  std::unique_ptr<ViewServer> server = ViewServer::Create(config, {}, nullptr);
  const int port = server->port();
  // served: the subprotocol chosen in the answer, serverInfo the first message
  const std::string ok = UntilServerInfo(port, FoxgloveUpgrade(port, "foxglove.websocket.v1", ""));
  EXPECT_EQ(Status(ok), 101) << ok;
  EXPECT_NE(ok.find("Sec-WebSocket-Protocol: foxglove.websocket.v1"), std::string::npos) << ok;
  EXPECT_NE(ok.find("\"op\":\"serverInfo\""), std::string::npos) << ok;
  EXPECT_EQ(Status(UntilServerInfo(port, FoxgloveUpgrade(port, "x, foxglove.websocket.v1", ""))), 101);
  EXPECT_EQ(Status(UntilServerInfo(port, FoxgloveUpgrade(port, "foxglove.websocket.v1", "HTTPS://App.Foxglove.dev"))),
            101);
  EXPECT_EQ(Status(UntilServerInfo(port, FoxgloveUpgrade(port, "foxglove.websocket.v1", "http://localhost:8080"))),
            101);
  // refused: no subprotocol or another one (400), a foreign origin, the allowed one on another scheme or port (403)
  EXPECT_EQ(Status(Raw(port).Send(FoxgloveUpgrade(port, "", "")).ReadAll()), 400);
  EXPECT_EQ(Status(Raw(port).Send(FoxgloveUpgrade(port, "foxglove.websocket.v2", "")).ReadAll()), 400);
  for (const std::string origin : {"http://evil.example", "http://app.foxglove.dev", "https://app.foxglove.dev:444",
                                   "https://app.foxglove.dev.evil.example"}) {
    EXPECT_EQ(Status(Raw(port).Send(FoxgloveUpgrade(port, "foxglove.websocket.v1", origin)).ReadAll()), 403) << origin;
  }
  // no page: a GET is 404
  EXPECT_EQ(Status(Raw(port).Send("GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n").ReadAll()), 404);
  EXPECT_EQ(server->counters().bad_host, 4);
}

// a message data frame's subscription id, log time and payload
struct Data {
  std::uint32_t id = 0;
  std::uint64_t ns = 0;
  std::string payload;
};
Data DataOf(const std::string& m) {
  Data d;
  EXPECT_GE(m.size(), 13u);
  if (m.size() < 13) return d;
  EXPECT_EQ(m[0], '\x01') << "opcode: message data";
  std::memcpy(&d.id, m.data() + 1, 4);
  std::memcpy(&d.ns, m.data() + 5, 8);
  d.payload = m.substr(13);
  return d;
}

// the next message within 10 s (a guard against a hang), else "": the socket is shut down so that the read ends
std::string ReadWithin(view_test::WsClient& client) {
  auto next = std::async(std::launch::async, [&client] {
    std::string m;
    client.TryRead(&m);
    return m;
  });
  if (next.wait_for(std::chrono::seconds(10)) != std::future_status::ready) {
    ::shutdown(client.native_handle(), SHUT_RDWR);
  }
  return next.get();
}

TEST(FoxgloveProtocolTest, SessionSendsWhatWasSubscribedAndRefusesWrites) {
  ViewServerConfig config;
  config.port = 0;
  config.foxglove = true;
  config.foxglove_channels = {{"/scene", "a/msg/S", "S"}, {"/pa10", "a/msg/P", "P"}};
  std::unique_ptr<ViewServer> server = ViewServer::Create(config, {}, nullptr);
  server->Publish(FoxgloveRecord(0, "scene"), 0);  // sent once, as /scene is
  server->Publish(FoxgloveRecord(2000000, "p1"), 1);
  view_test::WsOptions options;
  options.path = "/";
  options.subprotocol = kFoxgloveSubprotocol;
  view_test::WsClient client(server->port(), options);
  EXPECT_EQ(nlohmann::json::parse(ReadWithin(client), nullptr, false)["op"], "serverInfo");
  const nlohmann::json advertise = nlohmann::json::parse(ReadWithin(client), nullptr, false);
  ASSERT_EQ(advertise["channels"].size(), 2u);
  EXPECT_EQ(advertise["channels"][1]["topic"], "/pa10");
  // subscribed: the channel's newest message, under the client's id, with its log time
  client.WriteText(R"({"op":"subscribe","subscriptions":[{"id":5,"channelId":1}]})");
  Data d = DataOf(ReadWithin(client));
  EXPECT_EQ(d.id, 5u);
  EXPECT_EQ(d.ns, 2000000u);
  EXPECT_EQ(d.payload, "p1");
  // writes: an error status each, and the session goes on
  client.WriteText(R"({"op":"advertise","channels":[{"id":1,"topic":"/cmd","encoding":"cdr","schemaName":"x"}]})");
  client.Write(std::string("\x01\x01\x00\x00\x00payload", 12));
  for (int i = 0; i < 2; ++i) {
    const nlohmann::json status = nlohmann::json::parse(ReadWithin(client), nullptr, false);
    EXPECT_EQ(status["op"], "status");
    EXPECT_EQ(status["level"], 2);
    EXPECT_NE(status["message"].get<std::string>().find("read-only"), std::string::npos) << status;
  }
  server->Publish(FoxgloveRecord(4000000, "p2"), 1);
  d = DataOf(ReadWithin(client));
  EXPECT_EQ(d.payload, "p2");
  // a message published once reaches a later subscription, and a new one after an unsubscribe
  client.WriteText(R"({"op":"subscribe","subscriptions":[{"id":6,"channelId":0}]})");
  d = DataOf(ReadWithin(client));
  EXPECT_EQ(d.id, 6u);
  EXPECT_EQ(d.payload, "scene");
  client.WriteText(R"({"op":"unsubscribe","subscriptionIds":[6]})");
  client.WriteText(R"({"op":"subscribe","subscriptions":[{"id":7,"channelId":0}]})");
  d = DataOf(ReadWithin(client));
  EXPECT_EQ(d.id, 7u);
  EXPECT_EQ(d.payload, "scene");
  EXPECT_TRUE(testing::WaitUntil([&] { return server->counters().frames_sent == 4; }))
      << "4 messages: p1, p2, scene twice";
  EXPECT_EQ(server->counters().client_refused, 2);
  EXPECT_EQ(server->counters().client_bad, 0);
}

TEST(FoxgloveProtocolTest, AllowOriginTakesWholeOrigins) {
  EXPECT_TRUE(ValidOrigin("https://app.foxglove.dev"));
  EXPECT_TRUE(ValidOrigin("http://lab-pc:8080"));
  EXPECT_TRUE(ValidOrigin("https://[::1]:8080"));
  for (const char* bad : {"app.foxglove.dev", "https://app.foxglove.dev/", "https://", "*", "null", "file://x",
                          "https://user@app.foxglove.dev", "ftp://x"}) {
    EXPECT_FALSE(ValidOrigin(bad)) << bad;
  }
}

}  // namespace foxglove_protocol_test
}  // namespace vlab::view
