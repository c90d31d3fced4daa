// The run's own control device (kind sim): the simulation's clock and
// counters out; pause, resume, step, reset and the realtime factor in.
//
// Ports
//   input   [op, arg]: 1 reset, 2 pause, 3 resume, 4 step arg periods, 5 set
//           the realtime factor to arg; taken by the lab's loop before a
//           period begins (and while paused), never waited for
//   output  [sim_time, mode, clock, periods, refused_packets,
//           missed_deadlines, realtime_factor, max_lateness], set by the lab
//           before every publish. Its seq counts the states it sent (the
//           state re-sent after an op while paused gets a seq of its own, so
//           that the next op can answer it); `periods` is the period.
// Who may operate it (`ops_from`): `driver` (the default): while a controller
// drives the run (a commanded device other than the sim has an owner), only
// the owner of such a device (its address and port) may, and it takes the
// sim over; while nobody drives, the first accepted op claims the sim.
// `anyone`: the first accepted op claims it, whoever drives. Refused ops are
// answered with a session reply (result 5) and counted as not owner.
// Its owner is released after owner_timeout of silence (wall clock), paused
// or not, when it unsubscribes, or when a driver appears; a pause then ends
// or stays as `on_owner_lost` says.
// It has no physics: the lab's loop reads its commands and writes its state.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "bridge/bridge_protocol.h"
#include "lab/devices/device.h"

namespace vlab::lab {

/// What the lab does when the sim device's owner is lost while paused.
enum class OnOwnerLost { kResume, kStayPaused };
/// Who may operate the sim (scenario key `ops_from`).
enum class SimOps { kDriver, kAnyone };

struct SimParams : DeviceParams {
  OnOwnerLost on_owner_lost = OnOwnerLost::kResume;  ///< on_owner_lost: resume | stay_paused
  double owner_timeout_s = 1.0;                      ///< owner_timeout, s (wall clock)
  SimOps ops = SimOps::kDriver;                      ///< ops_from: driver | anyone
};

std::shared_ptr<const DeviceParams> ReadSimParams(MapReader& r);
std::unique_ptr<Device> MakeSim(const DeviceContext& context, const DeviceConfig& config);

class SimControl final : public Device, public CommandInput {
 public:
  explicit SimControl(const DeviceConfig& config);

  /// The state the next publish sends (one call per publish: it counts them).
  void set_state(const bridge::SimStateMsg& state) {
    state_ = state;
    ++states_;
  }
  OnOwnerLost on_owner_lost() const { return on_owner_lost_; }
  SimOps ops() const { return ops_; }
  /// The newest command the bridge took since the last call, if any.
  bool TakeOp(bridge::SimCommandMsg* command);

  // Device
  void Bind(const std::vector<Device*>& devices) override;
  void EncodeState(double seq, double t, std::uint32_t endpoint_bits, std::vector<double>* scratch,
                   std::vector<unsigned char>* out) const override;
  std::string DescribeJson(const bridge::DeviceDescription& common) const override;
  CommandRole command_role() const override { return CommandRole::kRun; }
  bool TakeCommand(bridge::DeviceEndpoint& endpoint, std::vector<double>* scratch) override;
  double owner_timeout_s() const override { return owner_timeout_s_; }

 private:
  OnOwnerLost on_owner_lost_ = OnOwnerLost::kResume;
  double owner_timeout_s_ = 1.0;
  SimOps ops_ = SimOps::kDriver;
  long states_ = 0;                   // states set, i.e. published
  std::vector<std::string> devices_;  // every device of the scenario, in its order
  bridge::SimStateMsg state_;
  bridge::SimCommandMsg pending_;
  bool has_pending_ = false;
};

}  // namespace vlab::lab
