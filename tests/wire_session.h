// The session handshake of a raw test peer (docs/protocol.md, "Sessions"):
// for tests that speak the wire byte by byte rather than through a client
// library.
#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "bridge/bridge_protocol.h"
#include "bridge/bridge_session.h"
#include "bridge/bridge_udp.h"

namespace vlab::testing {

/// Asks `device` for the cookie of `socket`'s address and subscribes it
/// (action 1) or ends its subscription (action 0). Returns the cookie, or 0
/// when the device did not answer within timeout_s, or refused (table full).
/// Other datagrams that arrive meanwhile (states, describe replies) are kept
/// in *other when given.
inline double WireSubscribe(bridge::UdpSocket& socket, const bridge::Endpoint& device, bridge::DeviceKind kind,
                            int action = 1, double timeout_s = 2.0,
                            std::vector<std::vector<unsigned char>>* other = nullptr) {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point end =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s));
  std::vector<unsigned char> request, buffer(65536);
  double cookie = 0;
  bridge::Header h;
  std::vector<double> payload;
  for (int attempt = 0; attempt < 2; ++attempt) {  // the challenge, then the request with the cookie
    bridge::EncodeSubscribeRequest(kind, cookie, action, &request);
    socket.SendTo(request.data(), request.size(), device);
    for (;;) {
      const double left = std::chrono::duration<double>(end - Clock::now()).count();
      if (left <= 0) return 0;
      bridge::Endpoint from;
      const long n = socket.Receive(buffer.data(), buffer.size(), &from, left);
      if (n < 0) return 0;
      if (!bridge::IsSessionReply(buffer.data(), static_cast<std::size_t>(n))) {
        if (other) other->emplace_back(buffer.begin(), buffer.begin() + n);
        continue;
      }
      bridge::DecodePacket(buffer.data(), static_cast<std::size_t>(n), &h, &payload);
      bridge::SessionResult result;
      if (!bridge::ParseSessionReply(h, payload, &cookie, &result)) return 0;
      if (result == bridge::SessionResult::kChallenge && attempt == 0) break;
      const bool ok =
          action == 1 ? result == bridge::SessionResult::kSubscribed : result == bridge::SessionResult::kUnsubscribed;
      return ok ? cookie : 0;
    }
  }
  return 0;
}

/// A session reply as a device sends it.
inline std::vector<unsigned char> SessionReplyPacket(bridge::DeviceKind kind, double cookie,
                                                     bridge::SessionResult result) {
  const double payload[2] = {cookie, static_cast<double>(result)};
  bridge::Header h;
  h.kind = static_cast<int>(kind);
  h.type = static_cast<int>(bridge::MessageType::kSession);
  std::vector<unsigned char> out;
  bridge::EncodePacket(h, payload, 2, &out);
  return out;
}

/// Plays a device's side of a client's handshake on `socket` (for tests that
/// fake a device): a challenge with `cookie` for the first request, then
/// "subscribed" for the subscribe request with it; the describe reply is the
/// caller's to send. Returns the number of requests that were as expected
/// (3: describe without cookie, then describe and subscribe with it, in
/// either order); *client is the client's address.
inline int PlayHandshake(bridge::UdpSocket& socket, bridge::Endpoint* client, bridge::DeviceKind kind, double cookie,
                         double timeout_s = 5.0) {
  std::vector<unsigned char> buffer(65536);
  bridge::Header h;
  std::vector<double> p;
  int good = 0;
  for (int i = 0; i < 3; ++i) {
    const long n = socket.Receive(buffer.data(), buffer.size(), client, timeout_s);
    if (n < 0 ||
        bridge::DecodePacket(buffer.data(), static_cast<std::size_t>(n), &h, &p) != bridge::DecodeError::kNone ||
        p.size() != 2) {
      return good;
    }
    const std::vector<unsigned char> reply = i == 0
                                                 ? SessionReplyPacket(kind, cookie, bridge::SessionResult::kChallenge)
                                                 : SessionReplyPacket(kind, cookie, bridge::SessionResult::kSubscribed);
    const bool describe = h.type == static_cast<int>(bridge::MessageType::kDescribe);
    const bool subscribe = h.type == static_cast<int>(bridge::MessageType::kSubscribe);
    if (i == 0 ? describe && p[0] == 0 : (describe || subscribe) && p[0] == cookie) ++good;
    if (i == 0 || subscribe) socket.SendTo(reply.data(), reply.size(), *client);
  }
  return good;
}

/// A device played by a test, datagram by datagram: it receives the client's
/// datagrams on a loopback port and answers to whoever sent the last one.
class FakeDevice {
 public:
  explicit FakeDevice(double patience_s = 5.0)
      : socket_(bridge::UdpSocket::Bind("127.0.0.1", 0)), patience_s_(patience_s) {}
  int port() const { return socket_->local_port(); }
  /// The client's next datagram (empty when none came within the patience).
  std::vector<unsigned char> Receive() {
    std::vector<unsigned char> buffer(65536);
    const long n = socket_->Receive(buffer.data(), buffer.size(), &client_, patience_s_);
    buffer.resize(n < 0 ? 0 : static_cast<std::size_t>(n));
    return buffer;
  }
  void Send(const std::vector<unsigned char>& bytes) { socket_->SendTo(bytes.data(), bytes.size(), client_); }
  void Send(const std::string& text) { Send(std::vector<unsigned char>(text.begin(), text.end())); }
  /// The device's side of the client's handshake (PlayHandshake, cookie 77).
  int Handshake(bridge::DeviceKind kind) { return PlayHandshake(*socket_, &client_, kind, 77, patience_s_); }
  const bridge::Endpoint& client() const { return client_; }

 private:
  std::unique_ptr<bridge::UdpSocket> socket_;
  double patience_s_;
  bridge::Endpoint client_;
};

}  // namespace vlab::testing
