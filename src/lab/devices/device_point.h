// A task-space interface to an arm's tool (kind point): a commanded point
// that the device turns into joint velocity commands for its arm (device_point.cc).
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "lab/devices/device.h"
#include "lab/devices/device_arm_chain.h"

namespace vlab::lab {

/// A task-space interface to an arm's tool (kind point), like a robot
/// controller's Cartesian position input: a commanded point [x, y, z] that the
/// device turns into joint velocity commands for its arm every control period
/// (device_point.cc).
/// Its arm, chain and gains are ArmChainParams (device_arm_chain.h): the site is
/// the point, and the orientation gain keeps the orientation the site had at the start.
struct PointParams : ArmChainParams {
  double max_speed = 1.0;  ///< m/s: the set-point ramps toward each command at most this fast
  /// Workspace box, world frame, m: commands outside [min, max] are refused (limits).
  std::vector<double> workspace_min = {-std::numeric_limits<double>::infinity(),
                                       -std::numeric_limits<double>::infinity(),
                                       -std::numeric_limits<double>::infinity()};
  std::vector<double> workspace_max = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                                       std::numeric_limits<double>::infinity()};
};

/// Reads the entry's own keys.
std::shared_ptr<const DeviceParams> ReadPointParams(MapReader& r);
/// Makes the device; throws InputError naming the device and the MJCF element it cannot bind.
std::unique_ptr<Device> MakePoint(const DeviceContext& context, const DeviceConfig& config);

}  // namespace vlab::lab
