#include "bridge/bridge_client_device.h"

#include <cmath>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "bridge/bridge_errors.h"

namespace vlab::bridge {

namespace {

// "q[7]" -> q[0] .. q[6]; "x" -> x
std::vector<std::string> Expand(const nlohmann::json& fields, const std::string& label) {
  std::vector<std::string> out;
  if (!fields.is_array()) throw ProtocolError(label + ": describe reply has no layout");
  for (const auto& f : fields) {
    if (!f.is_string()) throw ProtocolError(label + ": describe layout holds a non-string field");
    const std::string s = f.get<std::string>();
    const auto open = s.find('[');
    if (open == std::string::npos || s.back() != ']') {
      out.push_back(s);
      continue;
    }
    const std::string base = s.substr(0, open);
    int n = 0;
    try {
      n = std::stoi(s.substr(open + 1, s.size() - open - 2));
    } catch (const std::exception&) {
      throw ProtocolError(label + ": describe layout field '" + s + "' has a bad count");
    }
    if (n < 0 || n > kMaxPacketValues) throw ProtocolError(label + ": describe layout field '" + s + "' is too long");
    for (int i = 0; i < n; ++i) out.push_back(base + "[" + std::to_string(i) + "]");
  }
  return out;
}

}  // namespace

Device::Device(DeviceKind kind, const std::string& address, int port, double timeout_s,
               const std::string& bind_address)
    : DeviceClient(kind, address, port, timeout_s, bind_address) {
  const nlohmann::json& layout = describe().contains("layout") ? describe()["layout"] : nlohmann::json();
  if (!layout.is_object()) throw ProtocolError(Label() + ": describe reply has no layout");
  state_names_ = Expand(layout.value("state", nlohmann::json()), Label());
  command_names_ = Expand(layout.value("command", nlohmann::json::array()), Label());
  state_length_ = static_cast<int>(state_names_.size());
  command_length_ = static_cast<int>(command_names_.size());
  values_.reserve(static_cast<std::size_t>(state_length_));
}

Device Device::Connect(DeviceKind kind, const std::string& address, int port, double timeout_s,
                       const std::string& bind_address) {
  return Device(kind, address, port, timeout_s, bind_address);
}

int Device::StateIndex(const std::string& name) const {
  for (std::size_t i = 0; i < state_names_.size(); ++i) {
    if (state_names_[i] == name) return static_cast<int>(i);
  }
  return -1;
}

DecodeError Device::ParseState(const Header& header, const std::vector<double>& payload) {
  if (header.length != state_length_) return DecodeError::kBadLength;
  values_.assign(payload.begin(), payload.end());
  return DecodeError::kNone;
}

Device::State Device::Copy(const Header& header) const {
  State s;
  s.seq = static_cast<std::int64_t>(header.seq);
  s.time = header.time;
  s.values = values_;
  return s;
}

Device::State Device::Read(double timeout_s) { return Copy(ReceiveState(timeout_s, false)); }
Device::State Device::ReadLatest(double timeout_s) { return Copy(ReceiveState(timeout_s, true)); }

bool Device::Write(const std::vector<double>& values, std::int64_t seq) {
  if (command_length_ == 0) throw std::invalid_argument(Label() + ": this device takes no commands");
  if (static_cast<int>(values.size()) != command_length_) {
    throw std::invalid_argument(Label() + ": a command has " + std::to_string(command_length_) + " values, got " +
                                std::to_string(values.size()));
  }
  for (double v : values) {
    if (!std::isfinite(v)) throw std::invalid_argument(Label() + ": command value is not finite");
  }
  CheckSeq(seq);
  Header h;
  h.kind = static_cast<int>(kind());
  h.type = static_cast<int>(MessageType::kCommand);
  h.seq = static_cast<double>(seq);
  h.time = ClientTime();
  h.length = command_length_;
  EncodePacket(h, values.data(), command_length_, &packet_);
  return Send(packet_);
}

}  // namespace vlab::bridge
