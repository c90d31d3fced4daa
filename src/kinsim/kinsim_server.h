// The kinematic arm on the wire: a KinArm behind the bridge's DeviceEndpoint,
// run by a fixed-rate real-time loop. Speaks the same bytes as the lab's MuJoCo
// arm (protocol v1, describe JSON from bridge_describe, the same status bits).
//
// Ports
//   input   UDP datagrams on bind_address:port: arm commands, describe requests,
//           payloads (type 6: accepted from the owner and reported in the
//           describe reply, as the lab's arm does; with no dynamics here they
//           change no motion: describe says "feedforward": "none")
//   output  one arm state per period to every subscriber (seq = period k,
//           time = k / rate_hz s); describe replies (JSON, clock "realtime")
//   rate    rate_hz, paced with clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME)
//           to absolute deadlines; a command arriving during period k applies
//           from the step of period k (the step from (k-1)/rate to k/rate)
// Each period k: drain the socket (DeviceEndpoint::Handle), run the watchdog
// (BeginPeriod), take the newest accepted command, Step(1 / rate_hz) (period 0
// publishes the initial state without a step), publish the state.
#pragma once

#include <csignal>
#include <memory>
#include <string>
#include <vector>

#include "bridge/bridge_device_server.h"
#include "kinsim/kinsim.h"

namespace vlab::kinsim {

struct ServerConfig {
  std::string bind_address = "127.0.0.1";
  int port = 50010;                    ///< 0: any free port (see KinsimServer::port)
  double rate_hz = 500;                ///< control rate, 1 to 10000 Hz
  double duration_s = 0;               ///< run time; 0: until stopped
  int watchdog_periods = 3;            ///< silent owner -> hold after this many periods; 0 disables
  double owner_timeout_s = 1.0;        ///< silent owner gives the command input up after this, s (> 0)
  double subscriber_timeout_s = 10.0;  ///< silent subscribers are dropped after this, s (> 0)
};

/// What the loop counted besides the endpoint's counters.
struct ServerCounters {
  long periods = 0;
  long applied = 0;              ///< commands the arm took
  long refused_torque = 0;       ///< commands accepted by the endpoint, refused by the arm for their mode
  long mode_watchdog_holds = 0;  ///< holds because the owner sent only refused-mode commands
  long missed_deadlines = 0;     ///< periods that ended after their deadline
  double max_lateness_s = 0;
};

class KinsimServer {
 public:
  /// Validates the config and binds the socket. Throws vlab::InputError for a
  /// bad config, bridge::NetworkError when the address cannot be bound.
  static std::unique_ptr<KinsimServer> Create(const ServerConfig& config, std::unique_ptr<KinArm> arm);

  /// Runs periods until duration_s has passed or *stop becomes non-zero (set
  /// it from a signal handler: the sleep is interrupted by the signal).
  void Run(const volatile std::sig_atomic_t* stop);
  /// Runs one period k without pacing (Run calls it; tests may too).
  void RunPeriod(long k);

  int port() const { return server_->port(); }
  const std::string& describe_json() const { return server_->describe_json(); }
  /// "vlab-kinsim: arm 'pa10' (7 joints) on 127.0.0.1:50010, 500 Hz"
  std::string StartLine() const;
  /// Counters as a few lines of text (no trailing newline).
  std::string ReportText() const;
  const ServerCounters& counters() const { return counters_; }
  const bridge::EndpointCounters& endpoint_counters() const { return server_->endpoint().counters(); }

 private:
  KinsimServer() = default;

  ServerConfig config_;
  std::unique_ptr<KinArm> arm_;
  std::unique_ptr<bridge::DeviceServer> server_;
  ServerCounters counters_;
  long last_applied_period_ = -1;
  bool mode_hold_ = false;
  // scratch, sized at start
  std::vector<unsigned char> packet_;
  bridge::ArmCommandMsg command_;
  bridge::ArmStateMsg state_;
};

}  // namespace vlab::kinsim
