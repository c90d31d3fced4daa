// Simulated wrench device: a JR3 force/torque sensor over MuJoCo's force and
// torque sensors at one site.
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

#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "bridge/bridge_messages.h"
#include "lab/lab_scenario.h"
#include "sensors/sensor_wrench.h"

namespace vlab::lab {

class SimWrench {
 public:
  /// Binds to the force and torque sensors the scenario names (which must be
  /// at the same site). Throws InputError naming the device and element.
  static std::unique_ptr<SimWrench> Create(const mjModel* model, const DeviceConfig& config, std::uint64_t seed);

  const std::string& name() const { return name_; }
  /// Restarts the sensor (new bias from the seed, filters settled on the
  /// current load). mj_forward must have run on `data`.
  void Reset(const mjData& data);
  /// Feeds the load of the physics step just taken (after mj_step2).
  void Step(const mjData& data, double dt);
  /// Forms the host's reading at the end of a control period (once per period).
  void EndPeriod();
  /// The reading formed by the last EndPeriod().
  void Sample(double time_s, bridge::WrenchState* state) const;

  /// Log columns: NAME.Fx .. NAME.Mz, NAME.saturated.
  std::vector<std::string> Columns() const;
  int ColumnCount() const { return 7; }
  void Row(double* out) const;

  const sensors::WrenchSensorModel& sensor() const { return *sensor_; }

 private:
  SimWrench() = default;
  sensors::Wrench TrueLoad(const mjData& data) const;

  std::string name_;
  int force_adr_ = -1, torque_adr_ = -1;
  std::unique_ptr<sensors::WrenchSensorModel> sensor_;
  sensors::WrenchSensorState state_;
  sensors::WrenchReading reading_;
  bool saturated_in_period_ = false;  // since the last EndPeriod
  bool saturated_ = false;            // during the period the reading closes
};

}  // namespace vlab::lab
