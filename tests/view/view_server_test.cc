// Tests the server of vlab view (src/view/view_server.cc) on loopback with
// hostile clients: it serves only its own table (path traversal in every
// spelling gets 404/400, never a file of the disk), bounds header, body,
// connections and WebSocket messages, answers malformed requests with an
// HTTP error and malformed WebSocket frames by closing that session, and
// keeps serving afterwards; a WebSocket client gets the newest frame, not a
// queue of old ones. The panels' channels (/camera, /plot) are each their own
// newest-wins slot, and their clients count toward the same connection and
// message bounds.
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <gtest/gtest.h>

#include "view/view_server.h"

namespace vlab::view {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
using tcp = asio::ip::tcp;

constexpr const char* kPage = "<html>vlab view test page</html>";

std::unique_ptr<ViewServer> Start(int max_connections = 16, std::vector<std::string> channels = {"/ws"}) {
  ViewServerConfig config;
  config.port = 0;
  config.max_connections = max_connections;
  config.channels = std::move(channels);
  config.idle_timeout_s = 5;
  std::map<std::string, StaticFile> files{{"/index.html", {"text/html", kPage}}, {"/view.js", {"text/javascript", "//"}}};
  auto resources = [](const std::string& path, std::string* type, std::string* body) {
    if (path != "/scene.json") return false;
    *type = "application/json";
    *body = "{}";
    return true;
  };
  return ViewServer::Create(config, std::move(files), resources);
}

// a raw TCP client: sends bytes, reads until the server closes or 3 s pass
class Raw {
 public:
  explicit Raw(int port) : socket_(io_) { socket_.connect({asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(port)}); }
  Raw& Send(const std::string& bytes) {
    boost::system::error_code ec;
    asio::write(socket_, asio::buffer(bytes), ec);  // the server may close before all is sent
    return *this;
  }
  std::string ReadAll(double timeout_s = 3) {
    std::string out;
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    char buffer[4096];
    while (std::chrono::steady_clock::now() < end) {
      pollfd p{socket_.native_handle(), POLLIN, 0};
      if (::poll(&p, 1, 50) <= 0) continue;
      const ssize_t n = ::recv(socket_.native_handle(), buffer, sizeof(buffer), 0);
      if (n <= 0) break;
      out.append(buffer, static_cast<std::size_t>(n));
    }
    return out;
  }

 private:
  asio::io_context io_;
  tcp::socket socket_;
};

// the status code of a raw response ("HTTP/1.1 404 Not Found" -> 404; 0: none)
int Status(const std::string& response) {
  if (response.compare(0, 5, "HTTP/") != 0) return 0;
  const std::size_t space = response.find(' ');
  return space == std::string::npos ? 0 : std::atoi(response.c_str() + space + 1);
}

std::string Get(int port, const std::string& target) {
  return Raw(port).Send("GET " + target + " HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n").ReadAll();
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
  for (const char* target : {"/../../../../etc/passwd", "/%2e%2e/%2e%2e/%2e%2e/etc/passwd", "/index.html/../../../etc/passwd",
                             "/..%2f..%2f..%2fetc%2fpasswd", "//etc/passwd", "/etc/passwd", "http://x/../../etc/passwd",
                             "/..\\..\\..\\etc\\passwd", "/index.html%00", "*", "../../etc/passwd"}) {
    r = Get(port, target);
    const int status = Status(r);
    EXPECT_TRUE(status == 404 || status == 400) << target << ": " << r.substr(0, 40);
    EXPECT_EQ(r.find("root:"), std::string::npos) << target;
  }
  // read-only: no other method
  EXPECT_EQ(Status(Raw(port).Send("DELETE /index.html HTTP/1.1\r\nHost: x\r\n\r\n").ReadAll(1)), 405);
  EXPECT_EQ(Status(Raw(port).Send("POST / HTTP/1.1\r\nHost: x\r\nContent-Length: 2\r\n\r\nhi").ReadAll(1)), 405);
  // HEAD: the headers of a GET, no body
  r = Raw(port).Send("HEAD / HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n").ReadAll();
  EXPECT_EQ(Status(r), 200);
  EXPECT_EQ(r.find(kPage), std::string::npos);
}

TEST(ViewServerTest, OversizedAndMalformedRequestsGetAnHttpError) {
  auto server = Start();
  const int port = server->port();
  // headers beyond 8 KiB: 431; a body beyond 1 KiB: 413 (ViewServerConfig's bounds)
  const std::string big(20000, 'a');
  EXPECT_EQ(Status(Raw(port).Send("GET / HTTP/1.1\r\nHost: x\r\nX-Big: " + big + "\r\n\r\n").ReadAll()), 431);
  EXPECT_EQ(Status(Raw(port).Send("GET /" + big + " HTTP/1.1\r\nHost: x\r\n\r\n").ReadAll()), 431);
  EXPECT_EQ(Status(Raw(port).Send("POST / HTTP/1.1\r\nHost: x\r\nContent-Length: 100000\r\n\r\n" + big).ReadAll()), 413);
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
  { Raw half(port); half.Send("GET / HT"); }
  // a WebSocket upgrade elsewhere than /ws: 404
  EXPECT_EQ(Status(Raw(port)
                       .Send("GET /index.html HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                             "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n")
                       .ReadAll()),
            404);
  // still serving
  EXPECT_EQ(Status(Get(port, "/")), 200);
  EXPECT_GE(server->counters().errors, 9);
}

TEST(ViewServerTest, ConnectionsAreBounded) {
  auto server = Start(3);
  const int port = server->port();
  std::vector<std::unique_ptr<Raw>> idle;
  for (int i = 0; i < 3; ++i) idle.push_back(std::make_unique<Raw>(port));
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // let the server accept them
  EXPECT_EQ(Status(Get(port, "/")), 503);
  EXPECT_EQ(server->counters().refused, 1);
  idle.clear();  // they leave: room again
  std::string r;
  for (int attempt = 0; attempt < 50 && Status(r) != 200; ++attempt) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    r = Get(port, "/");
  }
  EXPECT_EQ(Status(r), 200);
}

// a WebSocket client of /ws (or another channel)
struct WsClient {
  explicit WsClient(int port, const std::string& path = "/ws") : ws(io) {
    ws.next_layer().connect({asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(port)});
    ws.handshake("127.0.0.1", path);
    ws.binary(true);
  }
  std::string Read() {
    beast::flat_buffer b;
    ws.read(b);
    return beast::buffers_to_string(b.data());
  }
  asio::io_context io;
  beast::websocket::stream<tcp::socket> ws;
};

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
  client.ws.write(asio::buffer(std::string("pause")));
  server->Publish("frame 52");
  EXPECT_EQ(client.Read(), "frame 52");
  // a message above the bound (1 KiB) closes that session only
  beast::flat_buffer b;
  beast::error_code ec;
  client.ws.write(asio::buffer(std::string(5000, 'x')), ec);  // the server may close while it is sent
  ec = {};
  server->Publish("frame 53");
  for (int i = 0; i < 3 && !ec; ++i) client.ws.read(b, ec);
  EXPECT_TRUE(ec) << "the session should have been closed";

  // malformed frames: an unmasked client frame, a reserved opcode, garbage
  for (const std::string& bad : {std::string("\x82\x03" "abc", 5), std::string("\x83\x80\x01\x02\x03\x04", 6),
                                 std::string(64, '\xff')}) {
    WsClient victim(port);
    beast::flat_buffer buffer;
    beast::error_code read_ec;
    victim.ws.next_layer().send(asio::buffer(bad), 0, read_ec);
    for (int i = 0; i < 20 && !read_ec; ++i) {
      server->Publish("more");
      victim.ws.read(buffer, read_ec);
      buffer.clear();
    }
    EXPECT_TRUE(read_ec) << "a malformed frame must end the session";
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_GE(server->counters().ws_closed_bad, 3);
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
  // three WebSocket clients fill the three connections: a fourth is refused
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_EQ(Status(Get(port, "/")), 503);
  EXPECT_THROW(WsClient(port, "/plot"), boost::system::system_error);
  // an oversized message on a panel's channel closes that session, as on /ws
  beast::flat_buffer b;
  beast::error_code ec;
  camera.ws.write(asio::buffer(std::string(5000, 'x')), ec);
  ec = {};
  server->Publish("picture 3", 1);
  for (int i = 0; i < 3 && !ec; ++i) camera.ws.read(b, ec);
  EXPECT_TRUE(ec) << "the camera session should have been closed";
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_GE(server->counters().ws_closed_bad, 1);
  // its slot is free again; a path that is no channel is 404
  std::string r = Raw(port).Send("GET /other HTTP/1.1\r\nHost: x\r\nConnection: Upgrade\r\nUpgrade: websocket\r\n"
                                 "Sec-WebSocket-Version: 13\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\r\n")
                      .ReadAll(1);
  EXPECT_EQ(Status(r), 404) << r;
}

}  // namespace
}  // namespace vlab::view
