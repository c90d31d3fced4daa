#include "bridge/bridge_endpoint.h"

#include <algorithm>
#include <cmath>

namespace vlab::bridge {

namespace {

SessionConfig Sessions(const EndpointConfig& c) {
  SessionConfig s;
  s.kind = c.kind;
  s.max_subscribers = c.max_subscribers;
  s.subscriber_timeout_s = c.subscriber_timeout_s;
  s.evict = true;  // a controller is never locked out by sockets that only subscribe
  s.clock = c.clock;
  return s;
}

}  // namespace

DeviceEndpoint::DeviceEndpoint(EndpointConfig config) : config_(std::move(config)), sessions_(Sessions(config_)) {
  payload_.reserve(kMaxPacketValues);
  arm_command_.value.reserve(kMaxPacketValues);
  parsed_.value.reserve(kMaxPacketValues);
  command_.reserve(kMaxPacketValues);
  if (config_.kind == DeviceKind::kArm) config_.status_first = true;
  not_owner_packet_.reserve(kMaxPacketValues * sizeof(double));
  arm_payload_ = config_.payload;
  describe_json_ = config_.kind == DeviceKind::kArm ? DescribeWithPayload(config_.describe_json, arm_payload_)
                                                    : config_.describe_json;
}

const EndpointCounters& DeviceEndpoint::counters() const {
  counters_.sessions = sessions_.counters();
  return counters_;
}

void DeviceEndpoint::ReleaseOwner() {
  if (owner_) ++counters_.owners_released;
  owner_.reset();
  last_seq_ = -1;
  last_payload_seq_ = 0;  // the next owner counts its payloads from its own 1
}

bool DeviceEndpoint::ReleaseSilentOwner() {
  if (!owner_ || sessions_.Now() - owner_heard_s_ <= config_.owner_timeout_s) return false;
  ReleaseOwner();
  return true;
}

bool DeviceEndpoint::CheckArmLimits(const ArmCommandMsg& c) const {
  auto within = [](const std::vector<double>& lo, const std::vector<double>& hi, const std::vector<double>& v) {
    for (std::size_t i = 0; i < v.size(); ++i) {
      if (!lo.empty() && v[i] < lo[i]) return false;
      if (!hi.empty() && v[i] > hi[i]) return false;
    }
    return true;
  };
  auto within_abs = [](const std::vector<double>& limit, const std::vector<double>& v) {
    for (std::size_t i = 0; i < v.size() && !limit.empty(); ++i) {
      if (std::abs(v[i]) > limit[i]) return false;
    }
    return true;
  };
  switch (c.mode) {
    case 1:
      return within(config_.position_min, config_.position_max, c.value);
    case 2:
      return within_abs(config_.velocity_max, c.value);
    case 3:
      return within_abs(config_.torque_max, c.value);
    default:
      return true;  // hold: values unused
  }
}

DeviceEndpoint::Received DeviceEndpoint::Handle(const unsigned char* data, std::size_t size, const Endpoint& from,
                                                long period, UdpSocket& socket) {
  ++counters_.received;
  ReleaseSilentOwner();  // first: an owner back after its timeout is an owner no more
  const bool from_owner = owner_ && *owner_ == from;
  auto refuse = [&](long* reason) {
    ++*reason;
    ++counters_.refused;
    if (from_owner) refused_flag_ = true;
    return Received::kOther;
  };
  header_.type = 0;  // (DecodePacket fills it when the header is sound)
  DecodeError e = DecodePacket(data, size, &header_, &payload_);
  // a payload with a value that is not finite goes on, to be answered (refused, below)
  const bool payload = header_.type == static_cast<int>(MessageType::kPayload) &&
                       (e == DecodeError::kNone || e == DecodeError::kNotFinite);
  const bool payload_finite = e == DecodeError::kNone;
  if (payload) e = DecodeError::kNone;
  // a describe request is answered whatever kind it names (0: any): tools discover with it
  const bool describe = e == DecodeError::kNone && header_.type == static_cast<int>(MessageType::kDescribe);
  if (e == DecodeError::kNone &&
      (describe ? header_.kind > kMaxDeviceKind : header_.kind != static_cast<int>(config_.kind))) {
    e = DecodeError::kBadKind;
  }
  // states and session replies go the other way; only an arm takes a payload
  if (e == DecodeError::kNone &&
      (header_.type == static_cast<int>(MessageType::kState) ||
       header_.type == static_cast<int>(MessageType::kSession) || (payload && config_.kind != DeviceKind::kArm))) {
    e = DecodeError::kBadType;
  }
  if (e != DecodeError::kNone) return refuse(&counters_.refused_malformed);

  if (describe || header_.type == static_cast<int>(MessageType::kSubscribe)) {
    const SessionTable::Outcome outcome =
        sessions_.HandleRequest(header_, payload_, from, socket, owner_ ? &*owner_ : nullptr);
    if (outcome != SessionTable::Outcome::kMalformed) ++counters_.requests;
    switch (outcome) {
      case SessionTable::Outcome::kMalformed:
        return refuse(&counters_.refused_malformed);
      case SessionTable::Outcome::kDescribe:
        ++counters_.describes;
        socket.SendTo(reinterpret_cast<const unsigned char*>(describe_json_.data()), describe_json_.size(), from);
        return Received::kOther;
      case SessionTable::Outcome::kSubscribed:
        return Received::kSubscribed;
      case SessionTable::Outcome::kUnsubscribed:
        if (from_owner) ReleaseOwner();  // an owner that leaves gives its input up
        return Received::kOther;
      case SessionTable::Outcome::kRenewed:
        if (from_owner) owner_heard_s_ = sessions_.Now();
        return Received::kOther;
      default:
        return Received::kOther;
    }
  }
  const bool commanded =
      config_.kind == DeviceKind::kArm || config_.kind == DeviceKind::kSim || config_.command_length > 0;
  if (!commanded) return refuse(&counters_.refused_malformed);  // output-only device
  // commands come from subscribers only: a proven address, which states reach
  if (!sessions_.Touch(from)) return refuse(&counters_.refused_not_subscribed);

  // the gate first (the sim in a driven run): it may refuse anyone, or let a driver take over
  const CommandGate gate = config_.gate ? config_.gate(from) : CommandGate::kOpen;
  const bool sim = config_.kind == DeviceKind::kSim;
  if (gate == CommandGate::kRefuse || (owner_ && !from_owner && gate != CommandGate::kTakeOver)) {
    if (sim) sessions_.Answer(from, SessionResult::kRefused, socket);  // an op: say so
    if (payload) sessions_.Answer(from, SessionResult::kPayloadRefused, socket);
    return refuse(&counters_.refused_not_owner);
  }
  // one owner at a time; an owner silent for too long gave the input up (above).
  // A new owner takes over with its first ACCEPTED command (or payload) only.
  if (from_owner) owner_heard_s_ = sessions_.Now();  // any datagram shows the owner is alive
  if (payload) return HandlePayload(from, payload_finite, socket);
  // the seq answers a state this device published, newer than the last accepted
  if (header_.seq > newest_seq_) {
    ++counters_.future;
    return Received::kOther;
  }
  const double last_seq = from_owner ? last_seq_ : -1;
  if (header_.seq < last_seq || header_.seq < newest_seq_ - kSeqWindow) {
    ++counters_.stale;
    if (header_.seq >= last_seq) ++counters_.stale_window;  // not a late copy: a reply fallen behind
    return Received::kOther;
  }
  if (header_.seq == last_seq) {
    ++counters_.duplicate;
    return Received::kOther;
  }
  if (config_.kind == DeviceKind::kArm) {
    if (ParseArmCommand(header_, payload_, config_.joints, &parsed_) != DecodeError::kNone) {
      return refuse(&counters_.refused_malformed);
    }
    if (!CheckArmLimits(parsed_)) return refuse(&counters_.refused_limits);
    std::swap(arm_command_, parsed_);
  } else if (config_.kind != DeviceKind::kSim) {
    if (header_.length != config_.command_length) return refuse(&counters_.refused_malformed);
    const CommandCheck verdict = config_.check_command ? config_.check_command(payload_) : CommandCheck::kAccept;
    if (verdict == CommandCheck::kMalformed) return refuse(&counters_.refused_malformed);
    if (verdict == CommandCheck::kLimits) return refuse(&counters_.refused_limits);
    command_.assign(payload_.begin(), payload_.end());
  } else {
    SimCommandMsg parsed;
    if (ParseSimCommand(header_, payload_, &parsed) != DecodeError::kNone) {
      return refuse(&counters_.refused_malformed);
    }
    sim_command_ = parsed;
  }
  if (!from_owner) {
    if (owner_) ++counters_.owners_released;  // taken over (a gate's kTakeOver)
    owner_ = from;
    last_payload_seq_ = 0;  // a new owner's payload counter starts from its own 1
  }
  owner_heard_s_ = sessions_.Now();
  last_seq_ = header_.seq;
  watch_seq_ = header_.seq;
  last_command_period_ = period;
  ever_commanded_ = true;
  has_command_ = true;
  refused_flag_ = false;
  watchdog_hold_ = false;
  ++counters_.accepted;
  return Received::kCommand;
}

DeviceEndpoint::Received DeviceEndpoint::HandlePayload(const Endpoint& from, bool finite, UdpSocket& socket) {
  ArmPayloadMsg parsed;
  const char* field = nullptr;
  const char* reason = nullptr;
  const bool from_owner = owner_ && *owner_ == from;
  // seq: the sender's own payload counter, a whole number >= 1 (DecodePacket checked it is whole)
  const bool ok = finite && header_.seq >= kFirstPayloadSeq &&
                  ParseArmPayload(header_, payload_, &parsed) == DecodeError::kNone &&
                  (config_.check_payload ? config_.check_payload(parsed) : CheckArmPayload(parsed, &field, &reason));
  if (!ok) {  // counted as malformed: seq 0, a length, a NaN or a load no rigid body has
    sessions_.Answer(from, SessionResult::kPayloadRefused, socket);
    ++counters_.refused_malformed;
    ++counters_.refused;
    if (from_owner) refused_flag_ = true;
    return Received::kOther;
  }
  // a late or replayed copy of an older payload must not set that payload again
  if (from_owner && header_.seq <= last_payload_seq_) {
    sessions_.Answer(from, SessionResult::kPayloadRefused, socket);
    ++counters_.stale;
    refused_flag_ = true;
    return Received::kOther;
  }
  if (!owner_) {  // a controller's first word may be its payload: it owns the arm from here on
    owner_ = from;
    last_seq_ = -1;
  }
  last_payload_seq_ = header_.seq;
  owner_heard_s_ = sessions_.Now();
  arm_payload_ = parsed;
  has_payload_ = true;
  describe_json_ = DescribeWithPayload(config_.describe_json, arm_payload_);
  ++counters_.payloads;
  sessions_.Answer(from, SessionResult::kPayloadSet, socket);
  return Received::kPayload;
}

bool DeviceEndpoint::UnansweredLongEnough(double pace_s) const {
  if (pace_s <= 0) return true;
  const double first = watch_seq_ + 1;  // the oldest state the owner left unanswered
  if (first > newest_seq_) return false;
  if (newest_seq_ - first >= kPublishedRing) return true;  // long gone
  const double published = published_s_[static_cast<std::size_t>(first) % kPublishedRing];
  return sessions_.Now() - published >= (config_.watchdog_periods - 1) * pace_s;
}

bool DeviceEndpoint::BeginPeriod(long period, double pace_s) {
  // (whether or not the silent owner still owns the input: a released arm holds too)
  const bool watched = config_.kind == DeviceKind::kArm || config_.command_length > 0;
  if (watched && config_.watchdog_periods > 0 && ever_commanded_ && !watchdog_hold_ &&
      period - last_command_period_ > config_.watchdog_periods && UnansweredLongEnough(pace_s)) {
    watchdog_hold_ = true;
    ++counters_.watchdog_holds;
  }
  return watchdog_hold_;
}

bool DeviceEndpoint::TakeArmCommand(ArmCommandMsg* command) {
  if (!has_command_ || config_.kind != DeviceKind::kArm) return false;
  command->mode = arm_command_.mode;
  command->value.assign(arm_command_.value.begin(), arm_command_.value.end());
  has_command_ = false;
  return true;
}

bool DeviceEndpoint::TakeSimCommand(SimCommandMsg* command) {
  if (!has_command_ || config_.kind != DeviceKind::kSim) return false;
  *command = sim_command_;
  has_command_ = false;
  return true;
}

bool DeviceEndpoint::TakeCommand(std::vector<double>* payload) {
  if (!has_command_ || config_.command_length == 0) return false;
  payload->assign(command_.begin(), command_.end());
  has_command_ = false;
  return true;
}

bool DeviceEndpoint::TakePayload(ArmPayloadMsg* payload) {
  if (!has_payload_) return false;
  *payload = arm_payload_;
  has_payload_ = false;
  return true;
}

std::uint32_t DeviceEndpoint::status_bits() const {
  std::uint32_t bits = 0;
  if (refused_flag_) bits |= kStatusRefused;
  if (watchdog_hold_) bits |= kStatusWatchdog | kStatusHolding;
  return bits;
}

bool DeviceEndpoint::MarkNotOwner(const std::vector<unsigned char>& packet) {
  if (!config_.status_first || !owner_ || packet.size() <= kHeaderBytes) return false;
  // the same state with kStatusNotOwner, for everyone but the owner
  not_owner_packet_ = packet;
  unsigned char* status = not_owner_packet_.data() + kHeaderBytes;
  const double value = GetDouble(status);
  const std::uint32_t bits = value >= 0 && value <= 4294967295.0 ? static_cast<std::uint32_t>(value) : 0;
  PutDouble(static_cast<double>(bits | kStatusNotOwner), status);
  return true;
}

void DeviceEndpoint::SendLatest(const std::vector<unsigned char>& packet, const Endpoint& to, UdpSocket& socket) {
  if (packet.empty()) return;
  const bool mark = !(owner_ && *owner_ == to) && MarkNotOwner(packet);
  const std::vector<unsigned char>& p = mark ? not_owner_packet_ : packet;
  socket.SendTo(p.data(), p.size(), to);
}

void DeviceEndpoint::Publish(const std::vector<unsigned char>& packet, UdpSocket& socket) {
  if (packet.size() >= kHeaderBytes) {
    const double seq = GetDouble(packet.data() + 4 * sizeof(double));
    if (seq > newest_seq_) {  // (a state sent again after a sim op keeps its first time)
      newest_seq_ = seq;
      published_s_[static_cast<std::size_t>(seq) % kPublishedRing] = sessions_.Now();
    }
  }
  ReleaseSilentOwner();
  sessions_.Expire(owner_ ? &*owner_ : nullptr);
  const bool mark = MarkNotOwner(packet);
  for (const SessionTable::Session& s : sessions_.sessions()) {
    const bool to_owner = owner_ && s.endpoint == *owner_;
    const std::vector<unsigned char>& p = mark && !to_owner ? not_owner_packet_ : packet;
    socket.SendTo(p.data(), p.size(), s.endpoint);
  }
}

}  // namespace vlab::bridge
