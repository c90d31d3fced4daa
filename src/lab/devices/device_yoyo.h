// The yo-yo of mjcf/yoyo measured (kind yoyo): centre, vertical speed,
// string tension and spin (device_yoyo.cc).
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "lab/devices/device.h"

namespace vlab::lab {

/// The yo-yo of mjcf/yoyo measured (kind yoyo): its centre, vertical speed,
/// string tension and spin, optionally at a camera's rate and with noise
/// (device_yoyo.cc). Defaults: the model's names.
struct YoyoParams : DeviceParams {
  std::string slide = "yoyo_drop";     ///< slide joint d: the centre's distance below the hand, m
  std::string spin = "yoyo_spin";      ///< hinge joint of the spin
  std::string centre = "yoyo_centre";  ///< site at the yo-yo's centre
  std::vector<std::string> tension = {"yoyo_string_plus_force",
                                      "yoyo_string_minus_force"};  ///< tendonlimitfrc sensors, summed
  double rate_hz = 0.0;  ///< sample-and-hold rate of the measurement, Hz (0: every control period)
  double noise = 0.0;    ///< Gaussian noise std on the position x, y, z, m (seeded)
};

/// Reads the entry's own keys.
std::shared_ptr<const DeviceParams> ReadYoyoParams(MapReader& r);
/// Makes the device; throws InputError naming the device and the MJCF element it cannot bind.
std::unique_ptr<Device> MakeYoyo(const DeviceContext& context, const DeviceConfig& config);

}  // namespace vlab::lab
