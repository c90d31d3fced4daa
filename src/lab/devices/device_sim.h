// The run's own control device (kind sim): the simulation's clock and
// counters out; pause, resume, step, reset and the realtime factor in.
//
// Ports
//   input   [op, arg]: 1 reset, 2 pause, 3 resume, 4 step arg periods, 5 set
//           the realtime factor to arg; taken by the lab's loop before a
//           period begins (and while paused), never waited for
//   output  [sim_time, mode, clock, periods, refused_packets,
//           missed_deadlines, realtime_factor, max_lateness], set by the lab
//           before every publish
// It has no physics: the lab's loop reads its commands and writes its state.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "bridge/bridge_protocol.h"
#include "lab/devices/device.h"

namespace vlab::lab {

/// The sim device has no keys of its own.
struct SimParams : DeviceParams {};

std::shared_ptr<const DeviceParams> ReadSimParams(MapReader& r);
std::unique_ptr<Device> MakeSim(const DeviceContext& context, const DeviceConfig& config);

class SimControl final : public Device {
 public:
  explicit SimControl(const DeviceConfig& config) : Device(config) {}

  /// The state the next publish sends.
  void set_state(const bridge::SimStateMsg& state) { state_ = state; }
  /// The newest command the bridge took since the last call, if any.
  bool TakeOp(bridge::SimCommandMsg* command);

  // Device
  void Bind(const std::vector<Device*>& devices) override;
  void EncodeState(double seq, double t, std::uint32_t endpoint_bits, std::vector<double>* scratch,
                   std::vector<unsigned char>* out) const override;
  std::string DescribeJson(const bridge::DeviceDescription& common) const override;
  CommandRole command_role() const override { return CommandRole::kRun; }
  bool TakeCommand(bridge::DeviceEndpoint& endpoint, std::vector<double>* scratch) override;

 private:
  std::vector<std::string> devices_;  // every device of the scenario, in its order
  bridge::SimStateMsg state_;
  bridge::SimCommandMsg pending_;
  bool has_pending_ = false;
};

}  // namespace vlab::lab
