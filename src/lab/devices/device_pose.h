// A tracked frame (kind pose), like a motion-capture rigid body: an MJCF
// site's pose in the frame of a body (device_pose.cc).
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "lab/devices/device.h"

namespace vlab::lab {

/// A tracked frame (kind pose), like a motion-capture system's rigid body:
/// an MJCF site's pose in the frame of a body, and its distance to a target.
struct PoseParams : DeviceParams {
  std::string site;                   ///< the tracked site
  std::string relative_to = "world";  ///< the body whose frame the pose is given in
  std::string target;                 ///< a site whose distance is logged ("": none)
  /// Gripper bodies (lab-only truth): log how many hold the site's body (two of a gripper's
  /// finger bodies touch it) and how long the body has touched nothing (empty: not logged).
  std::vector<std::string> grippers;
};

/// Reads the entry's own keys.
std::shared_ptr<const DeviceParams> ReadPoseParams(MapReader& r);
/// Makes the device; throws InputError naming the device and the MJCF element it cannot bind.
std::unique_ptr<Device> MakePose(const DeviceContext& context, const DeviceConfig& config);

}  // namespace vlab::lab
