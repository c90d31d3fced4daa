// Describe replies: the JSON a device sends back to a describe request.
// Tools discover a device from it; controllers may hard-code the same facts.
// Every reply has: name, kind, protocol (version), server, clock, endpoint
// {address, port}, rates {control_hz}, layout {state: [...], command: [...]}
// (field names in payload order; "q[7]" = 7 values), units, and the kind's
// own facts (arm: joints, limits, watchdog, payload; wrench: full scale, filter).
#pragma once

#include <string>
#include <vector>

#include "bridge/bridge_payload.h"

namespace vlab::bridge {

struct DeviceDescription {
  std::string name;
  std::string server;   ///< e.g. "vlab serve (MuJoCo 2.2.2)", "vlab kinsim"
  std::string clock;    ///< fast | lockstep | realtime
  std::string address;  ///< bound address
  int port = 0;
  double control_hz = 0;
};

struct ArmDescription : DeviceDescription {
  std::vector<std::string> joints;
  std::vector<double> position_min, position_max;  ///< rad (empty: unlimited)
  std::vector<double> velocity_max;                ///< rad/s, |qd| (empty: unlimited)
  std::vector<double> torque_max;                  ///< N m, |tau| (empty: unlimited)
  int watchdog_periods = 3;
  double owner_timeout_s = 1.0;
  /// Encoder resolution, rad (slide: m) per count, one per joint; empty: the
  /// positions are not quantised (then the reply has no "resolution").
  std::vector<double> resolution;
  /// The payload at the flange (reported as "payload": {mass, com, inertia}) ...
  ArmPayloadMsg payload;
  /// ... and what the servo does with it (reported as "feedforward"): "model"
  /// (its gravity and Coriolis feed-forward carries it), "world" (accepted and
  /// reported, the torques do not depend on it), "none" (no dynamics).
  std::string feedforward = "none";
};

struct WrenchDescription : DeviceDescription {
  std::string sensor_model;
  std::vector<double> full_scale;  ///< Fx Fy Fz (N), Mx My Mz (N m)
  int filter = 0;
  double filter_cutoff_hz = 0;  ///< of the filter in use (0: unfiltered)
  double sample_hz = 8000;
};

struct SimDescription : DeviceDescription {
  std::vector<std::string> devices;  ///< the other devices of the scene
  double owner_timeout_s = 1.0;
  std::string on_owner_lost = "resume";  ///< resume | stay_paused
  std::string ops_from = "driver";       ///< who may operate it: driver | anyone
};

std::string DescribeJson(const ArmDescription& d);
std::string DescribeJson(const WrenchDescription& d);
std::string DescribeJson(const SimDescription& d);
/// Any other kind: the common fields, then every field of `facts` (a JSON
/// object: layout, units and the kind's own facts).
std::string DescribeJson(const DeviceDescription& d, const std::string& kind, const std::string& facts);

}  // namespace vlab::bridge
