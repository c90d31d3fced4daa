// Simulated wrench device (kind wrench): a JR3 force/torque sensor over
// MuJoCo's force and torque sensors at one site.
//
// Ports
//   input   none
//   output  WrenchState: the selected JR3 filter's wrench (load applied by the
//           tool side, sensor frame: Fx Fy Fz N, Mx My Mz N·m), the filter in
//           use, saturation
//   rate    the JR3 model runs at 8 kHz internally, fed after every physics
//           step with the wrench held over that step; output at control rate
// Noise and bias are seeded per device from the scenario seed.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "lab/devices/device.h"
#include "sensors/sensor_wrench.h"

namespace vlab::lab {

/// The wrench axes, in the order of the device's log columns (NAME.Fx ... NAME.Mz) and state.
inline constexpr const char* kWrenchAxes[6] = {"Fx", "Fy", "Fz", "Mx", "My", "Mz"};

struct WrenchParams : DeviceParams {
  std::string site;           ///< sensor site (documentation; frames come from the sensors)
  std::string force_sensor;   ///< MJCF force sensor at the site
  std::string torque_sensor;  ///< MJCF torque sensor at the site
  std::string model = "67M25A";
  std::vector<double> full_scale;  ///< 6 values, N and N·m; empty: the model's defaults
  int filter = 4;
  bool noise = true;
  bool bias = true;
  bool quantization = true;
};

/// The JR3 model configuration the device runs for `params`, seeded with `seed`. Throws
/// nothing; WrenchSensorModel::Create checks it.
sensors::WrenchSensorConfig WrenchSensorConfigOf(const WrenchParams& params, std::uint64_t seed);

/// Reads a wrench entry's keys (site, force_sensor, torque_sensor, model,
/// full_scale, filter, noise, bias, quantization).
std::shared_ptr<const DeviceParams> ReadWrenchParams(MapReader& r);
/// Binds to the force and torque sensors the entry names (which must be at the
/// same site). Throws InputError naming the device and element.
std::unique_ptr<Device> MakeWrench(const DeviceContext& context, const DeviceConfig& config);

}  // namespace vlab::lab
