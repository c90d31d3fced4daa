#include "yoyosim/yoyosim_server.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "bridge/bridge_describe.h"
#include "bridge/bridge_layouts.h"
#include "bridge/bridge_yoyo.h"
#include "core/core_errors.h"
#include "yoyosim/yoyosim_describe.h"

namespace vlab::yoyosim {

namespace {

// longest single wait: a stop request (signal) is seen within this, s
constexpr double kPollSlice_s = 0.05;

// the point's and the yo-yo's layouts (bridge_layouts.h)
constexpr bridge::DeviceKind kPoint = bridge::DeviceKind::kPoint, kYoyo = bridge::DeviceKind::kYoyo;
constexpr int kPointValues = bridge::ValueCount(bridge::LayoutOf(kPoint).state);
constexpr int kPointCommandValues = bridge::ValueCount(bridge::LayoutOf(kPoint).command);
static_assert(bridge::CommandIndex(kPoint, "x") == 0 && bridge::CommandIndex(kPoint, "y") == 1 &&
                  bridge::CommandIndex(kPoint, "z") == 2 && kPointCommandValues == 3,
              "a point command is the set-point [x, y, z] YoyoSim takes");

void Require(bool ok, const std::string& what) {
  if (!ok) throw vlab::InputError(what);
}

}  // namespace

std::unique_ptr<YoyoSimServer> YoyoSimServer::Create(const ServerConfig& c, std::unique_ptr<YoyoSim> sim) {
  Require(sim != nullptr, "yoyosim: no simulation");
  Require(c.clock == "lockstep" || c.clock == "realtime",
          "--clock must be lockstep or realtime, not '" + c.clock + "'");
  Require(c.duration_s >= 0 && std::isfinite(c.duration_s), "--duration must be >= 0 s");
  Require(c.start_timeout_s >= 0 && std::isfinite(c.start_timeout_s), "--start-timeout must be >= 0 s");
  Require(c.timeout_s > 0 && std::isfinite(c.timeout_s), "--timeout must be > 0 s");
  Require(c.release_after >= 1, "release_after must be >= 1");
  Require(c.speed_max > 0 && std::isfinite(c.speed_max), "--max-speed must be > 0 m/s");
  Require(c.watchdog_periods >= 0, "watchdog periods must be >= 0");
  Require(c.owner_timeout_s > 0 && std::isfinite(c.owner_timeout_s), "owner timeout must be > 0 s");
  Require(c.subscriber_timeout_s > 0 && std::isfinite(c.subscriber_timeout_s), "subscriber timeout must be > 0 s");

  std::unique_ptr<YoyoSimServer> s(new YoyoSimServer());
  s->config_ = c;
  // a new subscriber gets the latest state at once (it may be what lockstep waits on)
  bridge::DeviceServerConfig server;
  server.bind_address = c.bind_address;
  server.send_latest = true;
  server.port = c.point_port;
  s->point_ = bridge::DeviceServer::Bind(server);  // throws NetworkError naming it
  server.port = c.yoyo_port;
  s->yoyo_ = bridge::DeviceServer::Bind(server);
  const double period = sim->period_s();

  bridge::DeviceDescription d;
  d.server = "vlab-yoyosim (MuJoCo " + vlab::MujocoVersion() + ")";
  d.clock = c.clock;
  d.address = s->point_->local_endpoint().address().to_string();
  d.control_hz = 1.0 / period;

  bridge::EndpointConfig point;
  d.name = point.name = "point";
  d.port = s->point_->port();
  point.kind = kPoint;
  point.describe_json = PointDescribeJson(d, *sim, PointFacts{c.speed_max, c.watchdog_periods, c.owner_timeout_s});
  point.owner_timeout_s = c.owner_timeout_s;
  point.subscriber_timeout_s = c.subscriber_timeout_s;
  point.watchdog_periods = c.watchdog_periods;
  point.command_length = kPointCommandValues;
  point.status_first = true;
  YoyoSimServer* self = s.get();
  point.check_command = [self](const std::vector<double>& p) { return self->CheckSetPoint(p); };
  s->point_->Serve(std::move(point));

  bridge::EndpointConfig yoyo;
  d.name = yoyo.name = "yoyo";
  d.port = s->yoyo_->port();
  yoyo.kind = kYoyo;
  yoyo.describe_json = YoyoDescribeJson(d, *sim);
  yoyo.subscriber_timeout_s = point.subscriber_timeout_s;
  s->yoyo_->Serve(std::move(yoyo));

  // the lab's clock policy
  ClockConfig clock;
  clock.mode = ParseClockMode(c.clock, "--clock");
  clock.period_s = period;
  clock.lockstep.timeout_s = c.timeout_s;
  clock.lockstep.start_timeout_s = c.start_timeout_s;
  clock.lockstep.on_timeout = OnTimeout::kHold;
  clock.lockstep.release_after = c.release_after;
  clock.realtime.factor = 1.0;
  const long periods = c.duration_s > 0 ? std::lround(c.duration_s / period) : 0;
  s->clock_ = MakeClock(clock, periods);

  s->command_.reserve(bridge::kMaxPacketValues);
  s->sim_ = std::move(sim);
  return s;
}

bridge::CommandCheck YoyoSimServer::CheckSetPoint(const std::vector<double>& p) const {
  return sim_->WithinWorkspace(p.data()) ? bridge::CommandCheck::kAccept : bridge::CommandCheck::kLimits;
}

void YoyoSimServer::Receive() {
  point_->Receive(period_, [this] {
    // an accepted set-point: the newest, applied at the next period start
    point_->endpoint().TakeCommand(&command_);
    std::copy(command_.begin(), command_.begin() + 3, pending_W_.begin());
    pending_ = true;
  });
  yoyo_->Receive(period_);
}

void YoyoSimServer::Poll(double timeout_s, vlab::PollWait) {
  if (stopped_()) return;
  const int fds[2] = {point_->fd(), yoyo_->fd()};
  if (bridge::WaitReadable(fds, 2, std::min(timeout_s, kPollSlice_s))) Receive();
}

bool YoyoSimServer::Answered(std::int64_t k) const {
  if (stopped_()) return true;  // stop waiting: the loop ends
  const bridge::DeviceEndpoint& point = point_->endpoint();
  if (!point.has_owner()) return k > 0;
  return point.last_accepted_seq() >= static_cast<double>(k);
}

void YoyoSimServer::BeginPeriod(long k, vlab::PeriodStart start) {
  // lockstep: a silent owner costs a timeout per period, then loses the point
  if (start == vlab::PeriodStart::kTimedOut) {
    ++counters_.timeouts;
    if (++consecutive_timeouts_ >= config_.release_after && point_->endpoint().has_owner()) {
      point_->endpoint().ReleaseOwner();
      ++counters_.releases;
      if (!config_.quiet) {
        std::fprintf(stderr, "vlab-yoyosim: no command for %d periods in a row (t = %.3f s): point released\n",
                     consecutive_timeouts_, sim_->time());
      }
    }
  } else {
    consecutive_timeouts_ = 0;
  }
  Receive();  // what came since the clock's last poll
  // watchdog: hold where the hand is, once, until the next accepted command
  if (point_->endpoint().BeginPeriod(k)) {
    if (!watchdog_hold_) {
      sim_->Hold();
      pending_ = false;  // the hold ends the way to the last set-point
    }
    watchdog_hold_ = true;
  } else {
    watchdog_hold_ = false;
  }
  // the set-point in force moves towards the newest command by at most
  // speed_max x period in a period (a far command is reached at speed_max)
  if (pending_) {
    Vec3 next = sim_->target();
    double distance = 0;
    for (int i = 0; i < 3; ++i) distance += (pending_W_[i] - next[i]) * (pending_W_[i] - next[i]);
    distance = std::sqrt(distance);
    const double step = config_.speed_max * sim_->period_s();
    const double f = distance > step ? step / distance : 1.0;
    for (int i = 0; i < 3; ++i) next[i] += f * (pending_W_[i] - next[i]);
    if (sim_->SetTarget(next.data())) ++counters_.applied;
    pending_ = f < 1.0;
  }
}

void YoyoSimServer::Publish(long k) {
  static_assert(sizeof(values_) / sizeof(values_[0]) >=
                static_cast<std::size_t>(std::max(kPointValues, bridge::kYoyoValues)));
  const double seq = static_cast<double>(k), time = static_cast<double>(k) * sim_->period_s();
  sim_->SamplePoint(values_);
  constexpr int kStatus = bridge::StateIndex(kPoint, "status");
  const std::uint32_t status = static_cast<std::uint32_t>(values_[kStatus]) | point_->endpoint().status_bits();
  values_[kStatus] = static_cast<double>(status);
  point_->Publish(seq, time, values_, kPointValues);
  sim_->SampleYoyo(values_);
  yoyo_->Publish(seq, time, values_, bridge::kYoyoValues);
}

int YoyoSimServer::Run(const volatile std::sig_atomic_t* stop) {
  stopped_ = StopCheck(stop);
  const long last = config_.duration_s > 0 ? std::lround(config_.duration_s / sim_->period_s()) : -1;
  int result = 0;
  Publish(0);
  for (long k = 0; (last < 0 || k < last) && !stopped_(); ++k) {
    period_ = k;
    const vlab::PeriodStart start = clock_->BeginPeriod(k, this);
    if (stopped_()) break;
    BeginPeriod(k, start);
    if (!sim_->Step()) {
      std::fprintf(stderr, "vlab-yoyosim: error: the simulation diverged in the period from t = %.3f s (MuJoCo: %s)\n",
                   sim_->time(), sim_->divergence());
      result = 1;
      break;
    }
    counters_.periods = k + 1;
    Publish(k + 1);
  }
  const vlab::ClockStats& stats = clock_->stats();
  counters_.missed_deadlines = stats.missed_deadlines;
  counters_.max_lateness_s = stats.max_lateness_s;
  return result;
}

std::string YoyoSimServer::StartLine() const {
  char text[512];
  std::snprintf(text, sizeof(text), "vlab-yoyosim: point on %s, yoyo on %s, %s, %g Hz, scene %s",
                bridge::EndpointText(point_->local_endpoint()).c_str(),
                bridge::EndpointText(yoyo_->local_endpoint()).c_str(), config_.clock.c_str(), 1.0 / sim_->period_s(),
                sim_->scene().c_str());
  return text;
}

std::string YoyoSimServer::ReportText() const {
  const bridge::EndpointCounters& p = point_->endpoint().counters();
  const bridge::EndpointCounters& y = yoyo_->endpoint().counters();
  const ServerCounters& s = counters_;
  char text[1024];
  std::snprintf(text, sizeof(text),
                "vlab-yoyosim: %ld periods (%.3f s), set-points applied %ld, lockstep timeouts %ld, releases %ld, "
                "missed deadlines %ld (max lateness %.3f ms)\n"
                "vlab-yoyosim: point: received %ld, describes %ld, accepted %ld, refused %ld (malformed %ld, "
                "limits %ld, not owner %ld), stale %ld, duplicate %ld, watchdog holds %ld\n"
                "vlab-yoyosim: yoyo: received %ld, describes %ld, refused %ld",
                s.periods, sim_->time(), s.applied, s.timeouts, s.releases, s.missed_deadlines, s.max_lateness_s * 1e3,
                p.received, p.describes, p.accepted, p.refused, p.refused_malformed, p.refused_limits,
                p.refused_not_owner, p.stale, p.duplicate, p.watchdog_holds, y.received, y.describes, y.refused);
  return text;
}

}  // namespace vlab::yoyosim
