// The Foxglove WebSocket protocol v1 (subprotocol "foxglove.websocket.v1"),
// as `vlab view --foxglove` speaks it: the server's JSON messages, the binary
// message data frame, and what a client's message asks for. The session that
// uses them is in view_server_foxglove.cc.
//
// Server -> client
//   text    {"op":"serverInfo"} once, then {"op":"advertise"} with every
//           channel (id, topic, encoding "cdr", schemaName, schemaEncoding
//           "ros2msg", schema text); {"op":"status"} to answer a refused or
//           malformed client message
//   binary  message data: uint8 0x01, uint32 subscription id, uint64 log time
//           (ns: the message's simulated stamp), the CDR payload;
//           little-endian
// Client -> server
//   text    "subscribe" {subscriptions: [{id, channelId}]}, "unsubscribe"
//           {subscriptionIds: [...]}: served. Everything a read-only server
//           does not offer (client "advertise"/"unadvertise", parameters,
//           services, connection graph, assets) is refused with a status
//   binary  client message data (0x01) and service calls (0x02): refused
// Read-only: serverInfo's capabilities are empty, so a conforming client
// never publishes; one that does is answered with an error status, counted,
// and changes nothing.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace vlab::view {

inline constexpr char kFoxgloveSubprotocol[] = "foxglove.websocket.v1";

/// One advertised channel; its id is its index in the server's list.
struct FoxgloveChannel {
  std::string topic;        ///< "/tf", "/pa10", "/camera/webcam"
  std::string schema_name;  ///< ROS 2 type name: "tf2_msgs/msg/TFMessage"
  std::string schema;       ///< ros2msg text (scene_messages.h)
};

/// The serverInfo message: name "vlab view", no capabilities (read-only).
std::string FoxgloveServerInfo();

/// The advertise message of `channels` (ids 0 .. n-1).
std::string FoxgloveAdvertise(const std::vector<FoxgloveChannel>& channels);

/// A status message: level 0 info, 1 warning, 2 error.
std::string FoxgloveStatus(int level, const std::string& message);

/// What the server keeps as a channel's newest message: the uint64 log time
/// (ns, little-endian) then the payload; a session puts the opcode and its
/// subscription id before it.
std::string FoxgloveRecord(std::uint64_t log_time_ns, const std::string& payload);

/// The 5 bytes a session puts before a record: opcode 0x01, uint32 id.
void FoxgloveDataHeader(std::uint32_t subscription_id, char out[5]);

/// One client's subscriptions: subscription id -> channel, at most one per
/// channel (the spec's rule).
class FoxgloveSubscriptions {
 public:
  explicit FoxgloveSubscriptions(int channels) : by_channel_(channels, kNone) {}
  /// Applies one client message (text or binary). Returns "" when it was
  /// served, else the reason of the refusal for a status message;
  /// *read_only is set when it asked for something a read-only server does
  /// not do (publishing, parameters, services, ...), *malformed when it was
  /// not a message of the protocol. A refused message changes nothing; in a
  /// subscribe or unsubscribe, the valid entries are applied and the invalid
  /// ones named.
  std::string Apply(const std::string& message, bool binary, bool* read_only, bool* malformed);
  /// The subscription id of `channel`, or -1 when the client has none.
  std::int64_t IdOf(int channel) const { return by_channel_[channel]; }
  int channels() const { return static_cast<int>(by_channel_.size()); }

 private:
  static constexpr std::int64_t kNone = -1;
  std::vector<std::int64_t> by_channel_;
  std::map<std::uint32_t, int> by_id_;
};

}  // namespace vlab::view
