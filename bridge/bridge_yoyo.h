// The yo-yo case study's device kinds (docs/protocol.md), shared by every
// server of them (the lab, vlab-yoyosim, the vision program) and their
// clients. Their layouts are rows of the table in bridge_layouts.h; the name
// arrays below are taken from it, for the code that wants them as arrays.
//
//   point (kind 10): a point that is commanded and measured, e.g. the robot's
//     hand. Command [x, y, z]: where the point should go (m, world frame).
//     State [status, x, y, z, vx, vy, vz]: where it is (m) and how fast it moves
//     (m/s), world frame; status bits as an arm's (holding, refused, watchdog,
//     not_owner).
//   yoyo (kind 11): a yo-yo on its string, measured. No commands.
//     State [status, x, y, z, vz, string_force, spin]: the yo-yo's centre (m,
//     world), its vertical velocity (m/s), the string's tension at the hand (N,
//     >= 0; 0 while the string is slack) and the spin rate (rad/s). status bit
//     kYoyoNotSeen: a measurement that has no fresh position (e.g. vision lost
//     it); the values are then the last ones.
#pragma once

#include <array>

#include "bridge/bridge_layouts.h"

namespace vlab::bridge {

/// Value names of the point kind's command and state (the table's).
inline constexpr std::array<const char*, 3> kPointCommandLayout = FieldNames<3>(LayoutOf(DeviceKind::kPoint).command);
inline constexpr std::array<const char*, 7> kPointStateLayout = FieldNames<7>(LayoutOf(DeviceKind::kPoint).state);

/// Value names of the yoyo kind's state (it takes no commands).
inline constexpr std::array<const char*, 7> kYoyoStateLayout = FieldNames<7>(LayoutOf(DeviceKind::kYoyo).state);

/// Payload positions of the yoyo state's values (the table's), and its length.
inline constexpr int kYoyoStatus = StateIndex(DeviceKind::kYoyo, "status");
inline constexpr int kYoyoX = StateIndex(DeviceKind::kYoyo, "x");
inline constexpr int kYoyoY = StateIndex(DeviceKind::kYoyo, "y");
inline constexpr int kYoyoZ = StateIndex(DeviceKind::kYoyo, "z");
inline constexpr int kYoyoVz = StateIndex(DeviceKind::kYoyo, "vz");
inline constexpr int kYoyoStringForce = StateIndex(DeviceKind::kYoyo, "string_force");
inline constexpr int kYoyoSpin = StateIndex(DeviceKind::kYoyo, "spin");
inline constexpr int kYoyoValues = ValueCount(LayoutOf(DeviceKind::kYoyo).state);

/// Yoyo status bit: no fresh measurement of the position in this state.
inline constexpr unsigned kYoyoNotSeen = 1u << 6;  // after the arm bits (bridge_protocol.h)

}  // namespace vlab::bridge
