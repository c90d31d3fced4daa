// The wire layouts of every device kind, in one table: each kind's name and
// the fields of its state (type 1) and command (type 2) payloads, in payload
// order, with their units. Servers build their describe replies' "layout"
// from it (LayoutJson), clients find values by name (StateIndex,
// CommandIndex), and tests/bridge/protocol_doc_test.cc checks the per-kind
// tables of docs/protocol.md against it.
//
// A field is one value, or a group whose size depends on the device:
//   per joint         one value per joint of an arm: "q" is q_1..q_n on the
//                     page, "q[n]" in a describe reply
//   per sensor value  one value per configured MJCF sensor value (feet, imu):
//                     the describe reply names each value after its sensor
//                     ("lf_fr", "gyro.x"); the group's name is the page's label
// Camera (4) and markers (5) are not float64-per-period kinds: their rows have
// a note and no fields (docs/protocol_camera.md, docs/protocol_markers.md).
//
// Everything here is constexpr over static data, so an index of a fixed
// layout is a compile-time constant:
//   constexpr int kGrasped = StateIndex(DeviceKind::kGripper, "grasped");  // 4
// and a misspelt name fails to compile there; at run time it throws
// std::invalid_argument naming the kind and the field.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "bridge/bridge_protocol.h"

namespace vlab::bridge {

/// How many payload values one layout field stands for.
enum class FieldGroup : int {
  kOne = 0,             ///< one value
  kPerJoint = 1,        ///< one value per joint of the device (arm)
  kPerSensorValue = 2,  ///< one value per configured sensor value (feet, imu)
};

/// One field of a state or command payload. Strings are literals (so they
/// are null-terminated); unit "" means a pure number (counts, codes, flags).
struct LayoutField {
  const char* name;                     ///< as in describe replies' "layout" ("grasped"; a group: "q")
  const char* unit;                     ///< SI unit as docs/protocol.md writes it ("m/s"), "" for none
  const char* meaning;                  ///< a short description
  FieldGroup group = FieldGroup::kOne;  ///< one value, or a group of them
};

/// A view of a payload's fields, in payload order.
struct FieldList {
  const LayoutField* data = nullptr;  ///< static storage (the table's arrays)
  std::size_t size = 0;               ///< number of fields (a group counts 1)

  constexpr const LayoutField* begin() const { return data; }
  constexpr const LayoutField* end() const { return data + size; }
  constexpr const LayoutField& operator[](std::size_t i) const { return data[i]; }
  constexpr bool empty() const { return size == 0; }
};

/// One device kind: its code, its name on the wire ("arm", "yoyo"), and its
/// state and command fields. `float64` is false for the kinds whose payload
/// is not one float64 array per period (camera, markers; see `note`).
struct KindLayout {
  DeviceKind kind;    ///< the kind's code in the header
  const char* name;   ///< describe replies' "kind"
  bool float64;       ///< one float64 array per state / command
  FieldList state;    ///< type 1 payload, device -> client
  FieldList command;  ///< type 2 payload, client -> device (empty: takes none)
  const char* note;   ///< what else to know about the kind
};

namespace layout_detail {

// a list of all of an array's fields
template <std::size_t N>
constexpr FieldList Fields(const LayoutField (&fields)[N]) {
  return {fields, N};
}

constexpr FieldGroup kJoint = FieldGroup::kPerJoint;
constexpr FieldGroup kSensor = FieldGroup::kPerSensorValue;

inline constexpr LayoutField kArmState[] = {
    {"status", "", "a sum of status bits (holding 1, refused 2, saturated 4, at_limit 8, watchdog 16, not_owner 32)"},
    {"q", "rad", "joint positions", kJoint},
    {"qd", "rad/s", "joint velocities", kJoint},
    {"tau", "N m", "applied joint torques", kJoint},
};
inline constexpr LayoutField kArmCommand[] = {
    {"mode", "", "0 hold, 1 position, 2 velocity, 3 torque"},
    {"value", "rad (mode 1), rad/s (mode 2), N m (mode 3)", "one per joint; ignored in mode 0", kJoint},
};
inline constexpr LayoutField kWrenchState[] = {
    {"Fx", "N", "force, sensor frame"},
    {"Fy", "N", "force, sensor frame"},
    {"Fz", "N", "force, sensor frame"},
    {"Mx", "N m", "moment, sensor frame"},
    {"My", "N m", "moment, sensor frame"},
    {"Mz", "N m", "moment, sensor frame"},
    {"filter", "", "the sensor filter the values come from (0 unfiltered, 1..6)"},
    {"saturated", "", "1 if an axis was beyond its range during the period, else 0"},
};
inline constexpr LayoutField kSimState[] = {
    {"sim_time", "s", "simulated time"},
    {"mode", "", "0 running, 1 paused"},
    {"clock", "", "0 fast, 1 lockstep, 2 realtime"},
    {"periods", "", "control periods run"},
    {"refused_packets", "", "datagrams refused by all devices"},
    {"missed_deadlines", "", "periods that finished late (realtime)"},
    {"realtime_factor", "", "simulated seconds per wall-clock second asked for"},
    {"max_lateness", "s", "the worst lateness of a period so far"},
};
inline constexpr LayoutField kSimCommand[] = {
    {"op", "", "1 reset, 2 pause, 3 resume, 4 step, 5 set realtime factor"},
    {"arg", "", "op 4: periods to step; op 5: the factor; others: 0"},
};
inline constexpr LayoutField kBaseState[] = {
    {"status", "", "status bits (holding, refused, watchdog, not_owner)"},
    {"x", "m", "odometry position, world frame"},
    {"y", "m", "odometry position, world frame"},
    {"yaw", "rad", "odometry heading"},
    {"vx", "m/s", "measured velocity, base frame"},
    {"vy", "m/s", "measured velocity, base frame"},
    {"wz", "rad/s", "measured yaw rate"},
};
inline constexpr LayoutField kBaseCommand[] = {
    {"frame", "", "0 base frame, 1 world frame"},
    {"vx", "m/s", "velocity"},
    {"vy", "m/s", "velocity"},
    {"wz", "rad/s", "yaw rate"},
};
inline constexpr LayoutField kGripperState[] = {
    {"status", "", "status bits (holding, refused, watchdog, not_owner)"},
    {"opening", "m", "distance between the pads"},
    {"opening_velocity", "m/s", "rate of the opening"},
    {"force", "N", "mean normal force of the pads on what they hold"},
    {"grasped", "", "1 when every pad presses with at least grasp_force and the jaws are at rest, else 0"},
};
inline constexpr LayoutField kGripperCommand[] = {
    {"mode", "", "0 position, 1 force"},
    {"value", "m (mode 0), N (mode 1)", "the opening set-point, or the grip force"},
};
inline constexpr LayoutField kFeetState[] = {
    {"force", "N", "normal force of one force-sensing resistor, named after its sensor", kSensor},
};
inline constexpr LayoutField kImuState[] = {
    {"reading", "rad/s (gyro), m/s² (accelerometer)", "one axis of a gyro or accelerometer, named after its sensor",
     kSensor},
};
inline constexpr LayoutField kPointState[] = {
    {"status", "", "status bits (holding, refused, watchdog, not_owner)"},
    {"x", "m", "where the point is, world frame"},
    {"y", "m", "where the point is, world frame"},
    {"z", "m", "where the point is, world frame"},
    {"vx", "m/s", "its velocity, world frame"},
    {"vy", "m/s", "its velocity, world frame"},
    {"vz", "m/s", "its velocity, world frame"},
};
inline constexpr LayoutField kPointCommand[] = {
    {"x", "m", "where the point should go, world frame"},
    {"y", "m", "where the point should go, world frame"},
    {"z", "m", "where the point should go, world frame"},
};
inline constexpr LayoutField kYoyoState[] = {
    {"status", "", "64 not_seen: no fresh position in this state"},
    {"x", "m", "the yo-yo's centre, world frame"},
    {"y", "m", "the yo-yo's centre, world frame"},
    {"z", "m", "the yo-yo's centre, world frame"},
    {"vz", "m/s", "its vertical velocity"},
    {"string_force", "N", "the string's tension at the hand, >= 0"},
    {"spin", "rad/s", "spin rate about the axle"},
};
inline constexpr LayoutField kGazeState[] = {
    {"error_deg", "deg", "angle between the optical axis and the ray to the target"},
    {"u", "px", "the target's pixel column"},
    {"v", "px", "the target's pixel row"},
    {"visible", "", "1 when in front of the camera and inside the image, else 0"},
};
inline constexpr LayoutField kPoseState[] = {
    {"x", "m", "position in the describe reply's frame"},
    {"y", "m", "position in the describe reply's frame"},
    {"z", "m", "position in the describe reply's frame"},
    {"qw", "", "orientation in that frame (unit quaternion)"},
    {"qx", "", "orientation in that frame (unit quaternion)"},
    {"qy", "", "orientation in that frame (unit quaternion)"},
    {"qz", "", "orientation in that frame (unit quaternion)"},
};
inline constexpr LayoutField kCounterState[] = {
    {"revolutions", "turns", "whole turns since the start of the run, signed"},
    {"rpm", "1/min", "the speed over the last gate time, rounded to the describe reply's resolution_rpm"},
};
inline constexpr LayoutField kSceneState[] = {
    {"pose", "m, unit quaternion", "x, y, z, qw, qx, qy, qz of each body of the describe reply's bodies, world frame",
     kSensor},
};

inline constexpr LayoutField kWordState[] = {
    {"spelled", "", "1 when every letter is within the describe reply's bounds, else 0"},
    {"letter", "m, deg, deg, m/s, –",
     "pos_error, yaw_error, tilt, speed, on_top of each letter of the describe reply's word, in order", kSensor},
};
inline constexpr LayoutField kToolState[] = {
    {"status", "", "status bits (holding, refused, watchdog, not_owner)"},
    {"x", "m", "where the tool is, world frame"},
    {"y", "m", "where the tool is, world frame"},
    {"z", "m", "where the tool is, world frame"},
    {"qw", "", "the tool's orientation, world frame (unit quaternion)"},
    {"qx", "", "the tool's orientation, world frame (unit quaternion)"},
    {"qy", "", "the tool's orientation, world frame (unit quaternion)"},
    {"qz", "", "the tool's orientation, world frame (unit quaternion)"},
    {"vx", "m/s", "its linear velocity, world frame"},
    {"vy", "m/s", "its linear velocity, world frame"},
    {"vz", "m/s", "its linear velocity, world frame"},
    {"wx", "rad/s", "its angular velocity, world frame"},
    {"wy", "rad/s", "its angular velocity, world frame"},
    {"wz", "rad/s", "its angular velocity, world frame"},
};
inline constexpr LayoutField kToolCommand[] = {
    {"x", "m", "where the tool should go, world frame"},
    {"y", "m", "where the tool should go, world frame"},
    {"z", "m", "where the tool should go, world frame"},
    {"qw", "", "the orientation it should take, world frame (unit quaternion)"},
    {"qx", "", "the orientation it should take, world frame (unit quaternion)"},
    {"qy", "", "the orientation it should take, world frame (unit quaternion)"},
    {"qz", "", "the orientation it should take, world frame (unit quaternion)"},
};

// an arm's payload message (type 6): the load at the flange (the body of the last joint)
inline constexpr LayoutField kArmPayload[] = {
    {"mass", "kg", "mass of the load, >= 0 (0: none)"},
    {"com_x", "m", "centre of mass, flange frame"},
    {"com_y", "m", "centre of mass, flange frame"},
    {"com_z", "m", "centre of mass, flange frame"},
    {"ixx", "kg m²", "moment of inertia about the centre of mass, flange axes"},
    {"iyy", "kg m²", "moment of inertia about the centre of mass, flange axes"},
    {"izz", "kg m²", "moment of inertia about the centre of mass, flange axes"},
    {"ixy", "kg m²", "product of inertia (as MJCF fullinertia)"},
    {"ixz", "kg m²", "product of inertia (as MJCF fullinertia)"},
    {"iyz", "kg m²", "product of inertia (as MJCF fullinertia)"},
};

}  // namespace layout_detail

/// The table: one row per device kind, row i is kind i + 1.
inline constexpr KindLayout kKindLayouts[kMaxDeviceKind] = {
    {DeviceKind::kArm, "arm", true, layout_detail::Fields(layout_detail::kArmState),
     layout_detail::Fields(layout_detail::kArmCommand), "n joints, from the describe reply's \"joints\""},
    {DeviceKind::kWrench, "wrench", true, layout_detail::Fields(layout_detail::kWrenchState), {}, "output only"},
    {DeviceKind::kSim, "sim", true, layout_detail::Fields(layout_detail::kSimState),
     layout_detail::Fields(layout_detail::kSimCommand), "the simulation's own control device"},
    {DeviceKind::kCamera, "camera", false, {}, {}, "frames in chunks: docs/protocol_camera.md"},
    {DeviceKind::kMarkers, "markers", false, {}, {}, "marker poses per image: docs/protocol_markers.md"},
    {DeviceKind::kBase, "base", true, layout_detail::Fields(layout_detail::kBaseState),
     layout_detail::Fields(layout_detail::kBaseCommand), "a holonomic mobile base"},
    {DeviceKind::kGripper, "gripper", true, layout_detail::Fields(layout_detail::kGripperState),
     layout_detail::Fields(layout_detail::kGripperCommand), "a parallel gripper"},
    {DeviceKind::kFeet,
     "feet",
     true,
     layout_detail::Fields(layout_detail::kFeetState),
     {},
     "output only; one value per touch sensor"},
    {DeviceKind::kImu,
     "imu",
     true,
     layout_detail::Fields(layout_detail::kImuState),
     {},
     "output only; one value per gyro or accelerometer axis"},
    {DeviceKind::kPoint, "point", true, layout_detail::Fields(layout_detail::kPointState),
     layout_detail::Fields(layout_detail::kPointCommand), "a commanded and measured point (a hand)"},
    {DeviceKind::kYoyo, "yoyo", true, layout_detail::Fields(layout_detail::kYoyoState), {}, "output only"},
    {DeviceKind::kGaze,
     "gaze",
     true,
     layout_detail::Fields(layout_detail::kGazeState),
     {},
     "output only; lab ground truth"},
    {DeviceKind::kPose,
     "pose",
     true,
     layout_detail::Fields(layout_detail::kPoseState),
     {},
     "output only; ground truth of a tracked frame"},
    {DeviceKind::kCounter,
     "counter",
     true,
     layout_detail::Fields(layout_detail::kCounterState),
     {},
     "output only; a gate-time speed counter"},
    {DeviceKind::kScene,
     "scene",
     true,
     layout_detail::Fields(layout_detail::kSceneState),
     {},
     "output only; 7 values per visual body, published at the describe reply's rate_hz"},
    {DeviceKind::kWord,
     "word",
     true,
     layout_detail::Fields(layout_detail::kWordState),
     {},
     "output only; lab ground truth; 5 values per letter"},
    {DeviceKind::kTool, "tool", true, layout_detail::Fields(layout_detail::kToolState),
     layout_detail::Fields(layout_detail::kToolCommand), "a commanded and measured tool pose"},
};

/// The fields of an arm's payload message (kind 1, type 6, client -> device;
/// bridge_payload.h), in payload order: mass, centre of mass, inertia.
inline constexpr FieldList kArmPayloadLayout = layout_detail::Fields(layout_detail::kArmPayload);

namespace layout_detail {

// the table's rows are in kind order, and every layout's names are unique
constexpr bool SameText(const char* a, const char* b) { return std::string_view(a) == std::string_view(b); }
constexpr bool UniqueNames(FieldList fields) {
  for (std::size_t i = 0; i < fields.size; ++i) {
    for (std::size_t j = i + 1; j < fields.size; ++j) {
      if (SameText(fields[i].name, fields[j].name)) return false;
    }
  }
  return true;
}
constexpr bool TableIsWellFormed() {
  for (int i = 0; i < kMaxDeviceKind; ++i) {
    const KindLayout& k = kKindLayouts[i];
    if (static_cast<int>(k.kind) != i + 1 || !UniqueNames(k.state) || !UniqueNames(k.command)) return false;
    if (!k.float64 && !(k.state.empty() && k.command.empty())) return false;
  }
  return true;
}
static_assert(TableIsWellFormed(), "kKindLayouts: rows out of kind order, or a repeated field name");

/// Throws std::invalid_argument "<kind>: no <what> field '<name>'" (not
/// constexpr: a call reached in a constant expression fails to compile).
[[noreturn]] void ThrowNoField(int kind, const char* what, std::string_view name);
/// Throws std::invalid_argument "<kind>: <what> field '<name>' has no fixed
/// index (it follows a per-joint or per-sensor group)".
[[noreturn]] void ThrowNotFixed(int kind, const char* what, std::string_view name);
/// Throws std::invalid_argument "device kind <kind> is not one of 1..kMaxDeviceKind".
[[noreturn]] void ThrowNoKind(int kind);
/// Throws std::invalid_argument: FieldNames<N> of a list that is not N single values.
[[noreturn]] void ThrowNotNames(std::size_t want, std::size_t have);

constexpr int FixedIndex(DeviceKind kind, FieldList fields, const char* what, std::string_view name) {
  for (std::size_t i = 0; i < fields.size; ++i) {
    if (std::string_view(fields[i].name) != name) continue;
    for (std::size_t j = 0; j < i; ++j) {
      if (fields[j].group != FieldGroup::kOne) ThrowNotFixed(static_cast<int>(kind), what, name);
    }
    return static_cast<int>(i);
  }
  ThrowNoField(static_cast<int>(kind), what, name);
}

}  // namespace layout_detail

/// The row of a kind code, or nullptr when the code is not 1..kMaxDeviceKind.
constexpr const KindLayout* FindKindLayout(int kind) {
  return kind >= 1 && kind <= kMaxDeviceKind ? &kKindLayouts[kind - 1] : nullptr;
}

/// The row of a kind name ("arm", "yoyo"), or nullptr when none has it.
constexpr const KindLayout* FindKindLayout(std::string_view name) {
  for (const KindLayout& k : kKindLayouts) {
    if (std::string_view(k.name) == name) return &k;
  }
  return nullptr;
}

/// The row of a kind; throws std::invalid_argument for a code outside the table.
constexpr const KindLayout& LayoutOf(DeviceKind kind) {
  const KindLayout* k = FindKindLayout(static_cast<int>(kind));
  if (k == nullptr) layout_detail::ThrowNoKind(static_cast<int>(kind));
  return *k;
}

/// Position of the field `name` in `fields` (a field, not a value: a group
/// counts 1), or -1 when there is none.
constexpr int FindField(FieldList fields, std::string_view name) {
  for (std::size_t i = 0; i < fields.size; ++i) {
    if (std::string_view(fields[i].name) == name) return static_cast<int>(i);
  }
  return -1;
}

/// True when every field is one value (no per-joint or per-sensor group).
constexpr bool IsFixed(FieldList fields) {
  for (const LayoutField& f : fields) {
    if (f.group != FieldGroup::kOne) return false;
  }
  return true;
}

/// Number of payload values of `fields` with `per_group` values in each group
/// (joints, sensor values; ignored by a fixed layout).
constexpr int ValueCount(FieldList fields, int per_group = 0) {
  int n = 0;
  for (const LayoutField& f : fields) n += f.group == FieldGroup::kOne ? 1 : per_group;
  return n;
}

/// Payload index of the state field `name` of `kind`: a compile-time constant
/// where used as one. Throws std::invalid_argument (fails to compile in a
/// constant expression) when the kind has no such state field, or when a
/// group comes before it (its index depends on the device).
constexpr int StateIndex(DeviceKind kind, std::string_view name) {
  return layout_detail::FixedIndex(kind, LayoutOf(kind).state, "state", name);
}

/// Payload index of the command field `name` of `kind`; errors as StateIndex.
constexpr int CommandIndex(DeviceKind kind, std::string_view name) {
  return layout_detail::FixedIndex(kind, LayoutOf(kind).command, "command", name);
}

/// Number of state / command values of a fixed layout (0 for none); throws
/// std::invalid_argument for a layout with a group, whose size depends on the
/// device, and for camera and markers.
int StateLength(DeviceKind kind);
int CommandLength(DeviceKind kind);

/// The names of a fixed layout's fields as an array of N C strings, for
/// constants such as bridge_yoyo.h's (N must be the field count).
template <std::size_t N>
constexpr std::array<const char*, N> FieldNames(FieldList fields) {
  std::array<const char*, N> names{};
  if (fields.size != N || !IsFixed(fields)) layout_detail::ThrowNotNames(N, fields.size);
  for (std::size_t i = 0; i < N; ++i) names[i] = fields[i].name;
  return names;
}

/// The describe reply's "layout" object {"state": [...], "command": [...]} of
/// a kind with fixed layouts (wrench, sim, base, gripper, point, yoyo, gaze,
/// pose). Throws std::invalid_argument for a kind with a group (arm, feet,
/// imu: use the overloads below) or without float64 layouts (camera, markers).
nlohmann::json LayoutJson(DeviceKind kind);

/// The same for a per-joint kind (arm) with `joints` joints (>= 1): each
/// group as "name[joints]", e.g. ["status", "q[7]", "qd[7]", "tau[7]"].
/// Throws std::invalid_argument for another kind or joints < 1.
nlohmann::json LayoutJson(DeviceKind kind, int joints);

/// The same for a per-sensor-value kind (feet, imu): the group is replaced
/// by `sensor_values`, one name per value as the device calls it ("gyro.x").
/// Throws std::invalid_argument for another kind or an empty list.
nlohmann::json LayoutJson(DeviceKind kind, const std::vector<std::string>& sensor_values);

}  // namespace vlab::bridge
