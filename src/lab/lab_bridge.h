// The lab's side of the wire: serves its devices over UDP under `vlab serve`.
//
// Ports (one UDP socket per served device, on the port its scenario gives)
//   input   arm commands, sim commands, describe requests (any time; received
//           while the clock waits, timestamped on arrival)
//   output  every control period: each served device's state to its
//           subscribers (arm: seq k = the state at t_k, sent as soon as it is
//           sampled); a new subscriber gets the latest state at once
// The rules of every device kind (owner, seq, limits, watchdog) are those of
// bridge::DeviceEndpoint, shared with every other server of the same kind.
#pragma once

#include <cstdint>
#include <map>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "bridge/bridge_endpoint.h"
#include "bridge/bridge_messages.h"
#include "bridge/bridge_udp.h"
#include "lab/lab_arm_device.h"
#include "core/core_clock.h"
#include "lab/lab_device.h"
#include "lab/lab_scenario.h"
#include "lab/lab_wrench_device.h"

namespace vlab::lab {

struct BridgeOptions {
  std::string bind = "127.0.0.1";    ///< address every device socket binds to
  std::map<std::string, int> ports;  ///< per-device port overrides (0: any free port)
  std::string server = "vlab serve";  ///< server name in describe replies
};

/// A served device's endpoint and counters, for summaries and `vlab devices`.
struct ServedDevice {
  std::string name;
  std::string kind;
  std::string address;
  int port = 0;
  std::string describe_json;
  bridge::EndpointCounters counters;
};

class LabBridge final : public CommandSource {
 public:
  /// Binds a socket for every device of the scenario with a port (or a port
  /// override). `arms`/`wrenches` are the lab's devices by scenario name.
  /// Throws InputError naming the device and address when a port cannot be bound.
  static std::unique_ptr<LabBridge> Create(const Scenario& scenario, const BridgeOptions& options,
                                           const std::vector<SimArm*>& arms, const std::vector<SimWrench*>& wrenches,
                                           const std::vector<SimDevice*>& devices, const std::string& clock_name);

  // CommandSource
  void Poll(double timeout_s) override;
  /// Lockstep: every served arm with an owner has a command answering k (for
  /// k = 0, every served arm has an owner: the run waits for its controllers).
  bool Answered(std::int64_t k) const override;

  /// Start of period k: the watchdog, then the newest accepted command of every
  /// served arm goes to its SimArm, and of every other commanded device to it
  /// (latency from arrival to now recorded for arms).
  void ApplyArmCommands(std::int64_t k);
  /// Also wait on fd, which becomes readable when the controller process
  /// that `vlab run` started has exited: from then on no period waits.
  void WatchPeerExit(int fd);
  /// Also wait on fd (a camera's socket) and call on_readable whenever the
  /// wait wakes up, so that such a device answers describe requests while
  /// lockstep waits for commands. on_readable must not block.
  void AddPollable(int fd, std::function<void()> on_readable);
  /// True once the watched controller process has exited.
  bool peer_gone() const { return peer_gone_; }
  /// The newest sim command since the last call, if any.
  bool TakeSimCommand(bridge::SimCommandMsg* command);
  /// Lockstep: period k began without the commands. After release_after such
  /// periods in a row, silent owners are released (a restarted controller can
  /// take over).
  void NoteTimeout(int release_after);
  void NoteAnswered() { consecutive_timeouts_ = 0; }

  /// Publishes the states of period k (time t) of every served device.
  void Publish(std::int64_t k, double t, const std::vector<bridge::ArmState>& arm_states,
               const bridge::SimStateMsg& sim_state);

  bool serves_sim() const { return sim_ != nullptr; }
  /// Refused datagrams over all served devices.
  long refused_total() const;
  std::vector<ServedDevice> Devices() const;
  /// Command arrival-to-apply latencies, s (arm commands applied so far).
  const std::vector<double>& latencies() const { return latencies_; }

 private:
  struct Served {
    std::string name;
    bridge::DeviceKind kind;
    std::unique_ptr<bridge::UdpSocket> socket;
    std::unique_ptr<bridge::DeviceEndpoint> endpoint;
    SimArm* arm = nullptr;
    bool driven = false;  // an arm a point device drives: its own commands are overridden, not waited for
    int arm_index = -1;  // in the lab's arm list (and its arm_states)
    SimWrench* wrench = nullptr;
    SimDevice* device = nullptr;  // base, feet, imu, ...
    std::vector<unsigned char> last_state;  // latest encoded state, for new subscribers
    double command_arrival = -1;            // wall time the pending command arrived
  };
  LabBridge() = default;
  void Receive(Served& d);

  std::vector<Served> devices_;
  Served* sim_ = nullptr;
  std::vector<int> fds_;
  std::vector<std::function<void()>> pollables_;
  int peer_exit_fd_ = -1;
  bool peer_gone_ = false;
  void CheckPeerExit();
  std::int64_t period_ = 0;
  int consecutive_timeouts_ = 0;
  std::vector<double> latencies_;
  // scratch, sized at creation
  std::vector<unsigned char> buffer_;
  std::vector<unsigned char> packet_;
  bridge::ArmStateMsg arm_msg_;
  bridge::ArmCommandMsg arm_command_;
  bridge::ArmCommand command_;
  std::vector<double> payload_;
};

}  // namespace vlab::lab
