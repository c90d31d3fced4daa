#include "bridge/bridge_session.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "bridge/bridge_errors.h"

namespace vlab::bridge {

namespace {

constexpr double kMaxCookie = 9007199254740992.0;  // 2^53
// describe rate limits are kept for this many sources (the least recently heard is reused)
constexpr std::size_t kMaxBuckets = 64;

std::uint64_t Rotl(std::uint64_t x, int b) { return (x << b) | (x >> (64 - b)); }

// SipHash-2-4 (Aumasson and Bernstein, 2012) of up to 24 bytes: a keyed hash
// whose output cannot be predicted without the key
std::uint64_t SipHash(const std::array<std::uint64_t, 2>& key, const unsigned char* data, std::size_t size) {
  std::uint64_t v0 = 0x736f6d6570736575ULL ^ key[0], v1 = 0x646f72616e646f6dULL ^ key[1];
  std::uint64_t v2 = 0x6c7967656e657261ULL ^ key[0], v3 = 0x7465646279746573ULL ^ key[1];
  auto round = [&] {
    v0 += v1, v1 = Rotl(v1, 13), v1 ^= v0, v0 = Rotl(v0, 32);
    v2 += v3, v3 = Rotl(v3, 16), v3 ^= v2;
    v0 += v3, v3 = Rotl(v3, 21), v3 ^= v0;
    v2 += v1, v1 = Rotl(v1, 17), v1 ^= v2, v2 = Rotl(v2, 32);
  };
  auto compress = [&](std::uint64_t m) {
    v3 ^= m;
    round();
    round();
    v0 ^= m;
  };
  std::size_t i = 0;
  for (; i + 8 <= size; i += 8) {
    std::uint64_t m = 0;
    for (int b = 0; b < 8; ++b) m |= static_cast<std::uint64_t>(data[i + b]) << (8 * b);
    compress(m);
  }
  std::uint64_t last = static_cast<std::uint64_t>(size & 0xff) << 56;
  for (std::size_t b = 0; i + b < size; ++b) last |= static_cast<std::uint64_t>(data[i + b]) << (8 * b);
  compress(last);
  v2 ^= 0xff;
  for (int r = 0; r < 4; ++r) round();
  return v0 ^ v1 ^ v2 ^ v3;
}

// a request's payload: [cookie, arg], the cookie a whole number below 2^53
bool RequestPayload(const std::vector<double>& p, double* cookie, double* arg) {
  if (p.size() != 2 || !(p[0] >= 0 && p[0] < kMaxCookie) || std::floor(p[0]) != p[0]) return false;
  *cookie = p[0];
  *arg = p[1];
  return true;
}

void EncodeRequest(int kind, MessageType type, double cookie, double arg, std::vector<unsigned char>* out) {
  const double payload[2] = {cookie, arg};
  Header h;
  h.kind = kind;
  h.type = static_cast<int>(type);
  EncodePacket(h, payload, 2, out);
}

}  // namespace

SessionTable::SessionTable(SessionConfig config) : config_(std::move(config)) {
  std::random_device entropy;  // the cookies' secret: unpredictable, not part of any simulation
  for (std::uint64_t& k : key_) k = (static_cast<std::uint64_t>(entropy()) << 32) ^ entropy();
  sessions_.reserve(static_cast<std::size_t>(std::max(config_.max_subscribers, 0)));
  buckets_.reserve(kMaxBuckets);
  reply_.reserve(kHeaderBytes + 2 * sizeof(double));
}

double SessionTable::Now() const {
  if (config_.clock) return config_.clock();
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

double SessionTable::Cookie(const Endpoint& from) const {
  unsigned char bytes[18] = {};
  std::size_t n = from.AddressBytes(bytes);
  bytes[n++] = static_cast<unsigned char>(from.port() & 0xff);
  bytes[n++] = static_cast<unsigned char>(from.port() >> 8);
  const std::uint64_t h = SipHash(key_, bytes, n) & ((1ULL << 53) - 1);
  return static_cast<double>(h == 0 ? 1 : h);
}

void SessionTable::Reply(double cookie, SessionResult result, const Endpoint& to, UdpSocket& socket) {
  const double payload[2] = {cookie, static_cast<double>(result)};
  Header h;
  h.kind = static_cast<int>(config_.kind);
  h.type = static_cast<int>(MessageType::kSession);
  EncodePacket(h, payload, 2, &reply_);
  socket.SendTo(reply_.data(), reply_.size(), to);
}

void SessionTable::Answer(const Endpoint& to, SessionResult result, UdpSocket& socket) {
  Reply(Cookie(to), result, to, socket);
}

bool SessionTable::MakeRoom(const Endpoint* keep) {
  Expire(keep);
  if (static_cast<int>(sessions_.size()) < config_.max_subscribers) return true;
  if (!config_.evict) return false;
  // the subscriber heard from least recently goes, never the one kept (the owner)
  auto oldest = sessions_.end();
  for (auto it = sessions_.begin(); it != sessions_.end(); ++it) {
    if (keep != nullptr && it->endpoint == *keep) continue;
    if (oldest == sessions_.end() || it->last_heard_s < oldest->last_heard_s) oldest = it;
  }
  if (oldest == sessions_.end()) return false;
  sessions_.erase(oldest);
  ++counters_.evicted;
  return true;
}

SessionTable::Outcome SessionTable::HandleRequest(const Header& header, const std::vector<double>& payload,
                                                  const Endpoint& from, UdpSocket& socket, const Endpoint* keep) {
  double cookie = 0, arg = 0;
  const bool subscribe = header.type == static_cast<int>(MessageType::kSubscribe);
  if (!RequestPayload(payload, &cookie, &arg)) return Outcome::kMalformed;
  if (subscribe ? (arg != 0 && arg != 1) : arg != 0) return Outcome::kMalformed;
  const double expected = Cookie(from);
  if (cookie != expected) {  // prove the address first: the reply is no larger than the request
    ++counters_.challenges;
    Reply(expected, SessionResult::kChallenge, from, socket);
    return Outcome::kChallenged;
  }
  const double now = Now();
  if (!subscribe) {
    if (TakeDescribeToken(from, now)) return Outcome::kDescribe;
    ++counters_.describes_limited;
    Reply(expected, SessionResult::kLimited, from, socket);
    return Outcome::kLimited;
  }
  if (arg == 0) {
    Remove(from);
    ++counters_.unsubscribed;
    Reply(expected, SessionResult::kUnsubscribed, from, socket);
    return Outcome::kUnsubscribed;
  }
  if (Touch(from)) {
    Reply(expected, SessionResult::kSubscribed, from, socket);
    return Outcome::kRenewed;
  }
  if (!MakeRoom(keep)) {
    ++counters_.refused_full;
    Reply(expected, SessionResult::kFull, from, socket);
    return Outcome::kFull;
  }
  sessions_.push_back({from, now, false});
  ++counters_.subscribed;
  Reply(expected, SessionResult::kSubscribed, from, socket);
  return Outcome::kSubscribed;
}

bool SessionTable::TakeDescribeToken(const Endpoint& from, double now) {
  auto it = std::find_if(buckets_.begin(), buckets_.end(), [&](const Bucket& b) { return b.endpoint == from; });
  if (it == buckets_.end()) {
    if (buckets_.size() < kMaxBuckets) {
      buckets_.push_back({from, static_cast<double>(config_.describe_burst), now});
      it = buckets_.end() - 1;
    } else {  // reuse the source heard least recently
      it = std::min_element(buckets_.begin(), buckets_.end(),
                            [](const Bucket& a, const Bucket& b) { return a.last_s < b.last_s; });
      *it = {from, static_cast<double>(config_.describe_burst), now};
    }
  }
  it->tokens =
      std::min(static_cast<double>(config_.describe_burst), it->tokens + (now - it->last_s) * config_.describe_rate_hz);
  it->last_s = now;
  if (it->tokens < 1) return false;
  it->tokens -= 1;
  return true;
}

bool SessionTable::IsSubscriber(const Endpoint& from) const {
  return std::any_of(sessions_.begin(), sessions_.end(), [&](const Session& s) { return s.endpoint == from; });
}

bool SessionTable::Touch(const Endpoint& from) {
  for (Session& s : sessions_) {
    if (s.endpoint == from) {
      s.last_heard_s = Now();
      return true;
    }
  }
  return false;
}

void SessionTable::Remove(const Endpoint& from) {
  sessions_.erase(
      std::remove_if(sessions_.begin(), sessions_.end(), [&](const Session& s) { return s.endpoint == from; }),
      sessions_.end());
}

void SessionTable::Expire(const Endpoint* keep) {
  const double now = Now();
  const auto silent = [&](const Session& s) {
    return (keep == nullptr || !(s.endpoint == *keep)) && now - s.last_heard_s > config_.subscriber_timeout_s;
  };
  const auto end = std::remove_if(sessions_.begin(), sessions_.end(), silent);
  counters_.expired += static_cast<long>(sessions_.end() - end);
  sessions_.erase(end, sessions_.end());
}

ClientSession::ClientSession(DeviceKind kind, std::string label) : kind_(kind), label_(std::move(label)) {
  request_.reserve(kHeaderBytes + 2 * sizeof(double));
}

void ClientSession::Connect(UdpSocket& socket, const Endpoint& device, double timeout_s,
                            std::vector<unsigned char>* buffer, const CheckDescribe& check, const Other& other,
                            long* skipped) {
  using Clock = std::chrono::steady_clock;
  constexpr double kRetry_s = 0.25;  // resend lost requests this often
  const auto after = [](Clock::time_point t, double s) {
    return t + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
  };
  const Clock::time_point deadline = after(Clock::now(), timeout_s);
  Clock::time_point resend = Clock::now();
  bool described = false, subscribed = false;
  Header header;
  std::vector<double> payload;
  for (;;) {
    Clock::time_point now = Clock::now();
    if (now >= resend) {  // first the cookie, then (with it) the reply and the subscription
      bool sent = true;
      if (!described) {
        EncodeDescribeRequest(static_cast<int>(kind_), cookie_, &request_);
        sent = socket.SendTo(request_.data(), request_.size(), device);
      }
      if (cookie_ != 0 && !subscribed) sent = KeepAlive(socket, device) && sent;
      if (!sent) throw NetworkError(label_ + ": cannot send to the device");
      resend = after(now, kRetry_s);
    }
    const double wait_s = std::chrono::duration<double>(std::min(deadline, resend) - now).count();
    Endpoint from;
    const long n = socket.Receive(buffer->data(), buffer->size(), &from, std::max(0.0, wait_s));
    if (n < 0) {
      if (Clock::now() < deadline) continue;
      char within[32];
      std::snprintf(within, sizeof within, "%g", timeout_s);
      throw TimeoutError(label_ + ": " +
                         (cookie_ == 0 ? "no answer"
                          : !described ? "no describe reply"
                                       : "no subscription") +
                         " within " + within + " s (is a device of this kind and protocol version " +
                         std::to_string(kProtocolVersion) + " serving that address and port?)");
    }
    // a multi-homed device may answer from another address, never from another port
    if (from.port() != device.port()) {
      if (skipped) ++*skipped;
      continue;
    }
    const unsigned char* data = buffer->data();
    if (n > 0 && data[0] == '{') {
      if (!described) check(data, n);
      described = true;
    } else if (IsSessionReply(data, static_cast<std::size_t>(n))) {
      DecodePacket(data, static_cast<std::size_t>(n), &header, &payload);
      double cookie = 0;
      SessionResult result = SessionResult::kChallenge;
      if (!ParseSessionReply(header, payload, &cookie, &result)) continue;
      if (result == SessionResult::kFull) {
        throw ProtocolError(label_ + ": the device refused the subscription: it has as many subscribers as it takes");
      }
      if (result == SessionResult::kChallenge && cookie != cookie_) {
        cookie_ = cookie;
        resend = Clock::now();  // at once, with the cookie
      }
      if (result == SessionResult::kSubscribed) subscribed = true;
    } else {
      if (n >= static_cast<long>(2 * sizeof(double)) && GetDouble(data) == kMagic &&
          GetDouble(data + sizeof(double)) != kProtocolVersion) {
        throw VersionMismatch(label_ + ": the device sent a datagram of protocol version " +
                              std::to_string(GetDouble(data + sizeof(double))) + ", this client speaks version " +
                              std::to_string(kProtocolVersion));
      }
      other(n);
    }
    if (described && subscribed) return;
  }
}

bool ClientSession::KeepAlive(UdpSocket& socket, const Endpoint& device) {
  EncodeSubscribeRequest(kind_, cookie_, 1, &request_);
  return socket.SendTo(request_.data(), request_.size(), device);
}

void ClientSession::Leave(UdpSocket& socket, const Endpoint& device) {
  if (cookie_ == 0) return;
  EncodeSubscribeRequest(kind_, cookie_, 0, &request_);
  socket.SendTo(request_.data(), request_.size(), device);
}

bool IsSessionReply(const unsigned char* data, std::size_t size) {
  return size == kHeaderBytes + 2 * sizeof(double) && GetDouble(data) == kMagic &&
         GetDouble(data + sizeof(double)) == kProtocolVersion &&
         GetDouble(data + 3 * sizeof(double)) == static_cast<double>(MessageType::kSession);
}

void EncodeSubscribeRequest(DeviceKind kind, double cookie, int action, std::vector<unsigned char>* out) {
  EncodeRequest(static_cast<int>(kind), MessageType::kSubscribe, cookie, action, out);
}

void EncodeDescribeRequest(int kind, double cookie, std::vector<unsigned char>* out) {
  EncodeRequest(kind, MessageType::kDescribe, cookie, 0, out);
}

bool ParseSessionReply(const Header& header, const std::vector<double>& payload, double* cookie,
                       SessionResult* result) {
  if (header.type != static_cast<int>(MessageType::kSession) || payload.size() != 2) return false;
  double c = 0, r = 0;
  if (!RequestPayload(payload, &c, &r) || c < 1 || std::floor(r) != r || r < 0 ||
      r > static_cast<double>(kMaxSessionResult)) {
    return false;
  }
  *cookie = c;
  *result = static_cast<SessionResult>(static_cast<int>(r));
  return true;
}

}  // namespace vlab::bridge
