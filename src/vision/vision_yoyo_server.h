// Device side of the vision program's yoyo device (kind 11, bridge/bridge_yoyo.h):
// one UDP socket and a bridge::DeviceEndpoint of kind yoyo, so that a
// controller reads the yo-yo from vision exactly as it reads the lab's yoyo
// device (same layout, same status bit, same rules).
//
// Ports
//   input   datagrams from clients (Poll): describe and subscribe requests
//   output  one state per camera frame to every subscriber (Publish):
//           [status, x, y, z, vz, string_force, spin], seq = frame id,
//           time = the frame's exposure time (s, the camera's clock);
//           describe replies (JSON) to the requester
//   rate    driven by its owner (the vision program): Poll between frames,
//           Publish once per frame
// Rules: bridge::DeviceEndpoint's. A client subscribes with the cookie
// handshake (docs/protocol.md, "Sessions"); a subscriber silent for
// subscriber_timeout_s is dropped; at most max_subscribers, and a newcomer to
// a full table is refused. The yoyo kind takes no commands: a command (of any
// kind) or a state datagram is refused and counted.
// Never throws and never blocks in Poll or Publish. Not thread-safe.
#pragma once

#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "bridge/bridge_device_server.h"
#include "vision/vision_device_socket.h"

namespace vlab::vision {

/// The yoyo device: name (default yoyo_vision), socket (default port 50054), subscribers, the camera's rate.
struct YoyoServerConfig : VisionDeviceConfig {
  YoyoServerConfig() : VisionDeviceConfig("yoyo_vision", 50054) {}
  double frame_hz = 0;  ///< the camera's frame rate: rates.control_hz of the describe reply
};

class YoyoServer {
 public:
  /// Binds the socket. Throws bridge::NetworkError naming the address when it cannot.
  static std::unique_ptr<YoyoServer> Create(const YoyoServerConfig& config);

  /// Handles every datagram already queued; never waits. `now_s`: a
  /// monotonic clock in seconds (subscriber timeouts). Returns how many.
  int Poll(double now_s);
  /// Sends one state (7 values, bridge::kYoyoStateLayout) to every subscriber.
  void Publish(double seq, double time, const double* state);

  const std::string& describe_json() const { return server_->describe_json(); }
  const bridge::EndpointCounters& counters() const { return server_->endpoint().counters(); }
  long states() const { return states_; }
  int local_port() const { return server_->port(); }
  int fd() { return server_->fd(); }

 private:
  YoyoServer() = default;

  std::unique_ptr<bridge::DeviceServer> server_;
  long states_ = 0;
};

/// The describe reply of the yoyo device (without the extra facts).
nlohmann::json YoyoDescribe(const YoyoServerConfig& config, int port);

}  // namespace vlab::vision
