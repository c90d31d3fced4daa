#include "lab/run/lab_runner_impl.h"

#include <algorithm>

#include "core/core_errors.h"
#include "lab/devices/device_arm.h"

namespace vlab::lab {

void Lab::Impl::ResetData(mjData* d) const {
  if (keyframe < 0) {
    mj_resetData(model.get(), d);
  } else {
    mj_resetDataKeyframe(model.get(), d, keyframe);
    d->time = 0;  // the run's time starts at 0 whatever the keyframe's time
  }
  if (randomizer) randomizer->Apply(model.get(), d);
}

void Lab::Impl::ResetState() {
  mjData* d = data.get();
  ResetData(d);
  for (const auto& dev : devices) dev->SetInitialState(*d);
  mj_forward(model.get(), d);
  // the servos hold from the first instant: recompute forces with their torques,
  // so the sensors start settled on the load of an arm at rest
  for (auto& dev : devices) dev->Start(*d);
  mj_forward(model.get(), d);
  for (auto& dev : devices) dev->Reset(*d);
}

void Lab::Impl::WriteRow(double time_s, std::vector<double>& row) const {
  double* out = row.data();
  *out++ = time_s;
  for (const Device* dev : log_order) {
    dev->Row(*data, out);
    out += dev->ColumnCount();
  }
}

std::unique_ptr<LabBridge> Lab::Impl::MakeBridge(const BridgeOptions& options, const std::string& clock_name) {
  std::unique_ptr<LabBridge> bridge = LabBridge::Create(scenario, options, device_ptrs, clock_name);
  ClaimTable with_wire = claims;  // the lab's own claims stay as they are for the next bridge
  with_wire.Add(*bridge);
  return bridge;
}

void Lab::Impl::ClaimDriven() {
  for (Device* device : device_ptrs) {
    CommandWriter* writer = device->command_writer();
    if (!writer) continue;
    claims.Add(*writer);
    // an arm another device drives: lockstep does not wait for the arm's own clients
    for (const Claim& claim : writer->Claims()) {
      for (Device* driven : device_ptrs) {
        if (driven->name() == claim.device && driven->arm()) driven->arm()->set_driver(device->name());
      }
    }
  }
}

bool Lab::Impl::HandleSimCommands(LabBridge& bridge, Clock& clock, bool* paused, long* steps_left) {
  bool changed = false;
  bridge::SimCommandMsg c;
  while (sim && bridge.TakeCommand(*sim) && sim->TakeOp(&c)) {
    changed = true;
    switch (static_cast<bridge::SimOp>(c.op)) {
      case bridge::SimOp::kReset:
        ResetState();
        break;
      case bridge::SimOp::kPause:
        *paused = true;
        *steps_left = -1;
        break;
      case bridge::SimOp::kResume:
        *paused = false;
        *steps_left = -1;
        clock.set_factor(clock.factor());  // realtime: pace from now, no catch-up burst
        break;
      case bridge::SimOp::kStep:
        *paused = false;
        *steps_left = static_cast<long>(c.arg);
        clock.set_factor(clock.factor());
        break;
      case bridge::SimOp::kSetRealtimeFactor:
        clock.set_factor(c.arg);
        break;
    }
  }
  return changed;
}

}  // namespace vlab::lab
