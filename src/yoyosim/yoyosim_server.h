// The yo-yo simulator on the wire: a YoyoSim behind two bridge DeviceEndpoints,
// `point` (the hand) and `yoyo`, timed by the lab's clock policy (core/core_clock.h).
//
// Ports
//   input   point port: point commands [x, y, z] (hand set-point, m, world),
//           describe requests; yoyo port: describe requests (commands refused)
//   output  one point state and one yoyo state per period to every subscriber
//           of each (seq = k, time = k * period_s); describe replies (JSON);
//           a new subscriber gets the device's latest state at once (a client
//           that connects while lockstep waits gets the state to answer; with
//           kStatusNotOwner when another client owns the point)
//   rate    1 / period_s. lockstep: state k of both devices is published, then
//           the loop waits for the point command answering k (from its owner;
//           period 0: for a first owner, start_timeout_s) before it simulates
//           period k; a period whose command does not come within timeout_s
//           runs with the set-point in force, and after release_after such
//           periods in a row the owner is released (then nothing is waited for
//           until a client owns the point again). realtime: paced to the wall
//           clock once period 0 is answered (or after start_timeout_s); a
//           command applies at the start of the next period.
// Command limits: a set-point outside the workspace box is refused as limits
// and counted. Speed: the set-point in force moves towards the newest accepted
// command by at most speed_max x period per period, so a far command is
// reached at speed_max (as the lab's point device does). Watchdog: no accepted
// command for watchdog_periods periods -> the hand holds where it is.
// The loop never throws; the datagram handlers never block.
#pragma once

#include <csignal>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "bridge/bridge_device_server.h"
#include "bridge/bridge_signals.h"
#include "core/core_clock.h"
#include "yoyosim/yoyosim.h"

namespace vlab::yoyosim {

struct ServerConfig {
  std::string bind_address = "127.0.0.1";
  int point_port = 50060;          ///< 0: any free port (see point_port())
  int yoyo_port = 50061;           ///< 0: any free port
  std::string clock = "lockstep";  ///< lockstep | realtime
  double duration_s = 0;           ///< simulated run time; 0: until stopped
  double start_timeout_s = 30;     ///< wait for a controller before period 0, s
  double timeout_s = 1.0;          ///< lockstep: wait per period, s
  int release_after = 3;           ///< lockstep: timeouts in a row that release the owner
  double speed_max = 2.0;          ///< m/s, set-point speed limit
  int watchdog_periods = 3;        ///< 0 disables
  double owner_timeout_s = 1.0;    ///< silent owner gives the input up after this, s
  double subscriber_timeout_s = 10.0;
  bool quiet = false;  ///< no messages while running (timeouts, releases)
};

/// What the loop counted besides the endpoints' counters.
struct ServerCounters {
  long periods = 0;           ///< periods simulated
  long applied = 0;           ///< set-points the hand took
  long timeouts = 0;          ///< lockstep periods run without their command
  long releases = 0;          ///< owners released after release_after timeouts
  long missed_deadlines = 0;  ///< realtime
  double max_lateness_s = 0;  ///< realtime
};

class YoyoSimServer final : public vlab::CommandSource {
 public:
  /// Validates the config and binds both sockets. Throws vlab::InputError for a
  /// bad value (naming the option), bridge::NetworkError for an address or
  /// port that cannot be bound.
  static std::unique_ptr<YoyoSimServer> Create(const ServerConfig& config, std::unique_ptr<YoyoSim> sim);

  /// Runs until duration_s of simulated time or *stop becomes non-zero (set it
  /// from a signal handler). Returns 0, or 1 when the simulation diverged.
  int Run(const volatile std::sig_atomic_t* stop);

  /// vlab::CommandSource: receives on both sockets for up to timeout_s.
  void Poll(double timeout_s, vlab::PollWait wait) override;  // (sleeps: it never spins)
  /// vlab::CommandSource: the point's owner has answered period k (period 0:
  /// some client owns the point; later: true while nobody owns it).
  bool Answered(std::int64_t k) const override;

  int point_port() const { return point_->port(); }
  int yoyo_port() const { return yoyo_->port(); }
  const YoyoSim& sim() const { return *sim_; }
  /// "vlab-yoyosim: point on 127.0.0.1:50060, yoyo on 127.0.0.1:50061, lockstep, 100 Hz, scene ..."
  std::string StartLine() const;
  /// Counters as a few lines of text (no trailing newline).
  std::string ReportText() const;
  const ServerCounters& counters() const { return counters_; }
  const bridge::EndpointCounters& point_counters() const { return point_->endpoint().counters(); }
  const bridge::EndpointCounters& yoyo_counters() const { return yoyo_->endpoint().counters(); }

 private:
  YoyoSimServer() = default;
  bridge::CommandCheck CheckSetPoint(const std::vector<double>& p) const;
  void Receive();
  void BeginPeriod(long k, vlab::PeriodStart start);
  void Publish(long k);

  ServerConfig config_;
  std::unique_ptr<YoyoSim> sim_;
  std::unique_ptr<bridge::DeviceServer> point_, yoyo_;
  std::unique_ptr<vlab::Clock> clock_;
  ServerCounters counters_;
  StopCheck stopped_;
  long period_ = 0;       // the period being waited for or run
  bool pending_ = false;  // an accepted set-point not yet reached by the set-point in force
  Vec3 pending_W_{};
  bool watchdog_hold_ = false;
  int consecutive_timeouts_ = 0;
  // scratch, sized at start
  std::vector<double> command_;
  double values_[7] = {0, 0, 0, 0, 0, 0, 0};
};

}  // namespace vlab::yoyosim
