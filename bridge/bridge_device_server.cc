#include "bridge/bridge_device_server.h"

namespace vlab::bridge {

std::unique_ptr<DeviceServer> DeviceServer::Bind(const DeviceServerConfig& config) {
  std::unique_ptr<DeviceServer> s(new DeviceServer());
  s->config_ = config;
  s->socket_ = UdpSocket::Bind(config.bind_address, config.port);  // throws NetworkError naming the address
  s->buffer_.resize(kDatagramBufferBytes);  // a longer datagram than a valid packet is refused as too long
  s->latest_.reserve(kMaxPacketValues * sizeof(double));
  s->payload_.reserve(kMaxPacketValues);
  return s;
}

void DeviceServer::Serve(EndpointConfig endpoint) { endpoint_ = std::make_unique<DeviceEndpoint>(std::move(endpoint)); }

void DeviceServer::ServeSessions(const SessionConfig& sessions, std::string describe_json) {
  sessions_ = std::make_unique<SessionTable>(sessions);
  describe_json_ = std::move(describe_json);
}

const std::string& DeviceServer::describe_json() const {
  return endpoint_ ? endpoint_->describe_json() : describe_json_;
}

int DeviceServer::Drain(double wait_s, const Handler& handle) {
  int handled = 0;
  while (config_.max_datagrams <= 0 || handled < config_.max_datagrams) {
    Endpoint from;
    bool truncated = false;
    const long size = socket_->Receive(buffer_.data(), buffer_.size(), &from, handled == 0 ? wait_s : 0.0, &truncated);
    if (size < 0) break;
    ++handled;
    // a truncated datagram was longer than any valid one: handed on whole-buffer, refused as too long
    handle(buffer_.data(), truncated ? buffer_.size() : static_cast<std::size_t>(size), from);
  }
  return handled;
}

int DeviceServer::Receive(long period, const std::function<void()>& on_command, double wait_s) {
  return Drain(wait_s, [&](const unsigned char* data, std::size_t size, const Endpoint& from) {
    using Received = DeviceEndpoint::Received;
    const Received what = endpoint_->Handle(data, size, from, period, *socket_);
    // a new subscriber gets the latest state at once (it may be what lockstep waits on)
    if (what == Received::kSubscribed && config_.send_latest) endpoint_->SendLatest(latest_, from, *socket_);
    if (what == Received::kCommand && on_command) on_command();
  });
}

DeviceServer::Request DeviceServer::HandleRequest(const unsigned char* data, std::size_t size, const Endpoint& from) {
  const int kind = static_cast<int>(sessions_->config().kind);
  DecodeError e = DecodePacket(data, size, &header_, &payload_);
  // a describe request is answered whatever kind it names (0: any): tools discover with it
  const bool describe = e == DecodeError::kNone && header_.type == static_cast<int>(MessageType::kDescribe);
  if (e == DecodeError::kNone && (describe ? header_.kind > kMaxDeviceKind : header_.kind != kind)) {
    e = DecodeError::kBadKind;
  }
  // states and session replies go the other way; a payload is for an arm's endpoint only
  if (e == DecodeError::kNone && (header_.type == static_cast<int>(MessageType::kState) ||
                                  header_.type == static_cast<int>(MessageType::kSession) ||
                                  header_.type == static_cast<int>(MessageType::kPayload))) {
    e = DecodeError::kBadType;
  }
  if (e != DecodeError::kNone) return Request::kMalformed;
  if (!describe && header_.type != static_cast<int>(MessageType::kSubscribe)) return Request::kCommand;
  switch (sessions_->HandleRequest(header_, payload_, from, *socket_)) {
    case SessionTable::Outcome::kMalformed:
      return Request::kMalformed;
    case SessionTable::Outcome::kDescribe:
      socket_->SendTo(reinterpret_cast<const unsigned char*>(describe_json_.data()), describe_json_.size(), from);
      return Request::kDescribed;
    default:
      return Request::kSession;
  }
}

void DeviceServer::Publish(const std::vector<unsigned char>& state) {
  latest_.assign(state.begin(), state.end());
  endpoint_->Publish(latest_, *socket_);
}

void DeviceServer::Publish(double seq, double time, const double* values, int n) {
  const Header header{static_cast<int>(endpoint_->config().kind), static_cast<int>(MessageType::kState), seq, time, n};
  EncodePacket(header, values, n, &latest_);
  endpoint_->Publish(latest_, *socket_);
}

void DeviceServer::PublishToSubscribers(const std::vector<unsigned char>& state) {
  sessions_->Expire();
  for (const SessionTable::Session& s : sessions_->sessions()) socket_->SendTo(state.data(), state.size(), s.endpoint);
}

}  // namespace vlab::bridge
