// Device side of the markers device (kind 5, bridge/bridge_markers.h): one UDP
// socket, the subscribers, the marker table and the describe reply.
//
// Ports
//   input   datagrams from clients (Poll): describe requests, marker
//           descriptions (commands)
//   output  one state per processed camera frame to every subscriber
//           (Publish); describe replies (JSON) to the requester
//   rate    driven by its owner: Poll whenever convenient (the vision
//           program polls between frames), Publish once per frame
// Rules (those of bridge::DeviceEndpoint, with seconds for periods)
//   - sessions (bridge_session.h): states go to subscribers only, who asked
//     with a subscribe request after the cookie handshake; describe replies
//     only to a request with the cookie, rate-limited per source; a
//     subscriber silent for subscriber_timeout_s is dropped (a command
//     renews it); a full table refuses newcomers;
//   - a marker-description command from any subscriber (others: refused) is
//     applied whole (no owner;
//     the latest description of a marker wins); a malformed one (framing,
//     layout, unknown dictionary or id, side outside [0, 10] m) or one that
//     would overfill the table is refused and counted, and changes nothing;
//   - a state datagram, or a command of another kind, is refused and counted.
// Never throws and never blocks in Poll or Publish. Not thread-safe.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bridge/bridge_device_server.h"
#include "bridge/bridge_markers.h"
#include "vision/vision_device_socket.h"
#include "vision/vision_locate.h"

namespace vlab::vision {

/// The markers device: name (default vision), socket (default port 50014), subscribers, the table's size.
struct MarkersServerConfig : VisionDeviceConfig {
  MarkersServerConfig() : VisionDeviceConfig("vision", 50014) {}
  std::size_t max_markers = 256;  ///< capacity of the marker table (the describe reply must fit a datagram)
};

struct MarkersServerCounters {
  long received = 0;                 ///< datagrams received
  long describes = 0;                ///< describe requests answered
  long accepted = 0;                 ///< marker-description commands applied
  long refused = 0;                  ///< all refusals
  long refused_malformed = 0;        ///< framing, kind, type, layout, domain
  long refused_limits = 0;           ///< the table would exceed max_markers
  long refused_not_subscribed = 0;   ///< commands from a source that is no subscriber
  long states = 0;                   ///< states published (frames)
  bridge::SessionCounters sessions;  ///< handshakes, subscriptions, rate limits
};

class MarkersServer {
 public:
  /// Binds the socket. Throws NetworkError naming the address when it cannot.
  static std::unique_ptr<MarkersServer> Create(const MarkersServerConfig& config);

  /// Handles every datagram already queued; never waits. `now_s`: a
  /// monotonic clock in seconds (subscriber timeouts). Returns how many.
  int Poll(double now_s);
  /// Sends one state (seq = frame id, time = exposure time, s) to every subscriber.
  void Publish(double seq, double time, const bridge::MarkersStateMsg& state, double now_s);

  /// The marker table; Describe changes it as a command would (false: full).
  const MarkerTable& table() const { return table_; }
  bool Describe(const std::vector<bridge::MarkerDescriptionMsg>& descriptions);

  /// The describe reply now (JSON text).
  const std::string& describe_json() const { return server_->describe_json(); }
  int local_port() const { return server_->port(); }
  int fd() { return server_->fd(); }
  int subscribers() const { return static_cast<int>(server_->sessions().sessions().size()); }
  const MarkersServerCounters& counters() const { return counters_; }

 private:
  explicit MarkersServer(const MarkersServerConfig& config);
  static bridge::SessionConfig Sessions(const MarkersServerConfig& config, const double* now_s);
  void Handle(const unsigned char* data, std::size_t size, const bridge::Endpoint& from);
  void RebuildDescribe();

  MarkersServerConfig config_;
  std::unique_ptr<bridge::DeviceServer> server_;
  MarkerTable table_;
  MarkersServerCounters counters_;
  double now_s_ = 0;  // the caller's clock at the last Poll or Publish: the sessions' clock
  // scratch
  std::vector<unsigned char> packet_;
  std::vector<bridge::MarkerDescriptionMsg> descriptions_;
};

}  // namespace vlab::vision
