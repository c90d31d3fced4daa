#include "lab/lab_bridge.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "bridge/bridge_describe.h"
#include "bridge/bridge_errors.h"
#include "core/core_errors.h"
#include "core/core_mujoco.h"

namespace vlab::lab {

namespace {

// how long Poll spins before it sleeps, s
constexpr double kSpinSeconds = 200e-6;

std::vector<double> ToVector(const Eigen::VectorXd& v, bool keep_infinite = false) {
  std::vector<double> out;
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    if (!keep_infinite && !std::isfinite(v[i])) return {};  // unlimited: no limit of that kind
    out.push_back(v[i]);
  }
  return out;
}

std::vector<double> TorqueMax(const SimArm& arm) {
  std::vector<double> out;
  for (int i = 0; i < arm.dof(); ++i) {
    const double m = std::min(std::abs(arm.torque_min()[i]), std::abs(arm.torque_max()[i]));
    if (!std::isfinite(m)) return {};
    out.push_back(m);
  }
  return out;
}

}  // namespace

std::unique_ptr<LabBridge> LabBridge::Create(const Scenario& scenario, const BridgeOptions& options,
                                             const std::vector<SimArm*>& arms, const std::vector<SimWrench*>& wrenches,
                                             const std::vector<SimDevice*>& devices, const std::string& clock_name) {
  std::unique_ptr<LabBridge> b(new LabBridge());
  const double control_hz = 1.0 / scenario.control_period_s;
  std::vector<std::string> names;
  for (const DeviceConfig& c : scenario.devices) names.push_back(c.name);
  for (const auto& [name, port] : options.ports) {
    if (std::find(names.begin(), names.end(), name) == names.end()) {
      throw InputError("--port " + name + "=" + std::to_string(port) + ": the scenario has no device '" + name + "'");
    }
  }
  b->devices_.reserve(scenario.devices.size());
  for (const DeviceConfig& c : scenario.devices) {
    const auto override_port = options.ports.find(c.name);
    const bool served = override_port != options.ports.end() || c.port > 0;
    if (!served || c.kind == "camera") continue;  // cameras: their own server (chunked frames)
    const int port = override_port != options.ports.end() ? override_port->second : c.port;
    Served d;
    d.name = c.name;
    try {
      d.socket = bridge::UdpSocket::Bind(options.bind, port);
    } catch (const bridge::NetworkError& e) {
      throw InputError(c.where + ": device '" + c.name + "': " + e.what());
    }
    bridge::EndpointConfig ec;
    ec.name = c.name;
    const int owner_periods = static_cast<int>(std::lround(c.arm.owner_timeout_s * control_hz));
    ec.owner_timeout_periods = std::max(1, owner_periods);
    ec.subscriber_timeout_periods = static_cast<int>(std::lround(10.0 * control_hz));
    const bridge::DeviceDescription common{c.name, options.server + " (MuJoCo " + MujocoVersion() + ")", clock_name,
                                           options.bind, d.socket->local_port(), control_hz};
    if (c.kind == "arm") {
      SimArm* arm = nullptr;
      for (std::size_t i = 0; i < arms.size(); ++i) {
        if (arms[i]->name() == c.name) {
          arm = arms[i];
          d.arm_index = static_cast<int>(i);
        }
      }
      d.arm = arm;
      for (const DeviceConfig& p : scenario.devices) d.driven = d.driven || (p.kind == "point" && p.point.arm == c.name);
      d.kind = bridge::DeviceKind::kArm;
      ec.kind = d.kind;
      ec.joints = arm->dof();
      ec.position_min = ToVector(arm->lower_limits(), true);
      ec.position_max = ToVector(arm->upper_limits(), true);
      ec.velocity_max = ToVector(arm->max_velocity());
      ec.torque_max = TorqueMax(*arm);
      ec.watchdog_periods = arm->watchdog_periods();
      bridge::ArmDescription desc;
      desc.joints = arm->joint_names();
      desc.position_min = ToVector(arm->lower_limits());
      desc.position_max = ToVector(arm->upper_limits());
      desc.velocity_max = ec.velocity_max;
      desc.torque_max = ec.torque_max;
      desc.watchdog_periods = ec.watchdog_periods;
      desc.owner_timeout_s = c.arm.owner_timeout_s;
      static_cast<bridge::DeviceDescription&>(desc) = common;
      ec.describe_json = bridge::DescribeJson(desc);
    } else if (c.kind == "wrench") {
      SimWrench* w = nullptr;
      for (SimWrench* x : wrenches) w = x->name() == c.name ? x : w;
      d.wrench = w;
      d.kind = bridge::DeviceKind::kWrench;
      ec.kind = d.kind;
      bridge::WrenchDescription desc;
      desc.sensor_model = w->sensor().model_name();
      desc.full_scale.assign(w->sensor().full_scale().data(), w->sensor().full_scale().data() + 6);
      desc.filter = w->sensor().filter();
      desc.filter_cutoff_hz = desc.filter > 0 ? w->sensor().stage(desc.filter).cutoff_hz : 0.0;
      desc.sample_hz = w->sensor().sample_rate_hz();
      static_cast<bridge::DeviceDescription&>(desc) = common;
      ec.describe_json = bridge::DescribeJson(desc);
    } else if (IsSimDeviceKind(c.kind)) {
      for (SimDevice* x : devices) d.device = x->name() == c.name ? x : d.device;
      d.kind = d.device->kind();
      ec.kind = d.kind;
      ec.command_length = d.device->command_length();
      if (ec.command_length > 0) {
        SimDevice* device = d.device;
        ec.check_command = [device](const std::vector<double>& p) { return device->CheckCommand(p); };
        ec.status_first = true;
        ec.watchdog_periods = device->watchdog_periods();
        ec.owner_timeout_periods = std::max(1, static_cast<int>(std::lround(device->owner_timeout_s() * control_hz)));
      }
      ec.describe_json = bridge::DescribeJson(common, c.kind, d.device->DescribeFacts());
    } else {
      d.kind = bridge::DeviceKind::kSim;
      ec.kind = d.kind;
      bridge::SimDescription desc;
      desc.devices = names;
      static_cast<bridge::DeviceDescription&>(desc) = common;
      ec.describe_json = bridge::DescribeJson(desc);
    }
    d.endpoint = std::make_unique<bridge::DeviceEndpoint>(ec);
    b->fds_.push_back(d.socket->fd());
    b->devices_.push_back(std::move(d));
  }
  for (Served& d : b->devices_) {
    if (d.kind == bridge::DeviceKind::kSim) b->sim_ = &d;
  }
  if (b->devices_.size() > 16) throw InputError(scenario.file + ": at most 16 devices can be served");
  b->buffer_.resize(65536);
  b->payload_.reserve(bridge::kMaxPacketValues);
  b->packet_.reserve(bridge::kMaxPacketValues * sizeof(double));
  b->latencies_.reserve(1 << 20);
  return b;
}

void LabBridge::Receive(Served& d) {
  bridge::Endpoint from;
  for (;;) {
    const long n = d.socket->Receive(buffer_.data(), buffer_.size(), &from, 0.0);
    if (n < 0) return;
    const long describes = d.endpoint->counters().describes;
    const bool command = d.endpoint->Handle(buffer_.data(), static_cast<std::size_t>(n), from, period_, *d.socket);
    if (command) d.command_arrival = WallNow();
    // a new subscriber gets the latest state at once (it may be what lockstep waits on)
    if (d.endpoint->counters().describes != describes && !d.last_state.empty()) {
      d.socket->SendTo(d.last_state.data(), d.last_state.size(), from);
    }
  }
}

void LabBridge::WatchPeerExit(int fd) {
  peer_exit_fd_ = fd;
  fds_.push_back(fd);
}

void LabBridge::AddPollable(int fd, std::function<void()> on_readable) {
  fds_.push_back(fd);
  pollables_.push_back(std::move(on_readable));
}

void LabBridge::CheckPeerExit() {
  if (peer_gone_ || peer_exit_fd_ < 0 || !bridge::WaitReadable(&peer_exit_fd_, 1, 0.0)) return;
  peer_gone_ = true;  // end of file: it stays readable, so stop waiting on it
  fds_.erase(std::remove(fds_.begin(), fds_.end(), peer_exit_fd_), fds_.end());
}

void LabBridge::Poll(double timeout_s) {
  if (fds_.empty()) return;
  // spin briefly first: an answer usually comes within tens of microseconds, and
  // a sleeping thread's wake-up costs about as much again
  const double spin_until = WallNow() + std::min(timeout_s, kSpinSeconds);
  do {
    if (bridge::WaitReadable(fds_.data(), static_cast<int>(fds_.size()), 0.0)) {
      for (Served& d : devices_) Receive(d);
      for (auto& poll : pollables_) poll();
      CheckPeerExit();
      return;
    }
  } while (WallNow() < spin_until);
  const double left = timeout_s - kSpinSeconds;
  if (left <= 0 || !bridge::WaitReadable(fds_.data(), static_cast<int>(fds_.size()), left)) return;
  for (Served& d : devices_) Receive(d);
  for (auto& poll : pollables_) poll();
  CheckPeerExit();
}

bool LabBridge::Answered(std::int64_t k) const {
  if (peer_gone_) return true;  // the controller vlab run started has exited: nobody to wait for
  // every commanded device that has an owner is waited for; period 0 also waits
  // for a controller to start: one per served arm, or, where no arm is served,
  // one for any commanded device (one that left was released: the device holds)
  bool any_arm = false, any_owner = false, any_commanded = false;
  for (const Served& d : devices_) {
    const bool arm = d.kind == bridge::DeviceKind::kArm && !d.driven;  // a driven arm: its point device is waited for
    const bool commanded = arm || (d.device && d.device->command_length() > 0);
    if (!commanded) continue;
    any_arm = any_arm || arm;
    any_commanded = true;
    any_owner = any_owner || d.endpoint->has_owner();
    if (k == 0 && arm && !d.endpoint->has_owner()) return false;
    if (d.endpoint->has_owner() && d.endpoint->last_accepted_seq() < static_cast<double>(k)) return false;
  }
  return !(k == 0 && !any_arm && any_commanded && !any_owner);
}

void LabBridge::ApplyArmCommands(std::int64_t k) {
  period_ = k;
  for (Served& d : devices_) Receive(d);  // what came since the clock's last poll
  const double now = WallNow();
  for (Served& d : devices_) {
    if (d.device && d.device->command_length() > 0) {
      if (d.endpoint->BeginPeriod(k)) d.device->Hold();
      if (d.endpoint->TakeCommand(&payload_)) d.device->Command(payload_);
    }
    if (d.kind != bridge::DeviceKind::kArm) continue;
    if (d.endpoint->BeginPeriod(k)) {
      command_.mode = bridge::ArmMode::kHold;
      d.arm->Command(command_);
    }
    if (d.endpoint->TakeArmCommand(&arm_command_)) {
      command_.mode = static_cast<bridge::ArmMode>(arm_command_.mode);
      command_.value = Eigen::Map<const Eigen::VectorXd>(arm_command_.value.data(),
                                                         static_cast<Eigen::Index>(arm_command_.value.size()));
      d.arm->Command(command_);
      if (d.command_arrival >= 0 && latencies_.size() < latencies_.capacity()) {
        latencies_.push_back(now - d.command_arrival);
      }
    }
  }
}

bool LabBridge::TakeSimCommand(bridge::SimCommandMsg* command) {
  return sim_ && sim_->endpoint->TakeSimCommand(command);
}

void LabBridge::NoteTimeout(int release_after) {
  if (++consecutive_timeouts_ < release_after) return;
  for (Served& d : devices_) {
    if (d.kind == bridge::DeviceKind::kArm || (d.device && d.device->command_length() > 0)) d.endpoint->ReleaseOwner();
  }
}

void LabBridge::Publish(std::int64_t k, double t, const std::vector<bridge::ArmState>& arm_states,
                        const bridge::SimStateMsg& sim_state) {
  const double seq = static_cast<double>(k);
  for (Served& d : devices_) {
    if (d.kind == bridge::DeviceKind::kArm) {
      const bridge::ArmState& st = arm_states[d.arm_index];
      arm_msg_.status = st.status | d.endpoint->status_bits();
      arm_msg_.q.assign(st.q.data(), st.q.data() + st.q.size());
      arm_msg_.qd.assign(st.qd.data(), st.qd.data() + st.qd.size());
      arm_msg_.tau.assign(st.tau.data(), st.tau.data() + st.tau.size());
      bridge::EncodeArmState(seq, t, arm_msg_, &d.last_state);
    } else if (d.kind == bridge::DeviceKind::kWrench) {
      bridge::WrenchState w;
      d.wrench->Sample(t, &w);
      bridge::WrenchStateMsg m;
      for (int i = 0; i < 6; ++i) m.wrench[i] = w.wrench[i];
      m.filter = w.filter;
      m.saturated = w.saturated;
      bridge::EncodeWrenchState(seq, t, m, &d.last_state);
    } else if (d.device) {
      d.device->State(&payload_);
      bridge::Header h;
      h.kind = static_cast<int>(d.kind);
      h.type = static_cast<int>(bridge::MessageType::kState);
      h.seq = seq;
      h.time = t;
      h.length = static_cast<int>(payload_.size());
      bridge::EncodePacket(h, payload_.data(), h.length, &d.last_state);
    } else {
      bridge::EncodeSimState(seq, t, sim_state, &d.last_state);
    }
    d.endpoint->Publish(d.last_state, *d.socket);
  }
}

long LabBridge::refused_total() const {
  long n = 0;
  for (const Served& d : devices_) n += d.endpoint->counters().refused;
  return n;
}

std::vector<ServedDevice> LabBridge::Devices() const {
  std::vector<ServedDevice> out;
  for (const Served& d : devices_) {
    out.push_back({d.name, bridge::KindName(static_cast<int>(d.kind)), d.socket->local_endpoint().address().to_string(),
                   d.socket->local_port(), d.endpoint->config().describe_json, d.endpoint->counters()});
  }
  return out;
}

}  // namespace vlab::lab
