// A ground-truth gaze probe (kind gaze, lab only): where a target lies
// relative to a camera's optical axis and in its image (device_gaze.cc).
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "lab/devices/device.h"

namespace vlab::lab {

/// A ground-truth gaze probe (kind gaze): where a target lies relative to an
/// MJCF camera's optical axis and in its pinhole image (no lens distortion).
struct GazeParams : DeviceParams {
  std::string camera;  ///< MJCF camera name
  std::string target;  ///< MJCF site or body name (a site wins when both exist)
  int width = 640;     ///< image size for the intrinsics, pixels (fx = fy = (height/2) / tan(fovy/2))
  int height = 480;
};

/// Reads the entry's own keys.
std::shared_ptr<const DeviceParams> ReadGazeParams(MapReader& r);
/// Makes the device; throws InputError naming the device and the MJCF element it cannot bind.
std::unique_ptr<Device> MakeGaze(const DeviceContext& context, const DeviceConfig& config);

}  // namespace vlab::lab
