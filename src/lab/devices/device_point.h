// A task-space interface to an arm's tool (kind point): a commanded point
// that the device turns into joint velocity commands for its arm (device_point.cc).
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "lab/devices/device.h"

namespace vlab::lab {

/// A task-space interface to an arm's tool (kind point), like a robot
/// controller's Cartesian position input: a commanded point [x, y, z] that the
/// device turns into joint velocity commands for its arm every control period
/// (device_point.cc).
struct PointParams : DeviceParams {
  std::string arm;                  ///< the arm device it drives (a device of the same scenario)
  std::string site = "tool";        ///< the point: an MJCF site at the end of the arm's chain
  std::string base_body = "world";  ///< the chain starts below this body
  double k_position = 20.0;         ///< position gain, 1/s
  double k_orientation = 20.0;      ///< orientation gain (the start orientation is kept), 1/s
  double k_null = 1.0;              ///< null-space gain toward the start posture, 1/s
  double damping = 1e-3;            ///< DLS damping of the pseudo-inverse
  double max_speed = 1.0;           ///< m/s: the set-point ramps toward each command at most this fast
  /// Workspace box, world frame, m: commands outside [min, max] are refused (limits).
  std::vector<double> workspace_min = {-std::numeric_limits<double>::infinity(),
                                       -std::numeric_limits<double>::infinity(),
                                       -std::numeric_limits<double>::infinity()};
  std::vector<double> workspace_max = {std::numeric_limits<double>::infinity(),
                                       std::numeric_limits<double>::infinity(),
                                       std::numeric_limits<double>::infinity()};
  CommandInputConfig input;  ///< watchdog_periods, owner_timeout
};

/// Reads the entry's own keys.
std::shared_ptr<const DeviceParams> ReadPointParams(MapReader& r);
/// Makes the device; throws InputError naming the device and the MJCF element it cannot bind.
std::unique_ptr<Device> MakePoint(const DeviceContext& context, const DeviceConfig& config);

}  // namespace vlab::lab
