#include "kinsim/kinsim_server.h"

#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>

#include "bridge/bridge_describe.h"
#include "bridge/bridge_signals.h"
#include "core/core_errors.h"

namespace vlab::kinsim {

namespace {

long long NowNs() {
  timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<long long>(t.tv_sec) * 1000000000LL + t.tv_nsec;
}

}  // namespace

std::unique_ptr<KinsimServer> KinsimServer::Create(const ServerConfig& c, std::unique_ptr<KinArm> arm) {
  if (!arm) throw vlab::InputError("kinsim: no arm");
  if (!(c.rate_hz >= 1 && c.rate_hz <= 10000)) throw vlab::InputError("--rate must be 1 to 10000 Hz");
  if (!(c.duration_s >= 0) || !std::isfinite(c.duration_s)) throw vlab::InputError("--duration must be >= 0 s");
  if (c.watchdog_periods < 0) throw vlab::InputError("--watchdog-periods must be >= 0");
  if (!(c.owner_timeout_s > 0) || !std::isfinite(c.owner_timeout_s)) {
    throw vlab::InputError("--owner-timeout must be > 0 s");
  }
  if (!(c.subscriber_timeout_s > 0) || !std::isfinite(c.subscriber_timeout_s)) {
    throw vlab::InputError("subscriber timeout must be > 0 s");
  }
  std::unique_ptr<KinsimServer> s(new KinsimServer());
  s->config_ = c;
  bridge::DeviceServerConfig server;
  server.bind_address = c.bind_address;
  server.port = c.port;
  s->server_ = bridge::DeviceServer::Bind(server);  // throws NetworkError naming the address

  const KinArmConfig& a = arm->config();
  bridge::ArmDescription d;
  d.name = a.name;
  d.server = "vlab-kinsim";
  d.clock = "realtime";
  d.address = s->server_->local_endpoint().address().to_string();
  d.port = s->server_->port();
  d.control_hz = c.rate_hz;
  d.joints = a.joints;
  d.position_min = a.position_min;
  d.position_max = a.position_max;
  d.velocity_max = a.velocity_max;
  d.torque_max = {};  // no dynamics: torque commands are refused whatever their size
  d.watchdog_periods = c.watchdog_periods;
  d.owner_timeout_s = c.owner_timeout_s;
  d.feedforward = "none";  // a payload is accepted and reported, and moves nothing: no dynamics

  bridge::EndpointConfig e;
  e.name = a.name;
  e.kind = bridge::DeviceKind::kArm;
  e.describe_json = bridge::DescribeJson(d);
  e.owner_timeout_s = c.owner_timeout_s;
  e.subscriber_timeout_s = c.subscriber_timeout_s;
  e.watchdog_periods = c.watchdog_periods;
  e.joints = arm->dof();
  e.position_min = a.position_min;
  e.position_max = a.position_max;
  e.velocity_max = a.velocity_max;
  s->server_->Serve(std::move(e));

  s->packet_.reserve(bridge::kMaxPacketValues * sizeof(double));
  s->command_.value.reserve(bridge::kMaxPacketValues);
  arm->Sample(&s->state_);
  s->arm_ = std::move(arm);
  return s;
}

void KinsimServer::RunPeriod(long k) {
  // 1. drain the socket: every datagram that arrived since the last period
  server_->Receive(k);

  // 2. watchdog, then the newest accepted command
  bridge::DeviceEndpoint& endpoint = server_->endpoint();
  const bool watchdog_hold = endpoint.BeginPeriod(k);
  if (endpoint.TakeArmCommand(&command_)) {
    if (arm_->Command(command_)) {
      ++counters_.applied;
      last_applied_period_ = k;
      mode_hold_ = false;
    } else {
      ++counters_.refused_torque;  // the endpoint checked size, finiteness and limits: only the mode is left
    }
  }
  // the endpoint counted a refused torque command as accepted, so it fed the
  // watchdog: apply the watchdog's rule to the commands the arm took instead,
  // or an owner sending only torques would keep its last velocity in force
  const int wd = config_.watchdog_periods;
  if (wd > 0 && !watchdog_hold && !mode_hold_ && last_applied_period_ >= 0 && k - last_applied_period_ > wd) {
    mode_hold_ = true;
    ++counters_.mode_watchdog_holds;
  }
  if (watchdog_hold || mode_hold_) arm_->Hold();

  // 3. step (period 0 closes at time 0: the initial state) and publish
  if (k > 0) arm_->Step(1.0 / config_.rate_hz);
  arm_->Sample(&state_);
  state_.status |= endpoint.status_bits();
  if (mode_hold_) state_.status |= bridge::kStatusWatchdog | bridge::kStatusHolding;
  bridge::EncodeArmState(static_cast<double>(k), static_cast<double>(k) / config_.rate_hz, state_, &packet_);
  server_->Publish(packet_);
  counters_.periods = k + 1;
}

void KinsimServer::Run(const volatile std::sig_atomic_t* stop_flag) {
  const StopCheck stopped(stop_flag);
  const double period_ns = 1e9 / config_.rate_hz;
  const long last = config_.duration_s > 0 ? std::lround(config_.duration_s * config_.rate_hz) : -1;
  long long start_ns = NowNs();
  for (long k = 0; (last < 0 || k <= last) && !stopped(); ++k) {
    RunPeriod(k);
    // absolute deadline of period k+1; no drift whatever the rate
    const long long deadline_ns = start_ns + std::llround(static_cast<double>(k + 1) * period_ns);
    const long long late_ns = NowNs() - deadline_ns;
    if (late_ns > 0) {
      ++counters_.missed_deadlines;
      counters_.max_lateness_s = std::max(counters_.max_lateness_s, late_ns * 1e-9);
      // more than a period behind: start the schedule afresh rather than run a burst of periods
      if (late_ns > period_ns) start_ns += late_ns;
      continue;
    }
    const timespec at{static_cast<time_t>(deadline_ns / 1000000000LL), static_cast<long>(deadline_ns % 1000000000LL)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &at, nullptr) == EINTR) {
      if (stopped()) break;
    }
  }
}

std::string KinsimServer::StartLine() const {
  char text[256];
  std::snprintf(text, sizeof(text), "vlab-kinsim: arm '%s' (%d joint%s) on %s, %g Hz", arm_->config().name.c_str(),
                arm_->dof(), arm_->dof() == 1 ? "" : "s", bridge::EndpointText(server_->local_endpoint()).c_str(),
                config_.rate_hz);
  return text;
}

std::string KinsimServer::ReportText() const {
  const bridge::EndpointCounters& e = server_->endpoint().counters();
  const ServerCounters& s = counters_;
  char text[1024];
  std::snprintf(text, sizeof(text),
                "vlab-kinsim: %ld periods (%.3f s), missed deadlines %ld (max lateness %.3f ms)\n"
                "vlab-kinsim: received %ld, describes %ld, accepted %ld, applied %ld, payloads %ld\n"
                "vlab-kinsim: refused %ld (malformed %ld, limits %ld, not owner %ld, torque mode %ld), "
                "stale %ld, duplicate %ld, watchdog holds %ld",
                s.periods, s.periods > 0 ? (s.periods - 1) / config_.rate_hz : 0.0, s.missed_deadlines,
                s.max_lateness_s * 1e3, e.received, e.describes, e.accepted, s.applied, e.payloads,
                e.refused + s.refused_torque, e.refused_malformed, e.refused_limits, e.refused_not_owner,
                s.refused_torque, e.stale, e.duplicate, e.watchdog_holds + s.mode_watchdog_holds);
  return text;
}

}  // namespace vlab::kinsim
