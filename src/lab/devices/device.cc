#include "lab/devices/device.h"

#include <algorithm>
#include <cmath>

#include "bridge/bridge_describe.h"
#include "bridge/bridge_layouts.h"
#include "lab/scenario/lab_yaml.h"

namespace vlab::lab {

// the commanded kinds served through this generic path start their state with the status word
static_assert(bridge::StateIndex(bridge::DeviceKind::kBase, "status") == 0 &&
                  bridge::StateIndex(bridge::DeviceKind::kGripper, "status") == 0 &&
                  bridge::StateIndex(bridge::DeviceKind::kPoint, "status") == 0,
              "status word first");

void ReadCommandInput(MapReader& r, CommandInputConfig* input) {
  input->watchdog_periods = r.Integer("watchdog_periods", input->watchdog_periods);
  if (input->watchdog_periods < 0) r.Fail("watchdog_periods", "must be >= 0 (0: off)");
  input->owner_timeout_s = r.Number("owner_timeout", input->owner_timeout_s);
  if (!(input->owner_timeout_s > 0)) r.Fail("owner_timeout", "must be > 0 s");
}

void Device::EncodeState(double seq, double t, std::uint32_t endpoint_bits, std::vector<double>* scratch,
                         std::vector<unsigned char>* out) const {
  State(scratch);
  // a commanded kind's state starts with its status word: the endpoint's bits (refused, watchdog) join it
  if (command_input() && command_input()->command_length() > 0 && endpoint_bits != 0 && !scratch->empty()) {
    const double word = (*scratch)[0];
    const std::uint32_t own = word >= 0 && word <= 4294967295.0 ? static_cast<std::uint32_t>(word) : 0;
    (*scratch)[0] = static_cast<double>(own | endpoint_bits);
  }
  bridge::Header h;
  h.kind = static_cast<int>(kind());
  h.type = static_cast<int>(bridge::MessageType::kState);
  h.seq = seq;
  h.time = t;
  h.length = static_cast<int>(scratch->size());
  bridge::EncodePacket(h, scratch->data(), h.length, out);
}

void Device::ConfigureEndpoint(double control_hz, bridge::EndpointConfig* ec) const {
  ec->kind = kind();
  (void)control_hz;
  const CommandInput* input = command_input();
  ec->owner_timeout_s = input ? input->owner_timeout_s() : 1.0;
  ec->command_length = input ? input->command_length() : 0;
  if (ec->command_length > 0) {
    ec->check_command = [input](const std::vector<double>& p) { return input->CheckCommand(p); };
    ec->status_first = true;
    ec->watchdog_periods = input->watchdog_periods();
  }
}

std::string Device::DescribeJson(const bridge::DeviceDescription& common) const {
  return bridge::DescribeJson(common, bridge::KindName(static_cast<int>(kind())), DescribeFacts());
}

bool CommandInput::TakeCommand(bridge::DeviceEndpoint& endpoint, std::vector<double>* scratch) {
  if (!endpoint.TakeCommand(scratch)) return false;
  Command(*scratch);
  return true;
}

}  // namespace vlab::lab
