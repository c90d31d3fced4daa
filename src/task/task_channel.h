// The runtime's view of a device: a name, a kind and float64 payloads, the
// same bytes whether the device is in the lab's process or across UDP.
#pragma once

#include <string>
#include <vector>

#include "bridge/bridge_markers.h"
#include "bridge/bridge_payload.h"
#include "bridge/bridge_protocol.h"

namespace vlab::task {

class Channel {
 public:
  virtual ~Channel() = default;
  virtual const std::string& name() const = 0;
  virtual bridge::DeviceKind kind() const = 0;
  /// One name per state / command value, in payload order ("status",
  /// "q[0]", ..., "grasped"): a describe reply's layout, groups expanded.
  virtual const std::vector<std::string>& state_names() const = 0;
  virtual const std::vector<std::string>& command_names() const = 0;
  /// An arm's joint names in device order (its describe reply); empty for
  /// other kinds.
  virtual std::vector<std::string> joint_names() const { return {}; }
  /// An arm's joint speed limits in device order, rad/s (its `max_velocity`,
  /// the describe reply's limits.velocity_max); empty when it gives none (the
  /// task language then keeps its defaults, task_rates.h).
  virtual std::vector<double> velocity_limits() const { return {}; }
  /// The newest state payload; false when the device has sent none yet.
  virtual bool Read(std::vector<double>* values) = 0;
  /// Sends a command payload (command_names().size() values). False with a
  /// reason when the device refuses it (in process: its own command check).
  virtual bool Write(const std::vector<double>& values, std::string* why) = 0;
  /// An arm's load at its flange (docs/protocol.md, "Arm payload"): sets it,
  /// in force from the next control period. False with the reason when the
  /// device refuses it or is no arm. May wait for the device's answer (UDP).
  virtual bool SetPayload(const bridge::ArmPayloadMsg& /*payload*/, std::string* why) {
    *why = "'" + name() + "' is not an arm";
    return false;
  }
  /// The arm's payload in force (what the device reports); false with the
  /// reason when the device is no arm.
  virtual bool GetPayload(bridge::ArmPayloadMsg* /*payload*/, std::string* why) {
    *why = "'" + name() + "' is not an arm";
    return false;
  }
};

/// The schedule of the camera a markers device reads (its describe reply):
/// frame i is exposed at i / fps + exposure / 2 and delivered latency later.
struct CameraTiming {
  double fps = 0;         ///< frames per second; 0: unknown (no hold, see MarkerChannel)
  double exposure_s = 0;  ///< exposure time
  double latency_s = 0;   ///< from the exposure stamp to the frame's delivery
};

/// A markers device (kind 5, docs/protocol_markers.md): one state per camera
/// frame the vision program processed, on the camera's clock (the lab's
/// simulated time for the lab's webcam). Always a UDP client: the vision
/// program is a process of its own, in process or not.
class MarkerChannel {
 public:
  virtual ~MarkerChannel() = default;
  virtual const std::string& name() const = 0;
  /// Connects when not yet connected (the vision program may still be
  /// starting: retried up to its timeout). Throws bridge errors or
  /// InputError with what went wrong.
  virtual void Open() = 0;
  /// The camera's schedule; fps 0 when the device did not say.
  virtual CameraTiming timing() const = 0;
  /// Takes every state that arrived (never blocks); the newest so far is in
  /// *out. False when none has arrived yet.
  virtual bool Latest(bridge::MarkersClient::State* out) = 0;
  /// The first state with time >= t_min - 1 us that arrives, taking states in
  /// order; waits up to timeout_s of wall time. False on timeout.
  virtual bool WaitFor(double t_min, double timeout_s, bridge::MarkersClient::State* out) = 0;
  /// Takes the states already arrived; the first with time >= t_min - 1 us
  /// in *out (true), without waiting.
  virtual bool Poll(double t_min, bridge::MarkersClient::State* out) = 0;
  /// Renews the subscription now (a script that read nothing for a while:
  /// the device drops a subscriber silent for 10 s).
  virtual void Renew() = 0;
};

/// The devices a runtime may use, by name; a robot program's arm among them.
class Devices {
 public:
  virtual ~Devices() = default;
  /// The channel of the device `name`, or nullptr when there is none.
  virtual Channel* Find(const std::string& name) = 0;
  /// The markers device `name`, or nullptr when there is none.
  virtual MarkerChannel* FindMarkers(const std::string& /*name*/) { return nullptr; }
  /// Names of every device, for messages.
  virtual std::vector<std::string> Names() const = 0;
};

/// The lockstep rule of markers:next() (docs/tasks.md): called at simulated
/// time t0 with control period `period_s`, the wanted frame is the first
/// whose exposure stamp is reported at or after t0. The camera stamps a frame
/// with the period boundary that closes its exposure stamp and delivers it at
/// the first boundary at least `latency_s` after that. Sets *frame_time_s
/// (the stamp the markers state will carry) and returns the delivery time:
/// at that period the frame has been sent and no later one. Requires
/// timing.fps > 0.
double MarkersFrameDue(const CameraTiming& timing, double period_s, double t0, double* frame_time_s);

/// Index of `name` in `names`, or -1.
int IndexOf(const std::vector<std::string>& names, const std::string& name);

}  // namespace vlab::task
