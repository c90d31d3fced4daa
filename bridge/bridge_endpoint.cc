#include "bridge/bridge_endpoint.h"

#include <cmath>

namespace vlab::bridge {

DeviceEndpoint::DeviceEndpoint(EndpointConfig config) : config_(std::move(config)) {
  payload_.reserve(kMaxPacketValues);
  subscribers_.reserve(config_.max_subscribers);
  arm_command_.value.reserve(kMaxPacketValues);
  parsed_.value.reserve(kMaxPacketValues);
  command_.reserve(kMaxPacketValues);
  if (config_.kind == DeviceKind::kArm) config_.status_first = true;
  not_owner_packet_.reserve(kMaxPacketValues * sizeof(double));
}

void DeviceEndpoint::Subscribe(const Endpoint& from, long period) {
  for (Subscriber& s : subscribers_) {
    if (s.endpoint == from) {
      s.last_period = period;
      return;
    }
  }
  // drop silent subscribers first; when still full, the longest silent one
  for (std::size_t i = 0; i < subscribers_.size();) {
    if (period - subscribers_[i].last_period > config_.subscriber_timeout_periods) {
      subscribers_.erase(subscribers_.begin() + static_cast<long>(i));
    } else {
      ++i;
    }
  }
  if (static_cast<int>(subscribers_.size()) >= config_.max_subscribers) {
    std::size_t oldest = 0;
    for (std::size_t i = 1; i < subscribers_.size(); ++i) {
      if (subscribers_[i].last_period < subscribers_[oldest].last_period) oldest = i;
    }
    subscribers_.erase(subscribers_.begin() + static_cast<long>(oldest));
  }
  subscribers_.push_back({from, period});
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
    case 1: return within(config_.position_min, config_.position_max, c.value);
    case 2: return within_abs(config_.velocity_max, c.value);
    case 3: return within_abs(config_.torque_max, c.value);
    default: return true;  // hold: values unused
  }
}

bool DeviceEndpoint::Handle(const unsigned char* data, std::size_t size, const Endpoint& from, long period,
                            UdpSocket& socket) {
  ++counters_.received;
  const bool from_owner = owner_ && *owner_ == from;
  auto refuse = [&](long* reason) {
    ++*reason;
    ++counters_.refused;
    if (from_owner) refused_flag_ = true;
    return false;
  };
  DecodeError e = DecodePacket(data, size, &header_, &payload_);
  // a describe request is answered whatever kind it names: tools discover with it
  const bool describe = e == DecodeError::kNone && header_.type == static_cast<int>(MessageType::kDescribe);
  if (e == DecodeError::kNone && !describe && header_.kind != static_cast<int>(config_.kind)) e = DecodeError::kBadKind;
  if (e == DecodeError::kNone && header_.type == static_cast<int>(MessageType::kState)) e = DecodeError::kBadType;
  if (e != DecodeError::kNone) return refuse(&counters_.refused_malformed);
  Subscribe(from, period);

  if (describe) {
    ++counters_.describes;
    socket.SendTo(reinterpret_cast<const unsigned char*>(config_.describe_json.data()),
                  config_.describe_json.size(), from);
    return false;
  }
  const bool commanded =
      config_.kind == DeviceKind::kArm || config_.kind == DeviceKind::kSim || config_.command_length > 0;
  if (!commanded) return refuse(&counters_.refused_malformed);  // output-only device

  // one owner at a time; an owner silent for too long gives the input up. A
  // new owner takes over with its first ACCEPTED command only.
  if (owner_ && !from_owner && period - owner_last_period_ <= config_.owner_timeout_periods) {
    return refuse(&counters_.refused_not_owner);
  }
  if (from_owner) owner_last_period_ = period;  // any datagram shows the owner is alive
  const double last_seq = from_owner ? last_seq_ : -1;
  if (header_.seq < last_seq) {
    ++counters_.stale;
    return false;
  }
  if (header_.seq == last_seq) {
    ++counters_.duplicate;
    return false;
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
  if (!from_owner) owner_ = from;
  owner_last_period_ = period;
  last_seq_ = header_.seq;
  last_command_period_ = period;
  ever_commanded_ = true;
  has_command_ = true;
  refused_flag_ = false;
  watchdog_hold_ = false;
  ++counters_.accepted;
  return true;
}

bool DeviceEndpoint::BeginPeriod(long period) {
  // (whether or not the silent owner still owns the input: a released arm holds too)
  const bool watched = config_.kind == DeviceKind::kArm || config_.command_length > 0;
  if (watched && config_.watchdog_periods > 0 && ever_commanded_ && !watchdog_hold_ &&
      period - last_command_period_ > config_.watchdog_periods) {
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

std::uint32_t DeviceEndpoint::status_bits() const {
  std::uint32_t bits = 0;
  if (refused_flag_) bits |= kStatusRefused;
  if (watchdog_hold_) bits |= kStatusWatchdog | kStatusHolding;
  return bits;
}

void DeviceEndpoint::Publish(const std::vector<unsigned char>& packet, UdpSocket& socket) {
  const bool mark = config_.status_first && owner_ && packet.size() > kHeaderBytes;
  if (mark) {
    // the same state with kStatusNotOwner, for everyone but the owner
    not_owner_packet_ = packet;
    unsigned char* status = not_owner_packet_.data() + kHeaderBytes;
    const double value = GetDouble(status);
    const std::uint32_t bits = value >= 0 && value <= 4294967295.0 ? static_cast<std::uint32_t>(value) : 0;
    PutDouble(static_cast<double>(bits | kStatusNotOwner), status);
  }
  for (const Subscriber& s : subscribers_) {
    const bool to_owner = owner_ && s.endpoint == *owner_;
    const std::vector<unsigned char>& p = mark && !to_owner ? not_owner_packet_ : packet;
    socket.SendTo(p.data(), p.size(), s.endpoint);
  }
}

}  // namespace vlab::bridge
