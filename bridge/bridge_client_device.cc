#include "bridge/bridge_client_device.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "bridge/bridge_errors.h"
#include "bridge/bridge_layouts.h"

namespace vlab::bridge {

namespace {

// the index of `name` in `names`, or -1
int IndexOf(const std::vector<std::string>& names, std::string_view name) {
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] == name) return static_cast<int>(i);
  }
  return -1;
}

// a kind that is not a float64 array per period cannot be read by layout
DeviceKind Float64Kind(DeviceKind kind) {
  const KindLayout* k = FindKindLayout(static_cast<int>(kind));
  if (k == nullptr) {
    throw std::invalid_argument("device kind " + std::to_string(static_cast<int>(kind)) + " is unknown");
  }
  if (!k->float64) {
    throw std::invalid_argument(std::string(k->name) + " devices are not float64 arrays (" + k->note +
                                "): use their own client");
  }
  return kind;
}

}  // namespace

std::vector<std::string> ExpandLayoutFields(const nlohmann::json& fields, const std::string& label) {
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

Device::Device(DeviceKind kind, const std::string& address, int port, double timeout_s, const std::string& bind_address)
    : DeviceClient(Float64Kind(kind), address, port, timeout_s, bind_address) {
  const nlohmann::json& layout = describe().contains("layout") ? describe()["layout"] : nlohmann::json();
  if (!layout.is_object()) throw ProtocolError(Label() + ": describe reply has no layout");
  state_names_ = ExpandLayoutFields(layout.value("state", nlohmann::json()), Label());
  command_names_ = ExpandLayoutFields(layout.value("command", nlohmann::json::array()), Label());
  // a fixed layout must be the table's: its compile-time indices are then right
  const KindLayout& table = LayoutOf(kind);
  if (IsFixed(table.state) && IsFixed(table.command)) {
    const nlohmann::json want = LayoutJson(kind);
    for (const char* part : {"state", "command"}) {
      const nlohmann::json have = layout.value(part, nlohmann::json::array());
      if (have != want[part]) {
        throw ProtocolError(Label() + ": describe layout." + part + " is " + have.dump() + ", the protocol's " +
                            table.name + " layout is " + want[part].dump());
      }
    }
  }
  state_length_ = static_cast<int>(state_names_.size());
  command_length_ = static_cast<int>(command_names_.size());
  values_.reserve(static_cast<std::size_t>(state_length_));
  command_.assign(static_cast<std::size_t>(command_length_), 0.0);
  given_.assign(static_cast<std::size_t>(command_length_), 0);
}

Device Device::Connect(DeviceKind kind, const std::string& address, int port, double timeout_s,
                       const std::string& bind_address) {
  return Device(kind, address, port, timeout_s, bind_address);
}

int Device::StateIndex(std::string_view name) const { return IndexOf(state_names_, name); }
int Device::CommandIndex(std::string_view name) const { return IndexOf(command_names_, name); }

double Device::Field(const State& state, std::string_view name) const {
  const int i = StateIndex(name);
  if (i < 0) throw std::invalid_argument(Label() + ": no state field '" + std::string(name) + "'");
  if (static_cast<int>(state.values.size()) != state_length_) {
    throw std::invalid_argument(Label() + ": field '" + std::string(name) + "' of a state with " +
                                std::to_string(state.values.size()) + " values, not " + std::to_string(state_length_));
  }
  return state.values[static_cast<std::size_t>(i)];
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

bool Device::WriteFields(std::initializer_list<FieldValue> values, std::int64_t seq) {
  if (command_length_ == 0) throw std::invalid_argument(Label() + ": this device takes no commands");
  std::fill(given_.begin(), given_.end(), 0);
  for (const FieldValue& v : values) {
    const int i = CommandIndex(v.name);
    if (i < 0) throw std::invalid_argument(Label() + ": no command field '" + std::string(v.name) + "'");
    if (given_[i]) throw std::invalid_argument(Label() + ": command field '" + std::string(v.name) + "' given twice");
    given_[i] = 1;
    command_[i] = v.value;
  }
  for (int i = 0; i < command_length_; ++i) {
    if (!given_[i]) throw std::invalid_argument(Label() + ": command field '" + command_names_[i] + "' not given");
  }
  return Write(command_, seq);
}

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
