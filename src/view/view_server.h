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
// Bounded: connections (max_connections; more are answered 503), request
// header and body sizes (431, 413), WebSocket message size (the session is
// closed), idle HTTP connections (timeout). A bad request is answered with an
// HTTP error, never a crash.
// Threading: one thread of its own runs every session; Publish and counters
// may be called from any thread.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

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
  int port = 8080;                          ///< 0: any free port
  int max_connections = 16;                 ///< HTTP and WebSocket, together
  std::size_t max_header_bytes = 8192;      ///< a request's start line and headers
  std::size_t max_body_bytes = 1024;        ///< a request's body (the page sends none)
  std::size_t max_ws_message_bytes = 1024;  ///< a client's WebSocket message
  double idle_timeout_s = 30;               ///< an HTTP connection silent this long is closed
  double frame_poll_s = 0.005;              ///< how often a WebSocket session looks for a newer frame
  /// WebSocket paths, one channel each (index = Publish's channel); an
  /// upgrade on any other path is answered 404
  std::vector<std::string> channels = {"/ws"};
};

struct ViewServerCounters {
  long requests = 0;        ///< HTTP requests answered (any status)
  long errors = 0;          ///< answered with a 4xx or 5xx status
  long refused = 0;         ///< connections refused: too many
  long ws_sessions = 0;     ///< WebSocket sessions opened
  long frames_sent = 0;     ///< WebSocket messages sent (all channels)
  long frames_skipped = 0;  ///< frames a client did not get because a newer one came first
  long ws_closed_bad = 0;   ///< WebSocket sessions closed for a bad or oversized message
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
  /// client of that channel's path.
  void Publish(std::string frame, int channel = 0);
  int port() const;
  const std::string& address() const;
  ViewServerCounters counters() const;
  /// WebSocket clients connected now.
  int clients() const;

  struct Impl;

 private:
  explicit ViewServer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace vlab::view
