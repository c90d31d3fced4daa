// A task-space pose interface to an arm's tool (kind tool): a commanded
// position and orientation that the device turns into joint velocity commands
// for its arm (device_tool.cc).
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "lab/devices/device.h"
#include "lab/devices/device_arm_chain.h"

namespace vlab::lab {

/// A task-space pose interface to an arm's tool (kind tool), like a robot
/// controller's Cartesian pose input: a commanded tool pose [x, y, z, qw, qx,
/// qy, qz] that the device turns into joint velocity commands for its arm every
/// control period (device_tool.cc).
/// Its arm, chain and gains are ArmChainParams (device_arm_chain.h): the site is
/// the tool frame.
struct ToolParams : ArmChainParams {
  static constexpr double kInf = std::numeric_limits<double>::infinity();
  double max_speed = 0.5;          ///< m/s: the position set-point ramps toward each command at most this fast
  double max_angular_speed = 1.0;  ///< rad/s: the orientation set-point turns at most this fast
  /// Workspace box, world frame, m: positions outside [min, max] are refused (limits).
  std::vector<double> workspace_min = {-kInf, -kInf, -kInf};
  std::vector<double> workspace_max = {kInf, kInf, kInf};
  /// Reach sphere: positions farther than the radius from the centre are
  /// refused (limits). kAuto (the default): centred on the chain's first
  /// joint's anchor (where it is at each period's end), radius the sum of the
  /// distances anchor to anchor along the chain and on to the site (rigid
  /// links: no posture reaches farther); kFixed: reach_centre (world frame, m)
  /// and reach_radius (m); kOff: no check.
  enum class Reach { kAuto, kFixed, kOff } reach = Reach::kAuto;
  std::vector<double> reach_centre = {0, 0, 0};
  double reach_radius = kInf;
  /// Tool-axis cone: orientations whose tool z axis is more than max_tilt_deg
  /// from tilt_axis are refused (limits); 180: no check.
  std::vector<double> tilt_axis = {0, 0, -1};
  double max_tilt_deg = 180;
};

/// Reads the entry's own keys.
std::shared_ptr<const DeviceParams> ReadToolParams(MapReader& r);
/// Makes the device; throws InputError naming the device and the MJCF element it cannot bind.
std::unique_ptr<Device> MakeTool(const DeviceContext& context, const DeviceConfig& config);

}  // namespace vlab::lab
