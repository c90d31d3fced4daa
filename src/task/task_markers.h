// A markers device (kind 5, docs/protocol_markers.md) for the task runtime:
// a UDP client of the vision program (`vlab vision`), in the lab's process
// and in `vlab task` alike: the vision program is always a process of its own.
//
// Ports
//   input   the device's states, one per processed camera frame, taken in
//           order (Poll, WaitFor) or newest first (Latest)
//   output  none (the marker table is the vision program's --marker list)
// Timing: the camera's schedule (fps, exposure, latency) comes from the
// describe reply's "camera" entry (docs/protocol_markers.md). Times are
// shifted by the runtime's clock origin (set_time_origin), so that a state's
// time and now() are on one clock.
// Threading: one thread. Errors: Open throws bridge errors (after retrying
// for its timeout: the vision program may still be starting).
#pragma once

#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "task/task_channel.h"

namespace vlab::task {

class UdpMarkers final : public MarkerChannel {
 public:
  /// `name` is what scripts call it (the scenario's key, or "" to take the
  /// device's own name at Open); "HOST:PORT" of the device; `timeout_s`:
  /// how long Open keeps trying.
  UdpMarkers(const std::string& name, const std::string& endpoint, double timeout_s);
  ~UdpMarkers() override;

  const std::string& name() const override { return name_; }
  void Open() override;
  CameraTiming timing() const override { return timing_; }
  bool Latest(bridge::MarkersClient::State* out) override;
  bool WaitFor(double t_min, double timeout_s, bridge::MarkersClient::State* out) override;
  bool Poll(double t_min, bridge::MarkersClient::State* out) override;

  /// Device time that is time 0 of the runtime (vlab task: the arm's first state).
  void set_time_origin(double t_s) { origin_s_ = t_s; }
  /// Called every few milliseconds while Open or WaitFor wait (in process:
  /// the lab serves its devices meanwhile, the camera the vision program
  /// reads among them); null: nothing.
  void set_idle(std::function<void()> idle) { idle_ = std::move(idle); }

 private:
  // the next state within timeout_s (0: only one already arrived); shifted
  bool Next(double timeout_s, bridge::MarkersClient::State* out);
  void KeepAliveNowAndThen();

  std::string name_, host_;
  int port_ = 0;
  double timeout_s_;
  double origin_s_ = 0;
  CameraTiming timing_;
  std::optional<bridge::MarkersClient> client_;
  bool have_ = false;
  bridge::MarkersClient::State newest_;
  std::chrono::steady_clock::time_point renewed_;
  std::function<void()> idle_;
};

}  // namespace vlab::task
