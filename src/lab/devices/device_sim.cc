#include "lab/devices/device_sim.h"

#include "bridge/bridge_describe.h"

namespace vlab::lab {

std::shared_ptr<const DeviceParams> ReadSimParams(MapReader&) { return std::make_shared<SimParams>(); }

std::unique_ptr<Device> MakeSim(const DeviceContext&, const DeviceConfig& config) {
  return std::make_unique<SimControl>(config);
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

void SimControl::EncodeState(double seq, double t, std::uint32_t, std::vector<double>*,
                             std::vector<unsigned char>* out) const {
  bridge::EncodeSimState(seq, t, state_, out);
}

std::string SimControl::DescribeJson(const bridge::DeviceDescription& common) const {
  bridge::SimDescription desc;
  desc.devices = devices_;
  static_cast<bridge::DeviceDescription&>(desc) = common;
  return bridge::DescribeJson(desc);
}

bool SimControl::TakeCommand(bridge::DeviceEndpoint& endpoint, std::vector<double>*) {
  if (!endpoint.TakeSimCommand(&pending_)) return false;
  has_pending_ = true;
  return true;
}

}  // namespace vlab::lab
