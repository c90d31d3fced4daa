// One device on the wire, as the servers beside the lab serve it (vlab-kinsim,
// vlab-yoyosim, the vision program's markers and yoyo devices, a camera): a UDP
// socket bound on an address and port, the device's rules, the latest state it
// published, and a bounded drain of its socket. What differs between servers
// (their simulation, their pacing, their counters) stays with them.
//
// Ports
//   input   datagrams on bind_address:port (Receive, Drain): commands, describe
//           and subscribe requests
//   output  states to every subscriber (Publish); describe replies (JSON) and
//           session replies to the requester; with send_latest, the latest
//           state to a new subscriber at once
//   rate    driven by its owner: Receive or Drain whenever convenient (every
//           period), Publish once per period or frame
// Rules: two ways to serve a device.
//   - Serve(EndpointConfig): bridge::DeviceEndpoint's (bridge_endpoint.h):
//     sessions, one owner, seq window, limits, watchdog, kStatusNotOwner for
//     the others (in the latest state a new subscriber gets too);
//   - ServeSessions(SessionConfig, describe): a bare bridge::SessionTable for a
//     kind whose commands follow other rules (markers: any subscriber, no
//     owner) or that streams in its own way (camera chunks). Request() frames
//     a datagram, answers describe and subscribe requests and leaves a command
//     to the caller.
// A datagram longer than any valid one is handed on as too long (its size the
// buffer's), and refused as malformed.
// Never throws nor blocks (but for the wait asked for) once bound. Not thread-safe.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "bridge/bridge_endpoint.h"
#include "bridge/bridge_protocol.h"
#include "bridge/bridge_session.h"
#include "bridge/bridge_udp.h"

namespace vlab::bridge {

/// The most datagrams one Receive handles by default, so that a flood cannot stall a loop.
inline constexpr int kMaxDatagramsPerReceive = 1000;

struct DeviceServerConfig {
  std::string bind_address = "127.0.0.1";
  int port = 0;  ///< 0: any free port (see DeviceServer::port)
  /// Datagrams handled per Receive or Drain call (0: until the socket is empty).
  int max_datagrams = kMaxDatagramsPerReceive;
  /// A new subscriber gets the latest published state at once (lockstep waits on it).
  bool send_latest = false;
};

class DeviceServer {
 public:
  /// Binds the socket. Throws NetworkError naming the address when it cannot.
  /// The device is served once Serve or ServeSessions ran (its describe reply
  /// may name the bound port).
  static std::unique_ptr<DeviceServer> Bind(const DeviceServerConfig& config);

  /// Serves the device with DeviceEndpoint's rules. Call once.
  void Serve(EndpointConfig endpoint);
  /// Serves the device with a bare session table and this describe reply. Call once.
  void ServeSessions(const SessionConfig& sessions, std::string describe_json);

  /// A datagram as Drain hands it on: its bytes (size: the buffer's when it was too long).
  using Handler = std::function<void(const unsigned char* data, std::size_t size, const Endpoint& from)>;
  /// Hands each queued datagram to `handle` (at most max_datagrams), waiting up
  /// to wait_s for the first (0: only what is queued). Returns how many.
  int Drain(double wait_s, const Handler& handle);
  /// Serve's: drains with the endpoint's rules at `period` (DeviceEndpoint::Handle).
  /// on_command (may be null) runs after each accepted command. Returns how many.
  int Receive(long period, const std::function<void()>& on_command = nullptr, double wait_s = 0);

  /// What Request made of a datagram to a device served by ServeSessions.
  enum class Request { kMalformed, kDescribed, kSession, kCommand };
  /// ServeSessions': refuses a malformed datagram, a state or session reply
  /// (kMalformed), answers a describe (kDescribed) or subscribe request
  /// (kSession) and leaves a command of the device's kind to the caller
  /// (kCommand: header() and payload() hold it). Counts nothing.
  Request HandleRequest(const unsigned char* data, std::size_t size, const Endpoint& from);
  const Header& header() const { return header_; }
  const std::vector<double>& payload() const { return payload_; }

  /// Serve's: sends a state to every subscriber (DeviceEndpoint::Publish) and keeps it as the latest.
  void Publish(const std::vector<unsigned char>& state);
  /// Serve's: encodes a state of the endpoint's kind (seq, time s, n values) and publishes it.
  void Publish(double seq, double time, const double* values, int n);
  /// ServeSessions': drops the silent subscribers, then sends a state to every other one.
  void PublishToSubscribers(const std::vector<unsigned char>& state);

  /// The describe reply of a device served by ServeSessions, changed (the marker table).
  void set_describe_json(std::string json) { describe_json_ = std::move(json); }
  const std::string& describe_json() const;

  int port() const { return socket_->local_port(); }
  /// The socket's descriptor, to wait on it together with others (WaitReadable).
  int fd() { return socket_->fd(); }
  UdpSocket& socket() { return *socket_; }
  const Endpoint& local_endpoint() const { return socket_->local_endpoint(); }
  DeviceEndpoint& endpoint() { return *endpoint_; }
  const DeviceEndpoint& endpoint() const { return *endpoint_; }
  SessionTable& sessions() { return *sessions_; }
  const SessionTable& sessions() const { return *sessions_; }
  /// The latest state published (empty before the first).
  const std::vector<unsigned char>& latest() const { return latest_; }

 private:
  DeviceServer() = default;

  DeviceServerConfig config_;
  std::unique_ptr<UdpSocket> socket_;
  std::unique_ptr<DeviceEndpoint> endpoint_;  // Serve
  std::unique_ptr<SessionTable> sessions_;    // ServeSessions
  std::string describe_json_;                 // ServeSessions
  // scratch, sized at binding
  std::vector<unsigned char> buffer_, latest_;
  Header header_;
  std::vector<double> payload_;
};

}  // namespace vlab::bridge
