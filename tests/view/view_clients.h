// Clients of the view's server for its tests: a raw TCP client that sends
// bytes and reads what comes back, a WebSocket client of one channel, and a
// server on a free port serving a small page. The sockets live in
// view_clients.cc (library vlab_view_test_clients), so that a test unit does
// not parse Boost.
#pragma once

#include <chrono>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>

#include "view/view_server.h"

namespace vlab::view::view_test {

constexpr const char* kPage = "<html>vlab view test page</html>";

/// The WebSocket close code of a server that is full ("try again later").
constexpr int kCloseTryAgainLater = 1013;

/// A server on a free loopback port with `config`'s bounds (its port and
/// channels as given), serving kPage at / and "{}" at /scene.json.
std::unique_ptr<ViewServer> StartServer(ViewServerConfig config);

/// A raw TCP client of 127.0.0.1:port (from `source`, another loopback
/// address, when given): sends bytes, reads until the server closes or the
/// timeout passes. The constructor throws std::runtime_error (the socket's
/// error) when it cannot connect.
class Raw {
 public:
  explicit Raw(int port, const std::string& source = "");
  ~Raw();
  Raw(const Raw&) = delete;
  Raw& operator=(const Raw&) = delete;
  /// Sends `bytes`; an error is ignored (the server may close before all is sent).
  Raw& Send(const std::string& bytes);
  /// What arrives until the server closes or `timeout_s` seconds pass.
  std::string ReadAll(double timeout_s = 3);
  /// True when the last ReadAll ended because the server closed.
  bool closed() const { return closed_; }

 private:
  struct Impl;  // the socket (view_clients.cc)
  std::unique_ptr<Impl> impl_;
  bool closed_ = false;
};

/// The status code of a raw response ("HTTP/1.1 404 Not Found" -> 404; 0: none).
inline int Status(const std::string& response) {
  if (response.compare(0, 5, "HTTP/") != 0) return 0;
  const std::size_t space = response.find(' ');
  return space == std::string::npos ? 0 : std::atoi(response.c_str() + space + 1);
}

/// GET target with Host 127.0.0.1 (and `extra` header lines), Connection: close;
/// the raw response.
std::string Get(int port, const std::string& target, const std::string& extra = "");

/// A WebSocket upgrade request for `path` with the given Host and extra header lines.
inline std::string Upgrade(const std::string& path, const std::string& host, const std::string& extra = "") {
  return "GET " + path + " HTTP/1.1\r\nHost: " + host + "\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n" + extra +
         "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n";
}

/// A WebSocket error (refused handshake, closed session, socket error, a read
/// past the timeout); what() is the WebSocket library's message.
class WsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// How a WsClient connects to 127.0.0.1:port.
struct WsOptions {
  std::string path = "/ws";  ///< the channel
  std::string origin;        ///< the Origin header; empty: none
  std::string source;        ///< the local address to bind; empty: any
  std::string host;          ///< the Host header; empty: "127.0.0.1:PORT"
  std::string subprotocol;   ///< offered in Sec-WebSocket-Protocol; empty: none
  /// A read that waits longer fails (SO_RCVTIMEO): a hang is a failure. Zero: no limit.
  std::chrono::seconds read_timeout{20};
};

/// The options of a plain viewer of `path`: Host "127.0.0.1" without the
/// port, reads without a time limit (the test's own timeout ends a hang).
inline WsOptions ViewerOptions(const std::string& path) {
  WsOptions options;
  options.path = path;
  options.host = "127.0.0.1";
  options.read_timeout = std::chrono::seconds(0);
  return options;
}

/// The code and reason of the close frame a server sent (code 0: none came).
struct WsCloseReason {
  int code = 0;
  std::string reason;
};

/// A WebSocket client of one of the view's channels; it sends binary messages.
/// Not thread-safe: one thread reads, and no other uses it meanwhile.
class WsClient {
 public:
  /// Connects to /ws (or another channel), with an Origin and from `source`
  /// when given; reads wait at most 20 s. Throws WsError when the connection
  /// or the handshake fails (a refused upgrade included).
  explicit WsClient(int port, const std::string& path = "/ws", const std::string& origin = "",
                    const std::string& source = "");
  /// Connects as `options` say. Throws WsError as above.
  WsClient(int port, const WsOptions& options);
  ~WsClient();
  WsClient(const WsClient&) = delete;
  WsClient& operator=(const WsClient&) = delete;

  /// The next message. Throws WsError when the session ends (a close frame:
  /// see close_reason()), on a socket error or past the read timeout.
  std::string Read();
  /// The next message into `message` (when given); false instead of a throw.
  bool TryRead(std::string* message = nullptr);
  /// Sends a binary message. Throws WsError on an error.
  void Write(const std::string& message);
  /// Sends a text message. Throws WsError on an error.
  void WriteText(const std::string& message);
  /// Sends a binary message; false on an error (the server may close while it is sent).
  bool TryWrite(const std::string& message);
  /// Sends `bytes` on the socket itself, past the WebSocket framing (a
  /// malformed frame); false on an error.
  bool SendRaw(const std::string& bytes);
  /// The close frame the server sent, once a read failed on it.
  WsCloseReason close_reason() const;
  /// The socket's file descriptor (to watch it at the TCP level).
  int native_handle();

 private:
  struct Impl;  // the WebSocket stream (view_clients.cc)
  std::unique_ptr<Impl> impl_;
};

}  // namespace vlab::view::view_test
