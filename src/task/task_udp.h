// The task runtime's devices over UDP (docs/protocol.md): an arm, wrenches
// and any float64 device, through the C++ client (bridge/bridge_client.h).
// The same scripts as in process; only the transport differs.
//
// Ports
//   input   each device's states, the newest one per control period
//           (ReadLatest: in lockstep there is exactly one, in real time the
//           newest wins)
//   output  each command answers the arm's state of the period (its seq)
// Threading: one thread. Errors: Connect throws what the clients throw
// (NetworkError, TimeoutError, ProtocolError) and InputError for a bad
// ADDRESS:PORT.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "bridge/bridge_client.h"
#include "task/task_channel.h"

namespace vlab::task {

class UdpDevices final : public Devices {
 public:
  UdpDevices();
  ~UdpDevices() override;
  /// Connects to the arm at "HOST:PORT" (the clock of the loop: its states
  /// pace Receive); its name comes from its describe reply.
  void AddArm(const std::string& endpoint, double timeout_s);
  /// Connects to a device of `kind` ("wrench", "gripper", ... any float64
  /// kind, or "markers": a vision program, tried until timeout_s) at
  /// "HOST:PORT".
  void Add(const std::string& kind, const std::string& endpoint, double timeout_s);
  /// The devices' time of the runtime's time 0 (the arm's first state).
  void set_time_origin(double t_s);
  /// Whether the arm's describe reply says "clock": "realtime".
  bool realtime() const;

  /// Waits up to timeout_s for the arm's next state and takes the newest of
  /// every other device. Returns the arm state's time (s). Throws TimeoutError.
  double Receive(double timeout_s);
  /// The arm's control rate from its describe reply (Hz; 0 if absent).
  double control_hz() const;
  /// The arm's name.
  const std::string& arm_name() const;

  Channel* Find(const std::string& name) override;
  MarkerChannel* FindMarkers(const std::string& name) override;
  std::vector<std::string> Names() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// "HOST:PORT" -> host, port; throws InputError naming `what`.
void SplitEndpoint(const std::string& endpoint, const std::string& what, std::string* host, int* port);

}  // namespace vlab::task
