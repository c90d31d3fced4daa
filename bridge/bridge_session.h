// Who a device streams to: subscriptions that a client asks for explicitly and
// proves it can receive at its address. Shared by every server of the wire (the
// lab's devices, the kinematic simulator, cameras, the vision server), so they
// all follow the same rules (docs/protocol.md, "Sessions").
//
// Ports
//   input   subscribe requests (type 4) and describe requests (type 3),
//           already framed by DecodePacket (HandleRequest); the server's own
//           sign of life from a subscriber (a command: Touch)
//   output  a session reply (type 5) to the requester: a challenge carrying
//           the cookie of its address, or the outcome of its request; never
//           larger than the request it answers
//   rate    driven by its owner, whenever a request arrives and when it
//           sends (Expire)
// Rules
//   - a request names its source's cookie: a whole number that depends on a
//     secret of this table, the source's address and its port. A request
//     without the right cookie is answered with a challenge only (the same
//     size as the request), so a spoofed source gets nothing more than its
//     own bytes back, and nothing is remembered about it (stateless);
//   - a subscribe request with the right cookie subscribes (or renews) its
//     source; action 0 unsubscribes it. A full table refuses a newcomer
//     (counted, reply "full"), unless the table evicts (SessionConfig::evict):
//     then the subscriber heard from least recently that is not `keep` (a
//     device's owner) makes room (counted), and only a table that holds
//     nothing but `keep` refuses;
//   - a subscriber silent (no request, no Touch) for subscriber_timeout_s of
//     the wall clock is dropped (Expire);
//   - a describe request with the right cookie is answered with the device's
//     JSON, at most describe_burst at once and describe_rate_hz on average per
//     source (beyond: a "limited" session reply, counted).
// Never throws and never blocks; no allocation once the tables are full.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "bridge/bridge_protocol.h"
#include "bridge/bridge_udp.h"

namespace vlab::bridge {

/// What a session reply's result value says (payload value 1).
enum class SessionResult : int {
  kChallenge = 0,       ///< repeat the request with this cookie
  kSubscribed = 1,      ///< subscribed (or renewed): states follow
  kFull = 2,            ///< refused: the device has as many subscribers as it takes
  kUnsubscribed = 3,    ///< no longer subscribed
  kLimited = 4,         ///< describe refused: too many requests from this source; retry later
  kRefused = 5,         ///< a command refused: another client controls the device (the sim's ops)
  kPayloadSet = 6,      ///< an arm's payload (type 6) accepted: in force from the next control period
  kPayloadRefused = 7,  ///< an arm's payload refused: not the owner, wrong length, NaN, not a rigid body
};
/// The highest result value a session reply carries.
inline constexpr int kMaxSessionResult = static_cast<int>(SessionResult::kPayloadRefused);

/// Counters of the sessions of one device (part of EndpointCounters).
struct SessionCounters {
  long challenges = 0;         ///< requests answered with a challenge (no or a wrong cookie)
  long subscribed = 0;         ///< subscriptions granted (renewals not counted)
  long unsubscribed = 0;       ///< subscriptions ended by the subscriber
  long expired = 0;            ///< subscribers dropped after falling silent
  long refused_full = 0;       ///< subscriptions refused: table full
  long evicted = 0;            ///< subscribers dropped to make room for a newcomer (SessionConfig::evict)
  long describes_limited = 0;  ///< describe requests refused by the rate limit
};

/// Subscribers a device keeps by default (`vlab serve --subscribers` changes it).
inline constexpr int kDefaultMaxSubscribers = 16;

struct SessionConfig {
  DeviceKind kind = DeviceKind::kArm;  ///< the kind in the session replies
  int max_subscribers = kDefaultMaxSubscribers;
  /// A full table makes room for a newcomer: the subscriber heard from least
  /// recently, other than the one HandleRequest is told to keep, is dropped.
  bool evict = false;
  double subscriber_timeout_s = 10;  ///< wall clock
  double describe_rate_hz = 10;      ///< describe replies per source, on average
  int describe_burst = 10;           ///< ... and at once
  /// Wall clock, s (null: the monotonic clock). Tests pass their own.
  std::function<double()> clock;
};

class SessionTable {
 public:
  struct Session {
    Endpoint endpoint;
    double last_heard_s = 0;  ///< wall clock of its last request or Touch
    bool mark = false;        ///< free for the server's own use (the camera: a chunk failed)
  };

  /// What HandleRequest did; the caller sends the JSON of kDescribe itself.
  enum class Outcome { kChallenged, kSubscribed, kRenewed, kUnsubscribed, kFull, kDescribe, kLimited, kMalformed };

  explicit SessionTable(SessionConfig config);

  /// The cookie of a source address and port: 1 ≤ cookie < 2^53.
  double Cookie(const Endpoint& from) const;

  /// Handles a subscribe or describe request (`header.type` 4 or 3, its
  /// payload [cookie, arg]) from `from`, and sends the session reply through
  /// `socket` (none for kDescribe: the caller answers with the JSON;
  /// kMalformed: a payload that breaks the layout, nothing sent). `keep` (a
  /// device's owner, may be null) is never evicted nor expired to make room.
  Outcome HandleRequest(const Header& header, const std::vector<double>& payload, const Endpoint& from,
                        UdpSocket& socket, const Endpoint* keep = nullptr);
  /// Sends `to` a session reply with its cookie and `result` (a refused
  /// command: kRefused; a payload: kPayloadSet, kPayloadRefused). Only to a
  /// subscriber (an address proven by the handshake): 9 values, which may be
  /// more than a malformed request it answers.
  void Answer(const Endpoint& to, SessionResult result, UdpSocket& socket);

  bool IsSubscriber(const Endpoint& from) const;
  /// A subscriber showed it is alive (a command): renews it. False if it is none.
  bool Touch(const Endpoint& from);
  /// Ends the subscription of `from` (if any).
  void Remove(const Endpoint& from);
  /// Drops the subscribers silent longer than the timeout, but not `keep`
  /// (a device's owner, which its commands keep alive).
  void Expire(const Endpoint* keep = nullptr);

  std::vector<Session>& sessions() { return sessions_; }
  const std::vector<Session>& sessions() const { return sessions_; }
  const SessionCounters& counters() const { return counters_; }
  const SessionConfig& config() const { return config_; }
  double Now() const;

 private:
  struct Bucket {  // describe rate limit of one source
    Endpoint endpoint;
    double tokens = 0;
    double last_s = 0;
  };
  bool TakeDescribeToken(const Endpoint& from, double now);
  void Reply(double cookie, SessionResult result, const Endpoint& to, UdpSocket& socket);
  bool MakeRoom(const Endpoint* keep);

  SessionConfig config_;
  SessionCounters counters_;
  std::array<std::uint64_t, 2> key_{};
  std::vector<Session> sessions_;
  std::vector<Bucket> buckets_;
  std::vector<unsigned char> reply_;
};

/// The client side of a session with one device: the handshake at connect,
/// renewals, and leaving.
class ClientSession {
 public:
  /// The datagrams of the device that are not part of the handshake (states,
  /// camera chunks) while Connect waits, by size in the buffer.
  using Other = std::function<void(long size)>;
  /// Checks the describe reply (JSON text) as soon as it arrives; throws.
  using CheckDescribe = std::function<void(const unsigned char* json, long size)>;

  ClientSession(DeviceKind kind, std::string label);

  /// Asks `device` for its cookie, then (with it) for its describe reply and
  /// a subscription, resending lost requests, until both came or timeout_s
  /// passed. Datagrams from other ports are skipped (counted in *skipped).
  /// Throws TimeoutError, ProtocolError (subscription refused: the device's
  /// table is full), VersionMismatch, NetworkError, and what check throws.
  void Connect(UdpSocket& socket, const Endpoint& device, double timeout_s, std::vector<unsigned char>* buffer,
               const CheckDescribe& check, const Other& other, long* skipped);
  /// Renews the subscription (a subscribe request with the cookie). False if
  /// the send failed.
  bool KeepAlive(UdpSocket& socket, const Endpoint& device);
  /// Ends the subscription (no reply awaited).
  void Leave(UdpSocket& socket, const Endpoint& device);

  double cookie() const { return cookie_; }

 private:
  DeviceKind kind_;
  std::string label_;
  double cookie_ = 0;
  std::vector<unsigned char> request_;
};

/// True when a datagram is a session reply (type 5): clients skip the
/// replies to their renewals.
bool IsSessionReply(const unsigned char* data, std::size_t size);

/// Encodes a subscribe request (type 4) to a device of `kind`: action 1
/// subscribes or renews, 0 unsubscribes; cookie 0 until the device gave one.
void EncodeSubscribeRequest(DeviceKind kind, double cookie, int action, std::vector<unsigned char>* out);
/// Encodes a describe request (type 3): kind 0 asks any device.
void EncodeDescribeRequest(int kind, double cookie, std::vector<unsigned char>* out);
/// Splits a session reply (type 5) into cookie and result; false if it is not one.
bool ParseSessionReply(const Header& header, const std::vector<double>& payload, double* cookie, SessionResult* result);

}  // namespace vlab::bridge
