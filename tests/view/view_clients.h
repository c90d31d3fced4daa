// Clients of the view's server for its tests (view_server_test.cc,
// view_server_limits_test.cc): a raw TCP client that sends bytes and reads
// what comes back, a Beast WebSocket client, and a server on a free port
// serving a small page.
#pragma once

#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>

#include "view/view_server.h"

namespace vlab::view::view_test {

namespace asio = boost::asio;
namespace beast = boost::beast;
using tcp = asio::ip::tcp;

constexpr const char* kPage = "<html>vlab view test page</html>";

/// A server on a free loopback port with `config`'s bounds (its port and
/// channels as given), serving kPage at / and "{}" at /scene.json.
inline std::unique_ptr<ViewServer> StartServer(ViewServerConfig config) {
  config.port = 0;
  std::map<std::string, StaticFile> files{{"/index.html", {"text/html", kPage}},
                                          {"/view.js", {"text/javascript", "//"}}};
  auto resources = [](const std::string& path, std::string* type, std::string* body) {
    if (path != "/scene.json") return false;
    *type = "application/json";
    *body = "{}";
    return true;
  };
  return ViewServer::Create(config, std::move(files), resources);
}

/// A raw TCP client of 127.0.0.1:port (from `source`, another loopback
/// address, when given): sends bytes, reads until the server closes or the
/// timeout passes.
class Raw {
 public:
  explicit Raw(int port, const std::string& source = "") : socket_(io_) {
    socket_.open(tcp::v4());
    if (!source.empty()) socket_.bind({asio::ip::make_address(source), 0});
    socket_.connect({asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(port)});
  }
  Raw& Send(const std::string& bytes) {
    boost::system::error_code ec;
    asio::write(socket_, asio::buffer(bytes), ec);  // the server may close before all is sent
    return *this;
  }
  std::string ReadAll(double timeout_s = 3) {
    std::string out;
    closed_ = false;
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    char buffer[4096];
    while (std::chrono::steady_clock::now() < end) {
      pollfd p{socket_.native_handle(), POLLIN, 0};
      if (::poll(&p, 1, 50) <= 0) continue;
      const ssize_t n = ::recv(socket_.native_handle(), buffer, sizeof(buffer), 0);
      if (n <= 0) {
        closed_ = true;
        break;
      }
      out.append(buffer, static_cast<std::size_t>(n));
    }
    return out;
  }
  /// True when the last ReadAll ended because the server closed.
  bool closed() const { return closed_; }

 private:
  asio::io_context io_;
  tcp::socket socket_;
  bool closed_ = false;
};

/// The status code of a raw response ("HTTP/1.1 404 Not Found" -> 404; 0: none).
inline int Status(const std::string& response) {
  if (response.compare(0, 5, "HTTP/") != 0) return 0;
  const std::size_t space = response.find(' ');
  return space == std::string::npos ? 0 : std::atoi(response.c_str() + space + 1);
}

/// GET target with Host 127.0.0.1 (and `extra` header lines), Connection: close.
inline std::string Get(int port, const std::string& target, const std::string& extra = "") {
  return Raw(port)
      .Send("GET " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\n" + extra + "Connection: close\r\n\r\n")
      .ReadAll();
}

/// A WebSocket upgrade request for `path` with the given Host and extra header lines.
inline std::string Upgrade(const std::string& path, const std::string& host, const std::string& extra = "") {
  return "GET " + path + " HTTP/1.1\r\nHost: " + host + "\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n" + extra +
         "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n";
}

/// A WebSocket client of /ws (or another channel), from `source` when given;
/// a read that waits longer than 20 s fails (SO_RCVTIMEO): a hang is a failure.
struct WsClient {
  explicit WsClient(int port, const std::string& path = "/ws", const std::string& origin = "",
                    const std::string& source = "")
      : ws(io) {
    ws.next_layer().open(tcp::v4());
    if (!source.empty()) ws.next_layer().bind({asio::ip::make_address(source), 0});
    ws.next_layer().connect({asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(port)});
    const timeval limit{20, 0};
    ::setsockopt(ws.next_layer().native_handle(), SOL_SOCKET, SO_RCVTIMEO, &limit, sizeof(limit));
    if (!origin.empty()) {
      ws.set_option(beast::websocket::stream_base::decorator(
          [origin](beast::websocket::request_type& r) { r.set(beast::http::field::origin, origin); }));
    }
    ws.handshake("127.0.0.1:" + std::to_string(port), path);
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

}  // namespace vlab::view::view_test
