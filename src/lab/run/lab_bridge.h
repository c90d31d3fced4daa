// The lab's side of the wire: serves its devices over UDP under `vlab serve`.
//
// Ports (one UDP socket per served device, on the port its scenario gives)
//   input   commands, describe and subscribe requests (any time; received while the clock
//           waits, timestamped on arrival)
//   output  every control period: each served device's state to its
//           subscribers (seq k = the state at t_k, sent as soon as it is
//           sampled); a new subscriber gets the latest state at once
// The bridge serves any device through the Device interface, with no branch
// on kind: the state, the command rules and the describe reply come from the
// device. The rules of every kind (owner, seq, limits, watchdog) are those of
// bridge::DeviceEndpoint, shared with every other server of the same kind. A
// device with its own transport (a camera: chunked frames) binds its socket
// here and is polled with the others, so it answers while lockstep waits.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "bridge/bridge_endpoint.h"
#include "bridge/bridge_messages.h"
#include "bridge/bridge_udp.h"
#include "core/core_clock.h"
#include "lab/devices/device.h"
#include "lab/run/lab_command_writer.h"
#include "lab/scenario/lab_scenario.h"

namespace vlab::lab {

struct BridgeOptions {
  std::string bind = "127.0.0.1";     ///< address every device socket binds to
  std::map<std::string, int> ports;   ///< per-device port overrides (0: any free port)
  std::string server = "vlab serve";  ///< server name in describe replies
  /// Subscribers each device endpoint keeps (`vlab serve --subscribers`), ≥ 1.
  int max_subscribers = bridge::kDefaultMaxSubscribers;
};

/// A served device's endpoint and counters, for summaries and `vlab devices`.
struct ServedDevice {
  std::string name;
  std::string kind;
  std::string address;
  int port = 0;
  std::string describe_json;
  bridge::EndpointCounters counters;
  FrameCounters frames;  ///< a camera's frames (zeros for other kinds)
};

/// The wire: the lab's UDP endpoints, what the clock polls while it waits
/// (vlab::CommandSource) and the command source of the served devices
/// (lab::CommandWriter).
class LabBridge final : public vlab::CommandSource, public CommandWriter {
 public:
  /// Binds a socket for every device with a port (or a port override), in
  /// scenario order, and makes each one's endpoint from the device's own rules
  /// (Device::ConfigureEndpoint, DescribeJson); a device with its own transport
  /// (a camera) binds its own socket here too. Throws InputError naming the
  /// device and address when a port cannot be bound.
  static std::unique_ptr<LabBridge> Create(const Scenario& scenario, const BridgeOptions& options,
                                           const std::vector<Device*>& devices, const std::string& clock_name);
  ~LabBridge() override;

  // CommandSource
  void Poll(double timeout_s, PollWait wait) override;
  /// Lockstep: every served device whose commands are waited for, and that has
  /// an owner, has a command answering k (for k = 0, every served arm has an
  /// owner: the run waits for its controllers).
  bool Answered(std::int64_t k) const override;

  // CommandWriter
  /// Every served device that takes commands, unless another source holds
  /// its claim (an arm under a point device: CommandRole::kDriven), claimed by
  /// "the UDP clients of its port".
  std::vector<Claim> Claims() const override;
  /// ApplyCommands(period.k, period.pace_s).
  bool Write(const CommandPeriod& period, std::string* failure) override;

  /// Start of period k: the watchdog, then the newest accepted command of every
  /// served commanded device goes to it (latency from arrival to now recorded).
  /// Devices of role kRun (sim) are left to TakeCommand. pace_s: wall seconds
  /// per period of a realtime clock (0 otherwise), for the watchdog.
  void ApplyCommands(std::int64_t k, double pace_s = 0);
  /// The newest accepted command of `device` (a served device), applied to it.
  /// False when none came.
  bool TakeCommand(Device& device);
  /// Releases the owner of `device` when it has been silent for its owner
  /// timeout (wall clock); true when it did. Publish does it for every
  /// device; the lab calls this while paused, when nothing is published.
  /// Also releases the sim's owner once the sim's gate refuses it (a
  /// controller drives now, and it is none of the drivers).
  bool ReleaseSilentOwner(const Device& device);
  /// True when a served `device` has an owner.
  bool HasOwner(const Device& device) const;
  /// Also wait on fd, which becomes readable when the controller process
  /// that `vlab run` started has exited: from then on no period waits.
  /// ends_run (controller.ends_run): it drives until it exits, so a period
  /// k > 0 waits for its commands also after it gave its devices up
  /// (unsubscribed): the run ends at the first period it left unanswered.
  void WatchPeerExit(int fd, bool ends_run = false);
  /// True once the watched controller process has exited.
  bool peer_gone() const { return peer_gone_; }
  /// True once the watched controller process has exited without answering
  /// period k: everything it sent before its exit is received first (a datagram
  /// sent on loopback is queued before its sender can exit).
  bool GoneWithoutAnswering(std::int64_t k);
  /// Lockstep: period k began without the commands. After release_after such
  /// periods in a row, silent owners are released (a restarted controller can
  /// take over).
  void NoteTimeout(int release_after);
  void NoteAnswered() { consecutive_timeouts_ = 0; }

  /// Publishes the states of period k (time t) of every served device.
  void Publish(std::int64_t k, double t);

  /// Refused datagrams over all served devices.
  long refused_total() const;
  /// Every served device, in scenario order.
  std::vector<ServedDevice> Devices() const;
  /// Command arrival-to-apply latencies, s (commands applied so far).
  const std::vector<double>& latencies() const { return latencies_; }
  /// Age of the newest command of each owned commanded device at the start of
  /// each period, s (wall time since it arrived; one value per device and period).
  const std::vector<double>& command_ages() const { return command_ages_; }

 private:
  struct Served {
    Device* device = nullptr;
    std::unique_ptr<bridge::UdpSocket> socket;         // null for a device with its own transport
    std::unique_ptr<bridge::DeviceEndpoint> endpoint;  // null for a device with its own transport
    std::vector<unsigned char> last_state;             // latest encoded state, for new subscribers
    double command_arrival = -1;                       // wall time the pending command arrived
  };
  LabBridge() = default;
  // Answered without the exited controller's exemption: AnsweredByPeer or AllAnswered
  bool CommandsAnswer(std::int64_t k) const;
  // every owner answered k; period 0 also waits for a controller to start
  bool AllAnswered(std::int64_t k) const;
  // ends_run, k > 0: every owner answered k; with no owner left, the newest command answered k
  bool AnsweredByPeer(std::int64_t k) const;
  void Receive(Served& d);
  void ReceiveAll();
  Served* Find(const Device& device);
  const Served* Find(const Device& device) const;
  // the sim's ops in a driven run: only a peer that owns a commanded device (docs/protocol.md)
  bridge::CommandGate SimGate(const bridge::Endpoint& from) const;

  std::vector<Served> devices_;
  std::vector<int> fds_;
  int peer_exit_fd_ = -1;
  bool peer_gone_ = false;
  bool peer_ends_run_ = false;
  void CheckPeerExit();
  std::int64_t period_ = 0;
  int consecutive_timeouts_ = 0;
  std::vector<double> latencies_;
  std::vector<double> command_ages_;
  // scratch, sized at creation
  std::vector<unsigned char> buffer_;
  std::vector<double> payload_;
};

}  // namespace vlab::lab
