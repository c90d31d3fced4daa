// The HTTP and WebSocket server of `vlab view` (Boost.Beast): serves the
// page's own files from memory, a few generated resources, and pushes pose
// frames to every WebSocket client, newest frame wins.
//
// Ports
//   input   HTTP/1.1 GET and HEAD requests on one TCP port (bind address:
//           loopback unless told otherwise); a WebSocket upgrade on one of
//           the channels' paths (/ws: poses; the view adds /camera, /plot)
//   output  the page's files (a fixed table: no request names a file on
//           disk), generated resources (Resources callback), and binary
//           WebSocket messages: on each channel, the newest message
//           Publish() was given for it
//   rate    a client gets a frame when one newer than its last is there and
//           its previous write has completed: a slow client skips frames, and
//           nothing ever waits on a client (Publish only swaps a pointer)
// Read-only: what a client sends over its WebSocket is read and dropped.
// Who: every request's Host and Origin are checked (view_access.h): a foreign
// Host is answered 421, a foreign Origin 403, WebSocket upgrades included.
// Bounded, so that no client can lock out another, even from the same address
// (a browser tab and a hostile local process are both 127.0.0.1):
//   - a request's head (start line and headers) must arrive whole within
//     header_timeout_s, and a keep-alive connection is closed after as long
//     without a request; HTTP connections at once: max_http, at most
//     max_per_address of them from one address; when either is reached a new
//     connection closes the connection that has waited longest for a request
//     head (a slow or idle one: never one that is being answered), and only
//     when every one is being answered is it answered 503;
//   - WebSocket sessions at once: max_connections, at most max_per_address
//     from one address; an upgrade beyond that is accepted and closed at once
//     with code 1013 (try again later) and a reason that says so, which the
//     page shows;
//   - a WebSocket's send queue is one message: while a message is being
//     written, newer ones replace the waiting one (a slow reader skips
//     frames); a write that has not completed after send_timeout_s closes the
//     session, and so does silence: a ping after ws_idle_timeout_s / 2
//     without a message from the client, no pong within as long again;
//   - request header and body sizes (431, 413), WebSocket message size (the
//     session is closed), an HTTP response's write (response_timeout_s).
// A bad request is answered with an HTTP error, never a crash.
// Threading: one thread of its own runs every session; Publish, counters,
// clients and http_connections may be called from any thread.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "view/view_foxglove.h"

namespace vlab::view {

/// One file of the page, held in memory.
struct StaticFile {
  std::string content_type;
  std::string body;
};

/// What a generated resource handler answers: found, its type and bytes.
using Resources = std::function<bool(const std::string& path, std::string* content_type, std::string* body)>;

struct ViewServerConfig {
  std::string bind = "127.0.0.1";
  int port = 8080;           ///< 0: any free port
  int max_connections = 64;  ///< WebSocket sessions at once (a tab takes 1-3)
  int max_http = 128;        ///< HTTP connections at once (see the file comment)
  int max_per_address = 32;  ///< WebSocket sessions, and HTTP connections, from one address
  /// names allowed in Host and Origin beside loopback and the bound address (view_access.h)
  std::vector<std::string> allowed_hosts;
  /// whole origins allowed in Origin beside those of the allowed hosts, e.g.
  /// "https://app.foxglove.dev" (view_access.h)
  std::vector<std::string> allowed_origins;
  std::size_t max_header_bytes = 8192;      ///< a request's start line and headers
  std::size_t max_body_bytes = 1024;        ///< a request's body (the page sends none)
  std::size_t max_ws_message_bytes = 1024;  ///< a client's WebSocket message
  double header_timeout_s = 5;              ///< a request head must arrive whole within this, s
  double response_timeout_s = 60;           ///< an HTTP response must be written within this, s
  double ws_idle_timeout_s = 10;            ///< a WebSocket client silent this long (no pong) is closed, s
  double send_timeout_s = 5;                ///< a WebSocket write not done within this closes the session, s
  double frame_poll_s = 0.005;              ///< how often a WebSocket session looks for a newer frame
  /// WebSocket paths, one channel each (index = Publish's channel); an
  /// upgrade on any other path is answered 404
  std::vector<std::string> channels = {"/ws"};
  /// true: a Foxglove WebSocket server (view_foxglove.h) instead: it serves
  /// no page; an upgrade on "/" that offers the subprotocol
  /// foxglove.websocket.v1 is a session that is advertised foxglove_channels
  /// (Publish's channel: an index into them) and sends the newest message of
  /// each channel it subscribed to, one message at a time
  bool foxglove = false;
  std::vector<FoxgloveChannel> foxglove_channels;
};

struct ViewServerCounters {
  long requests = 0;         ///< HTTP requests answered (any status)
  long errors = 0;           ///< answered with a 4xx or 5xx status
  long refused = 0;          ///< connections and WebSocket upgrades refused: too many
  long evicted = 0;          ///< HTTP connections closed for a newer one while waiting for a request head
  long header_timeouts = 0;  ///< HTTP connections closed: no whole request head in time
  long bad_host = 0;         ///< requests refused for their Host (421) or Origin (403)
  long ws_sessions = 0;      ///< WebSocket sessions opened
  long frames_sent = 0;      ///< WebSocket messages sent (all channels)
  long frames_skipped = 0;   ///< frames a client did not get because a newer one came first
  long ws_closed_bad = 0;    ///< WebSocket sessions closed for a bad or oversized message
  long ws_closed_slow = 0;   ///< WebSocket sessions closed: a write not done in send_timeout_s, or no pong
  long client_refused = 0;   ///< Foxglove: client messages refused as writes (publish, parameters, services)
  long client_bad = 0;       ///< Foxglove: client messages refused as malformed (bad JSON, unknown op or id)
};

class ViewServer {
 public:
  /// Binds and starts serving on its own thread. `files`: path ("/index.html")
  /// -> file; "/" serves "/index.html". Throws InputError naming the address
  /// and port when it cannot bind.
  static std::unique_ptr<ViewServer> Create(const ViewServerConfig& config, std::map<std::string, StaticFile> files,
                                            Resources resources);
  ~ViewServer();
  ViewServer(const ViewServer&) = delete;
  ViewServer& operator=(const ViewServer&) = delete;

  /// Makes `frame` the newest message of channel `channel` (an index into
  /// config.channels; 0: the poses): a binary WebSocket message to every
  /// client of that channel's path. A Foxglove server: `frame` is a
  /// FoxgloveRecord, `channel` an index into config.foxglove_channels.
  void Publish(std::string frame, int channel = 0);
  int port() const;
  const std::string& address() const;
  ViewServerCounters counters() const;
  /// WebSocket clients connected now.
  int clients() const;
  /// HTTP connections open now (waiting for a request or being answered).
  int http_connections() const;

  struct Impl;

 private:
  explicit ViewServer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace vlab::view
