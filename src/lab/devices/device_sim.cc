#include "lab/devices/device_sim.h"

#include "bridge/bridge_describe.h"
#include "lab/scenario/lab_yaml.h"

namespace vlab::lab {

std::shared_ptr<const DeviceParams> ReadSimParams(MapReader& r) {
  auto p = std::make_shared<SimParams>();
  const std::string lost = r.String("on_owner_lost", "resume");
  if (lost == "resume") {
    p->on_owner_lost = OnOwnerLost::kResume;
  } else if (lost == "stay_paused") {
    p->on_owner_lost = OnOwnerLost::kStayPaused;
  } else {
    r.Fail("on_owner_lost", "must be resume or stay_paused, not '" + lost + "'");
  }
  const std::string ops = r.String("ops_from", "driver");
  if (ops == "driver") {
    p->ops = SimOps::kDriver;
  } else if (ops == "anyone") {
    p->ops = SimOps::kAnyone;
  } else {
    r.Fail("ops_from", "must be driver or anyone, not '" + ops + "'");
  }
  p->owner_timeout_s = r.Number("owner_timeout", p->owner_timeout_s);
  if (!(p->owner_timeout_s > 0) || p->owner_timeout_s > 3600) r.Fail("owner_timeout", "must be > 0 and <= 3600 s");
  return p;
}

std::unique_ptr<Device> MakeSim(const DeviceContext&, const DeviceConfig& config) {
  return std::make_unique<SimControl>(config);
}

SimControl::SimControl(const DeviceConfig& config) : Device(config) {
  const SimParams& p = config.ParamsAs<SimParams>();
  on_owner_lost_ = p.on_owner_lost;
  owner_timeout_s_ = p.owner_timeout_s;
  ops_ = p.ops;
  capabilities_.command_input = this;
  capabilities_.sim_control = this;
}

void SimControl::Bind(const std::vector<Device*>& devices) {
  devices_.clear();
  for (const Device* d : devices) devices_.push_back(d->name());
}

bool SimControl::TakeOp(bridge::SimCommandMsg* command) {
  if (!has_pending_) return false;
  *command = pending_;
  has_pending_ = false;
  return true;
}

void SimControl::EncodeState(double, double t, std::uint32_t, std::vector<double>*,
                             std::vector<unsigned char>* out) const {
  bridge::EncodeSimState(static_cast<double>(states_ - 1), t, state_, out);
}

std::string SimControl::DescribeJson(const bridge::DeviceDescription& common) const {
  bridge::SimDescription desc;
  static_cast<bridge::DeviceDescription&>(desc) = common;
  desc.devices = devices_;
  desc.owner_timeout_s = owner_timeout_s_;
  desc.on_owner_lost = on_owner_lost_ == OnOwnerLost::kResume ? "resume" : "stay_paused";
  desc.ops_from = ops_ == SimOps::kDriver ? "driver" : "anyone";
  return bridge::DescribeJson(desc);
}

bool SimControl::TakeCommand(bridge::DeviceEndpoint& endpoint, std::vector<double>*) {
  if (!endpoint.TakeSimCommand(&pending_)) return false;
  has_pending_ = true;
  return true;
}

}  // namespace vlab::lab
