// The Foxglove WebSocket protocol's messages and a client's subscriptions
// (view_foxglove.h).
#include "view/view_foxglove.h"

#include <cstring>
#include <nlohmann/json.hpp>

#include "scene/scene_messages.h"

namespace vlab::view {

namespace {

// the client operations a read-only server refuses: publishing, parameters, services, graph, assets
const char* const kReadOnlyOps[] = {"advertise",
                                    "unadvertise",
                                    "getParameters",
                                    "setParameters",
                                    "subscribeParameterUpdates",
                                    "unsubscribeParameterUpdates",
                                    "subscribeConnectionGraph",
                                    "unsubscribeConnectionGraph",
                                    "fetchAsset"};

// a JSON value as a uint32 id: an integer 0 .. 2^32-1
bool AsId(const nlohmann::json& value, std::uint32_t* id) {
  if (!value.is_number_integer()) return false;
  if (value.is_number_unsigned()) {
    const auto v = value.get<std::uint64_t>();
    if (v > 0xffffffffull) return false;
    *id = static_cast<std::uint32_t>(v);
    return true;
  }
  const auto v = value.get<std::int64_t>();
  if (v < 0 || v > 0xffffffffll) return false;
  *id = static_cast<std::uint32_t>(v);
  return true;
}

}  // namespace

std::string FoxgloveServerInfo() {
  return nlohmann::json{{"op", "serverInfo"},
                        {"name", "vlab view"},
                        {"capabilities", nlohmann::json::array()},
                        {"metadata", {{"read_only", "true"}}}}
      .dump();
}

std::string FoxgloveAdvertise(const std::vector<FoxgloveChannel>& channels) {
  nlohmann::json list = nlohmann::json::array();
  for (std::size_t i = 0; i < channels.size(); ++i) {
    list.push_back({{"id", i},
                    {"topic", channels[i].topic},
                    {"encoding", scene::kMessageEncoding},
                    {"schemaName", channels[i].schema_name},
                    {"schemaEncoding", scene::kSchemaEncoding},
                    {"schema", channels[i].schema}});
  }
  return nlohmann::json{{"op", "advertise"}, {"channels", list}}.dump();
}

std::string FoxgloveStatus(int level, const std::string& message) {
  // replace: a client's bytes quoted back in a reason may be invalid UTF-8
  return nlohmann::json{{"op", "status"}, {"level", level}, {"message", message}}.dump(
      -1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string FoxgloveRecord(std::uint64_t log_time_ns, const std::string& payload) {
  std::string out(8, '\0');
  std::memcpy(out.data(), &log_time_ns, 8);  // little-endian hosts only, as every vlab wire
  out += payload;
  return out;
}

void FoxgloveDataHeader(std::uint32_t subscription_id, char out[5]) {
  out[0] = 0x01;
  std::memcpy(out + 1, &subscription_id, 4);
}

std::string FoxgloveSubscriptions::Apply(const std::string& message, bool binary, bool* read_only, bool* malformed) {
  *read_only = false;
  *malformed = false;
  if (binary) {
    const int opcode = message.empty() ? -1 : static_cast<unsigned char>(message[0]);
    if (opcode == 0x01 || opcode == 0x02) {
      *read_only = true;
      return std::string("vlab view is read-only: ") + (opcode == 0x01 ? "client message data" : "service call") +
             " refused (no clientPublish or services capability)";
    }
    *malformed = true;
    return "unknown binary opcode " + std::to_string(opcode);
  }
  const nlohmann::json m = nlohmann::json::parse(message, nullptr, false);
  if (m.is_discarded() || !m.is_object() || !m.contains("op") || !m["op"].is_string()) {
    *malformed = true;
    return "not a JSON object with a string 'op'";
  }
  const std::string op = m["op"].get<std::string>();
  for (const char* refused : kReadOnlyOps) {
    if (op == refused) {
      *read_only = true;
      return "vlab view is read-only: '" + op + "' refused (capabilities: none)";
    }
  }
  std::string errors;
  const auto note = [&errors](const std::string& e) { errors += (errors.empty() ? "" : "; ") + e; };
  if (op == "subscribe") {
    if (!m.contains("subscriptions") || !m["subscriptions"].is_array()) {
      *malformed = true;
      return "subscribe: 'subscriptions' must be an array";
    }
    for (const nlohmann::json& s : m["subscriptions"]) {
      std::uint32_t id = 0, channel = 0;
      if (!s.is_object() || !s.contains("id") || !s.contains("channelId") || !AsId(s["id"], &id) ||
          !AsId(s["channelId"], &channel)) {
        note("subscribe: each subscription needs integer 'id' and 'channelId' >= 0");
        continue;
      }
      if (channel >= by_channel_.size()) {
        note("subscribe: no channel " + std::to_string(channel));
      } else if (by_id_.count(id)) {
        note("subscribe: subscription id " + std::to_string(id) + " is in use");
      } else if (by_channel_[channel] != kNone) {
        note("subscribe: channel " + std::to_string(channel) + " is already subscribed");
      } else {
        by_id_[id] = static_cast<int>(channel);
        by_channel_[channel] = id;
      }
    }
    *malformed = !errors.empty();
    return errors;
  }
  if (op == "unsubscribe") {
    if (!m.contains("subscriptionIds") || !m["subscriptionIds"].is_array()) {
      *malformed = true;
      return "unsubscribe: 'subscriptionIds' must be an array";
    }
    for (const nlohmann::json& v : m["subscriptionIds"]) {
      std::uint32_t id = 0;
      const auto at = AsId(v, &id) ? by_id_.find(id) : by_id_.end();
      if (at == by_id_.end()) {
        note("unsubscribe: no subscription " + v.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
        continue;
      }
      by_channel_[at->second] = kNone;
      by_id_.erase(at);
    }
    *malformed = !errors.empty();
    return errors;
  }
  *malformed = true;
  return "unknown op '" + op + "'";
}

}  // namespace vlab::view
