// Inside the view's server (view_server.h): its state, shared by the
// listener (view_server.cc), the HTTP sessions (view_server_http.cc) and the
// WebSocket sessions (view_server_ws.cc). Everything but the frame slots and
// the atomic counters is touched on the server's own thread only.
#pragma once

#include <atomic>
#include <chrono>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include "view/view_access.h"
#include "view/view_server.h"

namespace vlab::view {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;

struct ViewServer::Impl {
  ViewServerConfig config;
  std::map<std::string, StaticFile> files;
  Resources resources;
  // both destroyed first, by ~ViewServer: pending handlers own sessions that use the rest
  std::unique_ptr<asio::io_context> io = std::make_unique<asio::io_context>(1);
  std::unique_ptr<tcp::acceptor> acceptor = std::make_unique<tcp::acceptor>(*io);
  std::thread thread;
  std::string address;
  int port = 0;

  // per channel, the newest message, swapped under the lock; version counts messages published
  struct Slot {
    std::shared_ptr<const std::string> frame;
    std::uint64_t version = 0;
  };
  mutable std::mutex frame_mutex;
  std::vector<Slot> slots;

  // the tables, touched on the server's thread only: HTTP connections (all,
  // and those waiting for a request head, longest waiting first), WebSocket
  // sessions, and both per remote address
  struct Waiting {
    virtual ~Waiting() = default;
    virtual void Evict() = 0;  // closes the connection and takes it out of the tables
    std::string address;
  };
  struct Peer {
    int http = 0, ws = 0;
  };
  AccessPolicy access;
  std::map<std::string, Peer> peers;
  std::list<Waiting*> waiting;
  int http_open = 0, ws_open = 0, refusing = 0;
  std::unique_ptr<asio::steady_timer> accept_retry;
  void Release(const std::string& address, bool ws) {
    auto at = peers.find(address);
    if (at == peers.end()) return;
    --(ws ? at->second.ws : at->second.http);
    if (at->second.http <= 0 && at->second.ws <= 0) peers.erase(at);  // flat: no entry per address ever seen
  }

  std::atomic<int> ws_clients{0}, http_clients{0};
  std::atomic<long> requests{0}, errors{0}, refused{0}, evicted{0}, header_timeouts{0}, bad_host{0}, ws_sessions{0},
      frames_sent{0}, frames_skipped{0}, ws_closed_bad{0}, ws_closed_slow{0}, client_refused{0}, client_bad{0};
  // Foxglove: the serverInfo and advertise messages every session starts with
  std::string foxglove_info, foxglove_advertise;

  std::shared_ptr<const std::string> Newest(int channel, std::uint64_t* v) const {
    std::lock_guard<std::mutex> lock(frame_mutex);
    *v = slots[channel].version;
    return slots[channel].frame;
  }
  void Accept();
};

/// Seconds as the steady clock's duration (the config's timeouts).
inline std::chrono::steady_clock::duration Seconds(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(s));
}

/// A WebSocket session's place in the server's tables (the page's channels,
/// view_server_ws.cc; Foxglove's, view_server_foxglove.cc): admitted (no
/// refusal) it counts as open, for its address too; refused, as refusing;
/// once its handshake completed (Welcome), as a client. Its destructor takes
/// back what it counted. The server's thread only.
class WsSeat {
 public:
  WsSeat(ViewServer::Impl& server, std::string address, std::string refusal)
      : server_(server), address_(std::move(address)), refusal_(std::move(refusal)) {
    if (refusal_.empty()) {
      ++server_.ws_open;
      ++server_.peers[address_].ws;
    } else {
      ++server_.refusing;
    }
  }
  ~WsSeat() {
    if (refusal_.empty()) {
      --server_.ws_open;
      server_.Release(address_, true);
    } else {
      --server_.refusing;
    }
    if (welcomed_) --server_.ws_clients;
  }
  WsSeat(const WsSeat&) = delete;
  WsSeat& operator=(const WsSeat&) = delete;
  /// The handshake completed: a session and a client.
  void Welcome() {
    ++server_.ws_sessions;
    ++server_.ws_clients;
    welcomed_ = true;
  }
  /// Why the session is refused ("": admitted).
  const std::string& refusal() const { return refusal_; }

 private:
  ViewServer::Impl& server_;
  std::string address_, refusal_;
  bool welcomed_ = false;
};

/// The bounds every WebSocket session of the server keeps: its message size,
/// the handshake's and a close's deadline, and silence (a ping at half of
/// ws_idle_timeout_s; no pong within as long again: closed).
inline void ApplyWsBounds(websocket::stream<beast::tcp_stream>& ws, const ViewServerConfig& config) {
  ws.read_message_max(config.max_ws_message_bytes);
  websocket::stream_base::timeout timeout;
  timeout.handshake_timeout = Seconds(config.header_timeout_s);
  timeout.idle_timeout = Seconds(config.ws_idle_timeout_s);
  timeout.keep_alive_pings = true;
  ws.set_option(timeout);
}

/// Counts how a WebSocket session ended with `ec`, the first error of its read
/// or of a write: a protocol violation or an oversized message (not a close, a
/// reset or a timeout) as bad, a timeout (no pong) of a session not already
/// `done` as slow. Beast hands the timeout to whichever of the session's
/// operations completes first: a frame written as the silence ends takes it,
/// and the read then ends as aborted.
inline void CountWsEnd(ViewServer::Impl& server, const beast::error_code& ec, bool done) {
  const bool websocket_error = ec.category() == websocket::make_error_code(websocket::error::closed).category();
  if (websocket_error && ec != websocket::error::closed) ++server.ws_closed_bad;
  if (ec == beast::error::timeout && !done) ++server.ws_closed_slow;
}

/// Serves one accepted connection from `address`: `admitted`, it enters the
/// HTTP table and is answered request after request; otherwise it gets 503.
void StartHttpSession(ViewServer::Impl& server, tcp::socket socket, std::string address, bool admitted);

/// Takes over an upgraded connection as a WebSocket session of `channel`
/// (counted in the WebSocket table); with a `refusal`, accepts it only to
/// close it at once with code 1013 and that reason.
void StartWebSocket(ViewServer::Impl& server, tcp::socket socket, int channel, std::string address, std::string refusal,
                    http::request<http::string_body> request);

/// The same for a Foxglove server's session (view_server_foxglove.cc).
void StartFoxgloveSession(ViewServer::Impl& server, tcp::socket socket, std::string address, std::string refusal,
                          http::request<http::string_body> request);

}  // namespace vlab::view
