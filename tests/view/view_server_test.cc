// Tests the server of vlab view (src/view/view_server.cc) on loopback with
// hostile clients: it serves only its own table (path traversal in every
// spelling gets 404/400, never a file of the disk), bounds header, body,
// connections and WebSocket messages, answers malformed requests with an
// HTTP error and malformed WebSocket frames by closing that session, and
// keeps serving afterwards; a WebSocket client gets the newest frame, not a
// queue of old ones. The panels' channels (/camera, /plot) are each their own
// newest-wins slot, and their clients count toward the same WebSocket table
// and message bounds. Host and Origin (view_access.h): a foreign Origin and a
// rebinding Host are refused (403, 421) on pages and WebSocket upgrades, the
// loopback names, the bound address and the names allowed are served.
// The limits that keep an attacker from locking a viewer out are tested in
// view_server_limits_test.cc.
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "view/view_access.h"
#include "view/view_server.h"
#include "view_clients.h"
#include "wait_until.h"

namespace vlab::view {
namespace {

using namespace view_test;  // NOLINT: the clients of view_clients.h

std::unique_ptr<ViewServer> Start(int max_connections = 16, std::vector<std::string> channels = {"/ws"},
                                  std::vector<std::string> allowed_hosts = {}) {
  ViewServerConfig config;
  config.max_connections = max_connections;
  config.channels = std::move(channels);
  config.allowed_hosts = std::move(allowed_hosts);
  return StartServer(config);
}

TEST(ViewServerTest, ServesItsTableAndNothingElse) {
  auto server = Start();
  const int port = server->port();
  EXPECT_EQ(server->address(), "127.0.0.1");  // loopback by default
  std::string r = Get(port, "/");
  EXPECT_EQ(Status(r), 200);
  EXPECT_NE(r.find(kPage), std::string::npos);
  EXPECT_EQ(Status(Get(port, "/scene.json")), 200);
  EXPECT_EQ(Status(Get(port, "/view.js?v=1")), 200);  // a query is not part of the path
  EXPECT_EQ(Status(Get(port, "/nothing")), 404);
  // path traversal, in the spellings that reach files elsewhere
  for (const char* target :
       {"/../../../../etc/passwd", "/%2e%2e/%2e%2e/%2e%2e/etc/passwd", "/index.html/../../../etc/passwd",
        "/..%2f..%2f..%2fetc%2fpasswd", "//etc/passwd", "/etc/passwd", "http://x/../../etc/passwd",
        "/..\\..\\..\\etc\\passwd", "/index.html%00", "*", "../../etc/passwd"}) {
    r = Get(port, target);
    const int status = Status(r);
    EXPECT_TRUE(status == 404 || status == 400) << target << ": " << r.substr(0, 40);
    EXPECT_EQ(r.find("root:"), std::string::npos) << target;
  }
  // read-only: no other method
  EXPECT_EQ(Status(Raw(port).Send("DELETE /index.html HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n").ReadAll(1)), 405);
  EXPECT_EQ(Status(Raw(port).Send("POST / HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 2\r\n\r\nhi").ReadAll(1)),
            405);
  // HEAD: the headers of a GET, no body
  r = Raw(port).Send("HEAD / HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n").ReadAll();
  EXPECT_EQ(Status(r), 200);
  EXPECT_EQ(r.find(kPage), std::string::npos);
}

TEST(ViewServerTest, OversizedAndMalformedRequestsGetAnHttpError) {
  auto server = Start();
  const int port = server->port();
  // headers beyond 8 KiB: 431; a body beyond 1 KiB: 413 (ViewServerConfig's bounds)
  const std::string big(20000, 'a');
  EXPECT_EQ(Status(Raw(port).Send("GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Big: " + big + "\r\n\r\n").ReadAll()), 431);
  EXPECT_EQ(Status(Raw(port).Send("GET /" + big + " HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n").ReadAll()), 431);
  EXPECT_EQ(
      Status(Raw(port).Send("POST / HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 100000\r\n\r\n" + big).ReadAll()),
      413);
  // not HTTP
  EXPECT_EQ(Status(Raw(port).Send("HELLO\r\n\r\n").ReadAll()), 400);
  EXPECT_EQ(Status(Raw(port).Send("GET / HTTP/1.1\r\nHost x\r\n\r\n").ReadAll()), 400);
  EXPECT_EQ(Status(Raw(port).Send("GET / HTTP/1.1\r\nContent-Length: -5\r\n\r\n").ReadAll()), 400);
  EXPECT_EQ(Status(Raw(port).Send("GET / HTTP/1.1\r\nTransfer-Encoding: chunked\r\n\r\nzz\r\n").ReadAll()), 400);
  std::string garbage;
  for (int i = 0; i < 3000; ++i) garbage += static_cast<char>((i * 7919) & 0xff);
  EXPECT_EQ(Status(Raw(port).Send(garbage).ReadAll()), 400);
  // a client that connects and leaves, one that sends half a request and leaves
  { Raw gone(port); }
  {
    Raw half(port);
    half.Send("GET / HT");
  }
  // a WebSocket upgrade elsewhere than /ws: 404
  EXPECT_EQ(
      Status(Raw(port)
                 .Send("GET /index.html HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                       "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n")
                 .ReadAll()),
      404);
  // still serving
  EXPECT_EQ(Status(Get(port, "/")), 200);
  EXPECT_GE(server->counters().errors, 9);
}

TEST(ViewServerTest, WebSocketGetsTheNewestFrameAndSurvivesBadFrames) {
  auto server = Start();
  const int port = server->port();
  // fifty frames before anyone listens: a client gets the newest, not a queue
  for (int i = 1; i <= 50; ++i) server->Publish("frame " + std::to_string(i));
  WsClient client(port);
  EXPECT_EQ(client.Read(), "frame 50");
  server->Publish("frame 51");
  EXPECT_EQ(client.Read(), "frame 51");
  // read-only: what a client sends is dropped
  client.Write("pause");
  server->Publish("frame 52");
  EXPECT_EQ(client.Read(), "frame 52");
  // a message above the bound (1 KiB) closes that session only
  client.TryWrite(std::string(5000, 'x'));  // the server may close while it is sent
  server->Publish("frame 53");
  bool failed = false;
  for (int i = 0; i < 3 && !failed; ++i) failed = !client.TryRead();
  EXPECT_TRUE(failed) << "the session should have been closed";

  // malformed frames: an unmasked client frame, a reserved opcode, garbage
  for (const std::string& bad : {std::string("\x82\x03"
                                             "abc",
                                             5),
                                 std::string("\x83\x80\x01\x02\x03\x04", 6), std::string(64, '\xff')}) {
    WsClient victim(port);
    bool failed = !victim.SendRaw(bad);
    for (int i = 0; i < 20 && !failed; ++i) {
      server->Publish("more");
      failed = !victim.TryRead();
    }
    EXPECT_TRUE(failed) << "a malformed frame must end the session";
  }
  // the server counts a bad session in its read handler, on its own thread: wait for the count
  EXPECT_TRUE(vlab::testing::WaitUntil([&] { return server->counters().ws_closed_bad >= 3; }))
      << server->counters().ws_closed_bad;
  // the server still serves pages and frames
  EXPECT_EQ(Status(Get(port, "/")), 200);
  server->Publish("frame 54");
  WsClient after(port);
  EXPECT_EQ(after.Read(), "frame 54");
}

TEST(ViewServerTest, PanelChannelsAreSeparateAndShareTheBounds) {
  auto server = Start(3, {"/ws", "/camera", "/plot"});
  const int port = server->port();
  server->Publish("pose 1");
  server->Publish("picture 1", 1);
  server->Publish("picture 2", 1);  // newest wins on each channel alone
  server->Publish("sample 1", 2);
  EXPECT_THROW(server->Publish("nowhere", 3), std::invalid_argument);
  WsClient poses(port), camera(port, "/camera"), plot(port, "/plot");
  EXPECT_EQ(poses.Read(), "pose 1");
  EXPECT_EQ(camera.Read(), "picture 2");
  EXPECT_EQ(plot.Read(), "sample 1");
  server->Publish("sample 2", 2);
  EXPECT_EQ(plot.Read(), "sample 2");
  // three WebSocket clients fill the three places: a fourth is told so and closed; pages are still served
  {
    WsClient fourth(port, "/plot");
    EXPECT_THROW(fourth.Read(), WsError);
    EXPECT_EQ(fourth.close_reason().code, kCloseTryAgainLater);
    EXPECT_NE(fourth.close_reason().reason.find("server full"), std::string::npos);
  }
  EXPECT_EQ(Status(Get(port, "/")), 200);
  // an oversized message on a panel's channel closes that session, as on /ws
  camera.TryWrite(std::string(5000, 'x'));
  server->Publish("picture 3", 1);
  bool failed = false;
  for (int i = 0; i < 3 && !failed; ++i) failed = !camera.TryRead();
  EXPECT_TRUE(failed) << "the camera session should have been closed";
  EXPECT_TRUE(vlab::testing::WaitUntil([&] { return server->counters().ws_closed_bad >= 1; }))
      << server->counters().ws_closed_bad;
  // its slot is free again; a path that is no channel is 404
  std::string r = Raw(port).Send(Upgrade("/other", "127.0.0.1")).ReadAll(1);
  EXPECT_EQ(Status(r), 404) << r;
}

TEST(ViewServerTest, ForeignOriginAndRebindingHostAreRefused) {
  auto server = Start(16, {"/ws"}, {"Lab-PC.example"});
  const int port = server->port();
  const std::string p = std::to_string(port);
  auto get = [&](const std::string& headers) {
    return Status(Raw(port).Send("GET / HTTP/1.1\r\n" + headers + "Connection: close\r\n\r\n").ReadAll());
  };
  // loopback names and addresses, with and without the port; a name given; no Host at all (not a browser)
  for (const std::string& host :
       std::vector<std::string>{"127.0.0.1:" + p, "127.0.0.1", "localhost:" + p, "LOCALHOST", "localhost.",
                                "[::1]:" + p, "[::1]", "127.9.8.7:" + p, "lab-pc.example:" + p, "Lab-PC.example"}) {
    EXPECT_EQ(get("Host: " + host + "\r\n"), 200) << host;
  }
  EXPECT_EQ(get(""), 200) << "no Host";
  // a rebinding page's name (it resolves here, but it is not ours), other addresses, malformed values: 421
  for (const std::string& host : std::vector<std::string>{
           "evil.example", "evil.example:" + p, "127.0.0.1.nip.io:" + p, "localhost.evil.example", "10.1.2.3:" + p,
           "::1", "127.0.0.1:80:80", "[::1", "[127.0.0.1]", "", "127.1", "localhost:http", "lab-pc.example.evil"}) {
    EXPECT_EQ(get("Host: " + host + "\r\n"), 421) << "'" << host << "'";
  }
  EXPECT_EQ(get("Host: 127.0.0.1\r\nHost: evil.example\r\n"), 400) << "two Hosts";
  EXPECT_NE(Raw(port).Send("GET / HTTP/1.1\r\nHost: labhost:" + p + "\r\n\r\n").ReadAll().find("--allow-host NAME"),
            std::string::npos)
      << "a 421 says how to allow a name";
  // an Origin, where a request carries one: ours (any port: an ssh -L forward) or refused with 403
  const std::string host = "Host: 127.0.0.1:" + p + "\r\n";
  for (const std::string& origin :
       std::vector<std::string>{"http://127.0.0.1:" + p, "http://localhost:9000", "https://[::1]:" + p}) {
    EXPECT_EQ(get(host + "Origin: " + origin + "\r\n"), 200) << origin;
  }
  for (const std::string& origin : std::vector<std::string>{
           "http://evil.example", "https://evil.example:" + p, "null", "file://", "http://127.0.0.1.evil.example",
           "http://127.0.0.1:" + p + "/x", "ftp://127.0.0.1", "http://user@127.0.0.1"}) {
    EXPECT_EQ(get(host + "Origin: " + origin + "\r\n"), 403) << origin;
  }
  // the WebSocket upgrade, as a page elsewhere would try it: refused before any frame
  server->Publish("pose");
  EXPECT_EQ(Status(Raw(port).Send(Upgrade("/ws", "127.0.0.1:" + p, "Origin: http://evil.example\r\n")).ReadAll(1)),
            403);
  EXPECT_EQ(
      Status(
          Raw(port).Send(Upgrade("/ws", "evil.example:" + p, "Origin: http://evil.example:" + p + "\r\n")).ReadAll(1)),
      421);
  EXPECT_THROW(WsClient(port, "/ws", "http://attacker.example"), WsError);
  EXPECT_EQ(server->clients(), 0);
  // and accepted from the page's own origin, and from a client that sends none
  WsClient page(port, "/ws", "http://localhost:" + p);
  EXPECT_EQ(page.Read(), "pose");
  WsClient tool(port);
  EXPECT_EQ(tool.Read(), "pose");
  EXPECT_GE(server->counters().bad_host, 13 + 8 + 3);
}

// the rules themselves, for addresses a test on loopback cannot bind
TEST(ViewAccessTest, BoundAddressAndAnyAddress) {
  const AccessPolicy specific{"192.168.7.20", {}, {}}, any{"0.0.0.0", {"labhost"}, {}}, any6{"::", {}, {}};
  EXPECT_TRUE(HostAllowed(specific, "192.168.7.20:8080"));
  EXPECT_TRUE(HostAllowed(specific, "localhost:8080"));
  EXPECT_FALSE(HostAllowed(specific, "192.168.7.21:8080"));
  EXPECT_FALSE(HostAllowed(specific, "labhost:8080"));
  // bound to every address: any address literal (a rebinding page sends a name), names only when given
  EXPECT_TRUE(HostAllowed(any, "192.168.7.21:8080"));
  EXPECT_TRUE(HostAllowed(any, "LABHOST:8080"));
  EXPECT_FALSE(HostAllowed(any, "evil.example:8080"));
  EXPECT_TRUE(HostAllowed(any6, "[fe80::1]:8080"));
  EXPECT_TRUE(OriginAllowed(any, "http://labhost:8080"));
  EXPECT_FALSE(OriginAllowed(any, "http://evil.example:8080"));
  EXPECT_TRUE(IsLoopbackAddress("::ffff:127.0.0.1"));
  EXPECT_FALSE(IsLoopbackAddress("0.0.0.0"));
  EXPECT_FALSE(IsLoopbackAddress("::"));
  EXPECT_EQ(UrlHost("::1"), "[::1]");
  EXPECT_EQ(UrlHost("127.0.0.1"), "127.0.0.1");
}

}  // namespace
}  // namespace vlab::view
