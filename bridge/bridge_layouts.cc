#include "bridge/bridge_layouts.h"

#include <stdexcept>

#include <nlohmann/json.hpp>

namespace vlab::bridge {

namespace layout_detail {

namespace {

std::string KindLabel(int kind) {
  const KindLayout* k = FindKindLayout(kind);
  return k != nullptr ? k->name : "device kind " + std::to_string(kind);
}

}  // namespace

void ThrowNoField(int kind, const char* what, std::string_view name) {
  throw std::invalid_argument(KindLabel(kind) + ": no " + what + " field '" + std::string(name) + "'");
}

void ThrowNotFixed(int kind, const char* what, std::string_view name) {
  throw std::invalid_argument(KindLabel(kind) + ": " + what + " field '" + std::string(name) +
                              "' has no fixed index (it follows a per-joint or per-sensor group)");
}

void ThrowNoKind(int kind) {
  throw std::invalid_argument("device kind " + std::to_string(kind) + " is not one of 1.." +
                              std::to_string(kMaxDeviceKind));
}

void ThrowNotNames(std::size_t want, std::size_t have) {
  throw std::invalid_argument("FieldNames<" + std::to_string(want) + ">: the layout has " + std::to_string(have) +
                              " fields, or a group");
}

}  // namespace layout_detail

namespace {

using nlohmann::json;

// a float64 kind's row, or throws naming the kind
const KindLayout& Float64Layout(DeviceKind kind) {
  const KindLayout& k = LayoutOf(kind);
  if (!k.float64) {
    throw std::invalid_argument(std::string(k.name) + ": not a float64 layout (" + k.note + ")");
  }
  return k;
}

// true when some field of the kind's state or command is of `group`
bool Has(const KindLayout& k, FieldGroup group) {
  for (FieldList fields : {k.state, k.command}) {
    for (const LayoutField& f : fields) {
      if (f.group == group) return true;
    }
  }
  return false;
}

// the names of `fields`, a group written by `group_names`
template <typename GroupNames>
json Names(FieldList fields, GroupNames group_names) {
  json out = json::array();
  for (const LayoutField& f : fields) {
    if (f.group == FieldGroup::kOne) {
      out.push_back(f.name);
    } else {
      group_names(f, &out);
    }
  }
  return out;
}

int FixedLength(DeviceKind kind, FieldList fields, const char* what) {
  if (!IsFixed(fields)) {
    throw std::invalid_argument(std::string(LayoutOf(kind).name) + ": the " + what +
                                " length depends on the device (a per-joint or per-sensor group)");
  }
  return ValueCount(fields);
}

}  // namespace

int StateLength(DeviceKind kind) { return FixedLength(kind, Float64Layout(kind).state, "state"); }
int CommandLength(DeviceKind kind) { return FixedLength(kind, Float64Layout(kind).command, "command"); }

json LayoutJson(DeviceKind kind) {
  const KindLayout& k = Float64Layout(kind);
  if (!IsFixed(k.state) || !IsFixed(k.command)) {
    throw std::invalid_argument(std::string(k.name) + ": the layout depends on the device; give its " +
                                (Has(k, FieldGroup::kPerJoint) ? "joint count" : "sensor value names"));
  }
  const auto none = [](const LayoutField&, json*) {};
  return {{"state", Names(k.state, none)}, {"command", Names(k.command, none)}};
}

json LayoutJson(DeviceKind kind, int joints) {
  const KindLayout& k = Float64Layout(kind);
  if (!Has(k, FieldGroup::kPerJoint)) {
    throw std::invalid_argument(std::string(k.name) + ": no per-joint layout");
  }
  if (joints < 1) throw std::invalid_argument(std::string(k.name) + ": " + std::to_string(joints) + " joints");
  const auto sized = [joints](const LayoutField& f, json* out) {
    out->push_back(std::string(f.name) + "[" + std::to_string(joints) + "]");
  };
  return {{"state", Names(k.state, sized)}, {"command", Names(k.command, sized)}};
}

json LayoutJson(DeviceKind kind, const std::vector<std::string>& sensor_values) {
  const KindLayout& k = Float64Layout(kind);
  if (!Has(k, FieldGroup::kPerSensorValue)) {
    throw std::invalid_argument(std::string(k.name) + ": no per-sensor layout");
  }
  if (sensor_values.empty()) throw std::invalid_argument(std::string(k.name) + ": no sensor values");
  const auto named = [&sensor_values](const LayoutField&, json* out) {
    for (const std::string& name : sensor_values) out->push_back(name);
  };
  return {{"state", Names(k.state, named)}, {"command", Names(k.command, named)}};
}

}  // namespace vlab::bridge
