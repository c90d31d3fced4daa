#include "lab/run/lab_bridge.h"

#include <sched.h>

#include <sys/socket.h>

#include <algorithm>
#include <cmath>

#include "bridge/bridge_describe.h"
#include "bridge/bridge_errors.h"
#include "core/core_errors.h"
#include "core/core_mujoco.h"
#include "lab/devices/device_sim.h"

namespace vlab::lab {

namespace {

// how long Poll spins before it sleeps, s
constexpr double kSpinSeconds = 200e-6;
// at most this many devices are served on endpoints of their own
constexpr std::size_t kMaxServed = 16;
// receive buffer asked for per device socket (the kernel caps it at net.core.rmem_max unless privileged)
constexpr int kReceiveBufferBytes = 4 << 20;

// the commands of this role go through ApplyCommands, and its owner is released on lockstep timeouts
bool Applied(CommandRole role) {
  return role == CommandRole::kWaited || role == CommandRole::kWaitedFromStart || role == CommandRole::kDriven;
}

}  // namespace

LabBridge::~LabBridge() {
  for (Served& d : devices_) {
    if (OwnTransport* t = d.device->own_transport()) t->Unserve();
  }
}

std::unique_ptr<LabBridge> LabBridge::Create(const Scenario& scenario, const BridgeOptions& options,
                                             const std::vector<Device*>& devices, const std::string& clock_name) {
  std::unique_ptr<LabBridge> b(new LabBridge());
  const double control_hz = 1.0 / scenario.control_period_s;
  if (options.max_subscribers < 1) {
    throw InputError("--subscribers " + std::to_string(options.max_subscribers) + ": must be at least 1");
  }
  for (const auto& [name, port] : options.ports) {
    // (a lambda captures a structured binding only from C++20: capture a reference to it)
    const std::string& wanted = name;
    const bool known =
        std::any_of(devices.begin(), devices.end(), [&wanted](const Device* d) { return d->name() == wanted; });
    if (!known)
      throw InputError("--port " + name + "=" + std::to_string(port) + ": the scenario has no device '" + name + "'");
  }
  const std::string server = options.server + " (MuJoCo " + MujocoVersion() + ")";
  b->devices_.reserve(devices.size());
  std::size_t endpoints = 0;
  for (std::size_t i = 0; i < devices.size(); ++i) {
    Device* device = devices[i];
    const DeviceConfig& c = scenario.devices[i];
    const auto override_port = options.ports.find(device->name());
    if (override_port == options.ports.end() && c.port == 0) continue;
    const int port = override_port != options.ports.end() ? override_port->second : c.port == kAutoPort ? 0 : c.port;
    Served d;
    d.device = device;
    if (OwnTransport* t = device->own_transport()) {  // unserved again by ~LabBridge
      t->Serve(options.bind, port, server, clock_name);
      b->fds_.push_back(t->fd());
      b->devices_.push_back(std::move(d));
      continue;
    }
    try {
      d.socket = bridge::UdpSocket::Bind(options.bind, port);
    } catch (const bridge::NetworkError& e) {
      throw InputError(c.where + ": device '" + c.name + "': " + e.what());
    }
    // room for a burst (a flood, or the lab descheduled for a while) before the kernel drops datagrams
    bridge::SetSocketBuffer(d.socket->fd(), SO_RCVBUF, kReceiveBufferBytes);
    bridge::EndpointConfig ec;
    ec.name = device->name();
    device->ConfigureEndpoint(control_hz, &ec);
    ec.max_subscribers = options.max_subscribers;
    const SimControl* sim = device->sim_control();
    if (sim && sim->ops() == SimOps::kDriver) {
      ec.gate = [self = b.get()](const bridge::Endpoint& from) { return self->SimGate(from); };
    }
    const bridge::DeviceDescription common{device->name(),         server,    clock_name, options.bind,
                                           d.socket->local_port(), control_hz};
    ec.describe_json = device->DescribeJson(common);
    d.endpoint = std::make_unique<bridge::DeviceEndpoint>(ec);
    b->fds_.push_back(d.socket->fd());
    b->devices_.push_back(std::move(d));
    ++endpoints;
  }
  if (endpoints > kMaxServed) throw InputError(scenario.file + ": at most 16 devices can be served");
  b->buffer_.resize(65536);
  b->payload_.reserve(bridge::kMaxPacketValues);
  b->latencies_.reserve(1 << 20);
  b->command_ages_.reserve(1 << 20);
  for (Served& d : b->devices_) d.last_state.reserve(bridge::kMaxPacketValues * sizeof(double));
  return b;
}

void LabBridge::Receive(Served& d) {
  if (OwnTransport* t = d.device->own_transport()) {
    t->PollRequests();  // describe replies while lockstep waits
    return;
  }
  bridge::Endpoint from;
  for (;;) {
    const long n = d.socket->Receive(buffer_.data(), buffer_.size(), &from, 0.0);
    if (n < 0) return;
    using Received = bridge::DeviceEndpoint::Received;
    const Received what = d.endpoint->Handle(buffer_.data(), static_cast<std::size_t>(n), from, period_, *d.socket);
    if (what == Received::kCommand) d.command_arrival = WallNow();
    // a new subscriber gets the latest state at once (it may be what lockstep waits on)
    if (what == Received::kSubscribed) d.endpoint->SendLatest(d.last_state, from, *d.socket);
  }
}

void LabBridge::ReceiveAll() {
  for (Served& d : devices_) {
    if (!d.device->own_transport()) Receive(d);
  }
  for (Served& d : devices_) {
    if (d.device->own_transport()) Receive(d);
  }
}

LabBridge::Served* LabBridge::Find(const Device& device) {
  for (Served& d : devices_) {
    if (d.device == &device) return &d;
  }
  return nullptr;
}

const LabBridge::Served* LabBridge::Find(const Device& device) const {
  for (const Served& d : devices_) {
    if (d.device == &device) return &d;
  }
  return nullptr;
}

bridge::CommandGate LabBridge::SimGate(const bridge::Endpoint& from) const {
  // driven: a commanded device (other than the sim) has an owner; then only such owners operate the sim
  bool driven = false;
  for (const Served& d : devices_) {
    if (!d.endpoint || !Applied(d.device->command_role())) continue;
    const std::optional<bridge::Endpoint>& owner = d.endpoint->owner();
    if (!owner) continue;
    if (*owner == from) return bridge::CommandGate::kTakeOver;
    driven = true;
  }
  return driven ? bridge::CommandGate::kRefuse : bridge::CommandGate::kOpen;
}

bool LabBridge::HasOwner(const Device& device) const {
  const Served* d = Find(device);
  return d && d->endpoint && d->endpoint->has_owner();
}

void LabBridge::WatchPeerExit(int fd, bool ends_run) {
  peer_exit_fd_ = fd;
  peer_ends_run_ = ends_run;
  fds_.push_back(fd);
}

void LabBridge::CheckPeerExit() {
  if (peer_gone_ || peer_exit_fd_ < 0 || !bridge::WaitReadable(&peer_exit_fd_, 1, 0.0)) return;
  peer_gone_ = true;  // end of file: it stays readable, so stop waiting on it
  fds_.erase(std::remove(fds_.begin(), fds_.end(), peer_exit_fd_), fds_.end());
}

void LabBridge::Poll(double timeout_s, PollWait wait) {
  if (fds_.empty()) return;
  // kSpin: briefly first, as an answer usually comes within tens of microseconds,
  // and a sleeping thread's wake-up costs about as much again (core_clock.h)
  const double spin_s = wait == PollWait::kSpin ? std::min(timeout_s, kSpinSeconds) : 0.0;
  const double spin_until = WallNow() + spin_s;
  for (;;) {
    if (bridge::WaitReadable(fds_.data(), static_cast<int>(fds_.size()), 0.0)) {
      ReceiveAll();
      CheckPeerExit();
      return;
    }
    if (WallNow() >= spin_until) break;
    ::sched_yield();  // a controller on this core runs at once (it polls too)
  }
  const double left = timeout_s - spin_s;
  if (left <= 0 || !bridge::WaitReadable(fds_.data(), static_cast<int>(fds_.size()), left)) return;
  ReceiveAll();
  CheckPeerExit();
}

bool LabBridge::Answered(std::int64_t k) const {
  if (peer_gone_) return true;  // the controller vlab run started has exited: nobody to wait for
  return CommandsAnswer(k);
}

bool LabBridge::GoneWithoutAnswering(std::int64_t k) {
  if (!peer_gone_) return false;
  ReceiveAll();  // what it sent before it exited (the clock may have seen its exit first)
  return !CommandsAnswer(k);
}

bool LabBridge::CommandsAnswer(std::int64_t k) const {
  return peer_ends_run_ && k > 0 ? AnsweredByPeer(k) : AllAnswered(k);
}

bool LabBridge::AnsweredByPeer(std::int64_t k) const {
  // A program sends its commands of a period before it unsubscribes, and a socket keeps their
  // order: once no owner is left, every command it sent is in, and the newest says whether it
  // answered k. So the unsubscribes and the exit end the run at the same period every run.
  bool any_owner = false;
  double newest = -1;
  for (const Served& d : devices_) {
    if (!d.endpoint) continue;
    const CommandRole role = d.device->command_role();
    if (role != CommandRole::kWaitedFromStart && role != CommandRole::kWaited) continue;
    if (d.endpoint->has_owner()) {
      any_owner = true;
      if (d.endpoint->last_accepted_seq() < static_cast<double>(k)) return false;
    }
    newest = std::max(newest, d.endpoint->newest_accepted_seq());
  }
  return any_owner || newest >= static_cast<double>(k);
}

bool LabBridge::AllAnswered(std::int64_t k) const {
  // every waited-for device that has an owner is waited for; period 0 also waits
  // for a controller to start: one per served arm, or, where no arm is served,
  // one for any commanded device (one that left was released: the device holds)
  bool any_from_start = false, any_owner = false, any_waited = false;
  for (const Served& d : devices_) {
    if (!d.endpoint) continue;
    const CommandRole role = d.device->command_role();
    const bool from_start = role == CommandRole::kWaitedFromStart;
    if (!from_start && role != CommandRole::kWaited) continue;
    any_from_start = any_from_start || from_start;
    any_waited = true;
    any_owner = any_owner || d.endpoint->has_owner();
    if (k == 0 && from_start && !d.endpoint->has_owner()) return false;
    if (d.endpoint->has_owner() && d.endpoint->last_accepted_seq() < static_cast<double>(k)) return false;
  }
  return !(k == 0 && !any_from_start && any_waited && !any_owner);
}

void LabBridge::ApplyCommands(std::int64_t k, double pace_s) {
  period_ = k;
  ReceiveAll();  // what came since the clock's last poll
  const double now = WallNow();
  for (Served& d : devices_) {
    if (!d.endpoint || !Applied(d.device->command_role())) continue;
    // how old the newest command is as the period starts: a stalled controller shows here
    if (d.endpoint->has_owner() && d.command_arrival >= 0 && command_ages_.size() < command_ages_.capacity()) {
      command_ages_.push_back(now - d.command_arrival);
    }
    CommandInput& input = *d.device->command_input();  // (a role that is applied has one)
    if (d.endpoint->BeginPeriod(k, pace_s)) input.Hold();
    if (input.TakeCommand(*d.endpoint, &payload_) && d.command_arrival >= 0 &&
        latencies_.size() < latencies_.capacity()) {
      latencies_.push_back(now - d.command_arrival);
    }
  }
}

std::vector<Claim> LabBridge::Claims() const {
  // every served device that takes commands, but one whose claim another source holds (kDriven)
  std::vector<Claim> claims;
  for (const Served& d : devices_) {
    const CommandRole role = d.device->command_role();
    if (!d.endpoint || role == CommandRole::kNone || role == CommandRole::kDriven) continue;
    claims.push_back({d.device->name(), "the UDP clients of its port", d.device->where()});
  }
  return claims;
}

bool LabBridge::Write(const CommandPeriod& period, std::string* failure) {
  (void)failure;
  ApplyCommands(period.k, period.pace_s);
  return true;
}

bool LabBridge::TakeCommand(Device& device) {
  Served* d = Find(device);
  return d && d->endpoint && device.command_input() && device.command_input()->TakeCommand(*d->endpoint, &payload_);
}

bool LabBridge::ReleaseSilentOwner(const Device& device) {
  Served* d = Find(device);
  if (!d || !d->endpoint) return false;
  if (d->endpoint->ReleaseSilentOwner()) return true;
  // an owner the gate now refuses (a controller drives, and it is none of the drivers) is owner no more
  const std::optional<bridge::Endpoint>& owner = d->endpoint->owner();
  const auto& gate = d->endpoint->config().gate;
  if (!owner || !gate || gate(*owner) != bridge::CommandGate::kRefuse) return false;
  d->endpoint->ReleaseOwner();
  return true;
}

void LabBridge::NoteTimeout(int release_after) {
  if (++consecutive_timeouts_ < release_after) return;
  for (Served& d : devices_) {
    if (d.endpoint && Applied(d.device->command_role())) d.endpoint->ReleaseOwner();
  }
}

void LabBridge::Publish(std::int64_t k, double t) {
  const double seq = static_cast<double>(k);
  for (Served& d : devices_) {
    if (!d.endpoint || !d.device->PublishDue()) continue;
    d.device->EncodeState(seq, t, d.endpoint->status_bits(), &payload_, &d.last_state);
    d.endpoint->Publish(d.last_state, *d.socket);
  }
}

long LabBridge::refused_total() const {
  long n = 0;
  for (const Served& d : devices_) {
    if (d.endpoint) n += d.endpoint->counters().refused;
  }
  return n;
}

std::vector<ServedDevice> LabBridge::Devices() const {
  std::vector<ServedDevice> out;
  for (const Served& d : devices_) {
    const char* kind = bridge::KindName(static_cast<int>(d.device->kind()));
    if (const OwnTransport* t = d.device->own_transport()) {
      out.push_back({d.device->name(), kind, t->address(), t->port(), t->describe_json(), t->counters(), t->frames()});
    } else {
      out.push_back({d.device->name(),
                     kind,
                     d.socket->local_endpoint().address().to_string(),
                     d.socket->local_port(),
                     d.endpoint->describe_json(),
                     d.endpoint->counters(),
                     {}});
    }
  }
  return out;
}

}  // namespace vlab::lab
