// An arm's payload on the wire: the load a controller declares at the flange,
// as a real arm takes it at run time (URScript set_payload, KRL LOAD_DATA,
// RAPID loaddata). docs/protocol.md, "Arm payload", is its contract.
//
// A payload datagram (kind 1 arm, type 6, client -> device) carries 10
// values (bridge_layouts.h, kArmPayloadLayout): mass kg; centre of mass x, y,
// z m; inertia about the centre of mass ixx, iyy, izz, ixy, ixz, iyz kg m^2;
// all in the flange frame (the body of the arm's last joint). Only the arm's
// owner may set it, with a seq (its own payload counter: 1, 2, 3, ...)
// above the last it set, so that a late or replayed copy of an older
// payload cannot set that one again; the device answers every payload from
// a subscriber with a session reply: kPayloadSet or kPayloadRefused
// (bridge_session.h). The
// describe reply of an arm reports the payload in force as
// "payload": {"mass": kg, "com": [x, y, z], "inertia": [ixx, iyy, izz, ixy, ixz, iyz]}.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "bridge/bridge_protocol.h"

namespace vlab::bridge {

/// Values in a payload datagram.
inline constexpr int kArmPayloadValues = 10;

/// The seq of a sender's first payload; each next payload it sends carries one
/// more. A seq below it (0) is malformed.
inline constexpr double kFirstPayloadSeq = 1;

/// A load at an arm's flange (frame: the body of its last joint).
struct ArmPayloadMsg {
  double mass_kg = 0;                                       ///< kg, >= 0 (0: no payload)
  std::array<double, 3> com_m = {0, 0, 0};                  ///< centre of mass in the flange frame, m
  std::array<double, 6> inertia_kgm2 = {0, 0, 0, 0, 0, 0};  ///< ixx iyy izz ixy ixz iyz about the com, kg m^2
  bool operator==(const ArmPayloadMsg& o) const {
    return mass_kg == o.mass_kg && com_m == o.com_m && inertia_kgm2 == o.inertia_kgm2;
  }
};

/// Encodes a payload datagram (kind arm, type 6) into `out` (resized). seq:
/// the sender's own payload counter, a whole number >= 1 that grows with every
/// payload it sends (the device refuses one not above the last it accepted
/// from its owner); time: the sender's clock, s (informative).
void EncodeArmPayload(double seq, double time, const ArmPayloadMsg& payload, std::vector<unsigned char>* out);

/// Payload of a framed datagram -> message: kind arm, type 6 and exactly 10
/// values (else kBadKind, kBadType, kBadLength). Finiteness is DecodePacket's.
DecodeError ParseArmPayload(const Header& header, const std::vector<double>& values, ArmPayloadMsg* payload);

/// Whether `payload` is a rigid body: finite values, mass >= 0, inertia
/// positive semi-definite with principal moments obeying the triangle
/// inequality (the same rule as the lab's CheckPayload). On false, `field`
/// ("mass", "com" or "inertia") and `reason` point to static text. No
/// allocation.
bool CheckArmPayload(const ArmPayloadMsg& payload, const char** field, const char** reason);

/// `describe_json` (a describe reply, a JSON object) with its "payload" set to
/// `payload`; the text unchanged when it is not a JSON object.
std::string DescribeWithPayload(const std::string& describe_json, const ArmPayloadMsg& payload);

/// Reads the "payload" object of a describe reply (JSON text). False when it
/// has none or it is malformed (then `payload` is untouched).
bool PayloadFromDescribe(const std::string& describe_json, ArmPayloadMsg* payload);

}  // namespace vlab::bridge
