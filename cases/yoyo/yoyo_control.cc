// yoyo_control: keeps a yo-yo swinging to a set height by moving the hand that holds
// its string up and down (x and y held). An external 100 Hz program that talks to the
// devices only through the vlab client library; the same binary in every stage.
//
//   yoyo_control --hand ADDR --yoyo ADDR [--force ADDR] [--mirror ADDR] [--level M]
//                [--string M] [--log FILE] [--check-from S --check-for S] [--timeout S] [--quiet]
//
// Devices: --hand, a point device (its states pace the loop: one command per state);
// --yoyo, a yoyo device (position; its string_force too when there is no --force). A
// lockstep yoyo device (its describe reply's clock; the lab's, vlab-yoyosim's) publishes
// every period: the loop waits for period k's state, and status kYoyoNotSeen marks a held
// value. Any other (vlab vision's: one state per camera frame, seq = the frame id) is read
// without waiting: the states that have arrived, the newest sighting counting, timed by
// its stamp (the exposure time, on the camera's clock: the lab's simulated time for its
// cameras) and set against the hand's state at that time. --force, a wrench device (the
// JR3): string force = |Fz - Fz at the first state| (the tool-side static load, and the
// 0.44 N of the yo-yo already falling at the start, removed), logged; while the hand
// accelerates it also holds the tool's inertia, so the control law, timed by the yo-yo's
// position alone, does not use it. --mirror, a second point device (vlab-yoyosim's hand)
// sent the hand's MEASURED position every period, shifted by (mirror start - hand start),
// and the yoyo device's positions are shifted back by the same offset, so the yo-yo hangs
// from the hand in the hand's frame.
// Level: --level M is the climb height of the swing's top above the end of the string
// with the hand at its start, z_ref = hand start z - L (L = --string, 1.0 m). A swing's
// amplitude is its top's height above z_ref.
// Lockstep: state k of the hand, then the states of the same period k of the others.
// Control law, per swing n (amplitude a_n = the swing's top above z_ref): a free yo-yo keeps
// e^2 = 0.657 of its fall height per bottom, and the hand adds energy mainly through the
// tension spike at the bottom (work = impulse x the hand's speed then); the quasi-static
// tension (0.44 N) does no net work over a cycle that ends where it began. So the map
// a_{n+1} = e^2 a_n + G S_n, S_n the stroke of the hand's pulse around bottom n+1.
// Pulse: after the top the hand sinks by S/2 over kPre_s (the yo-yo still slow, the hand then
// still for the late samples that predict the bottom), rises by S on a raised cosine of kUp_s
// centred kLead before the predicted bottom (the hand's velocity lags its set-point: its peak
// then meets the spike) and comes back to its start over kRet_s while the yo-yo climbs, so each
// top is measured with the hand at its start. Peak hand speed pi S / (2 kUp_s): 0.9 m/s at the
// S = 0.17 m the level 0.36 m needs, within the point device's max_speed (1 m/s); kMaxStroke
// keeps it there. Bottom: predicted from the last fresh yo-yo sample (depth below the hand d,
// its rate, descent a = 0.928 m/s^2 of the still-hand yo-yo, bottom when d = L) plus a bias
// learnt from the bottoms measured: extrapolated back to d = L, on the climb's deceleration,
// from the second rising sample in a row (a camera's rate is a difference of two frames, and
// the first rising frame's pair may straddle the bottom).
// Top: the highest sighting of the climb; the swing ends at the first sighting below it by
// 5 mm and falling (a camera's: the second such in a row, one low frame being no top).
// Stroke: deadbeat on the model towards a_n + kDamp (level - a_n), S = (target - e^2 a_n) / G^,
// within [0, kMaxStroke]; G^ from (a_n, S_n, a_{n+1}) by a scalar recursive least squares with
// forgetting kForget, clamped to [kGainMin, kGainMax]. Deterministic: only state times count.
// Ends when the hand is silent for --timeout s or on SIGTERM/SIGINT; then the check:
// every swing whose top lies in [S, S + F] within +-10 % of the level and the run past
// S + F. Exit 0; 1 when the check fails (a line says which swing); 2 on bridge errors.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include "bridge/bridge_client.h"
#include "bridge/bridge_client_device.h"
#include "bridge/bridge_layouts.h"
#include "bridge/bridge_program.h"
#include "bridge/bridge_row_log.h"
#include "bridge/bridge_yoyo.h"

namespace {

using vlab::bridge::Device;
using vlab::bridge::DeviceKind;
using vlab::bridge::Wrench;

using vlab::bridge::program::Address;
using vlab::bridge::program::ParseAddress;
using vlab::bridge::program::ReadUntil;
using vlab::bridge::program::RowLog;
using vlab::bridge::program::Stopped;

constexpr double kConnect_s = 5.0;
// positions in the point's and the yo-yo's states (bridge/bridge_layouts.h)
constexpr int Hand(const char* field) { return vlab::bridge::StateIndex(DeviceKind::kPoint, field); }
constexpr int Yoyo(const char* field) { return vlab::bridge::StateIndex(DeviceKind::kYoyo, field); }
constexpr int kHandX = Hand("x"), kHandY = Hand("y"), kHandZ = Hand("z"), kHandVz = Hand("vz");
constexpr int kYoyoStatus = Yoyo("status"), kYoyoZ = Yoyo("z"), kYoyoVz = Yoyo("vz");
constexpr int kYoyoForce = Yoyo("string_force");
constexpr double kDescent = 0.928;  // m/s^2, g m r^2 / (m r^2 + J) (mjcf/yoyo/README.md)
constexpr double kE2 = 0.657;       // e^2: a free yo-yo keeps this share of its fall height per bottom
constexpr double kUp_s = 0.30, kLead = 0.03, kPre_s = 0.4, kRet_s = 0.6, kMaxStroke = 0.19, kLowFrac = 0.5;
constexpr double kGain0 = 0.75, kGainMin = 0.2, kGainMax = 5.0, kP0 = 100.0, kForget = 0.9, kDamp = 0.8;
constexpr double kTolerance = 0.10;  // of the level
constexpr std::size_t kPast = 50;    // periods of the hand kept (0.5 s): a camera sample is a few periods old

struct Options {
  Address hand, yoyo, force, mirror;
  double level = 0.36, string = 1.0, check_from = -1, check_for = 0, timeout_s = 2.0;
  std::string log;
  bool quiet = false;
};

bool ParseOptions(int argc, char** argv, Options* o) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--quiet") {
      o->quiet = true;
      continue;
    }
    if (i + 1 >= argc) return false;
    const std::string v = argv[++i];
    bool ok = true;
    if (arg == "--hand")
      ok = ParseAddress(v, &o->hand);
    else if (arg == "--yoyo")
      ok = ParseAddress(v, &o->yoyo);
    else if (arg == "--force")
      ok = ParseAddress(v, &o->force);
    else if (arg == "--mirror")
      ok = ParseAddress(v, &o->mirror);
    else if (arg == "--level")
      o->level = std::atof(v.c_str());
    else if (arg == "--string")
      o->string = std::atof(v.c_str());
    else if (arg == "--log")
      o->log = v;
    else if (arg == "--check-from")
      o->check_from = std::atof(v.c_str());
    else if (arg == "--check-for")
      o->check_for = std::atof(v.c_str());
    else if (arg == "--timeout")
      o->timeout_s = std::atof(v.c_str());
    else
      return false;
    if (!ok) return false;
  }
  return o->hand.port > 0 && o->yoyo.port > 0 && o->level > 0 && o->string > 0 && o->timeout_s > 0;
}

// FNV-1a 64 of this program's file: the same binary in every stage
unsigned long long SelfHash(std::string* path) {
  char buf[4096];
  const long n = ::readlink("/proc/self/exe", buf, sizeof(buf) - 1);
  *path = n > 0 ? std::string(buf, n) : "?";
  std::ifstream in(*path, std::ios::binary);
  unsigned long long h = 1469598103934665603ull;
  for (char c; in.get(c);) h = (h ^ static_cast<unsigned char>(c)) * 1099511628211ull;
  return h;
}

double Cosine(double from, double to, double t, double duration) {  // raised cosine, t from its start
  const double s = std::clamp(t / duration, 0.0, 1.0);
  return from + (to - from) * 0.5 * (1 - std::cos(M_PI * s));
}

struct Swing {
  int n;
  double t, top;
};
struct HandAt {
  double t, z, vz;
};

// The yo-yo's state for period `seq`. per_period: waits for it, as ReadUntil; *seen: not
// flagged kYoyoNotSeen. Otherwise: takes the states that have arrived, without waiting;
// *y becomes the newest sighting among them, *seen whether there was one. False: silence
// or a signal (per_period only).
bool ReadYoyo(Device& yoyo, bool per_period, std::int64_t seq, double timeout_s, Device::State* y, bool* seen) {
  const auto sighted = [](const Device::State& s) {
    return !(static_cast<unsigned>(s.values[kYoyoStatus]) & vlab::bridge::kYoyoNotSeen);
  };
  if (per_period) {
    if (!ReadUntil(yoyo, seq, timeout_s, y)) return false;
    *seen = sighted(*y);
    return true;
  }
  *seen = false;
  for (;;) {
    try {
      Device::State s = yoyo.Read(0.0);
      if (sighted(s)) *y = std::move(s), *seen = true;
    } catch (const vlab::bridge::TimeoutError&) {
      return true;
    }
  }
}

int Run(const Options& o) {
  Device hand = Device::Connect(DeviceKind::kPoint, o.hand.host, o.hand.port, kConnect_s);
  Device yoyo = Device::Connect(DeviceKind::kYoyo, o.yoyo.host, o.yoyo.port, kConnect_s);
  std::unique_ptr<Wrench> force;
  std::unique_ptr<Device> mirror;
  if (o.force.port) force = std::make_unique<Wrench>(Wrench::Connect(o.force.host, o.force.port, kConnect_s));
  if (o.mirror.port)
    mirror = std::make_unique<Device>(Device::Connect(DeviceKind::kPoint, o.mirror.host, o.mirror.port, kConnect_s));
  const bool per_period = yoyo.describe().value("clock", "") == "lockstep";
  std::string self;
  const unsigned long long hash = SelfHash(&self);
  std::printf("yoyo_control: binary %s fnv1a64 %016llx\n", self.c_str(), hash);
  std::printf("yoyo_control: yo-yo from '%s' (%s), %s\n", yoyo.name().c_str(),
              yoyo.describe().value("server", "?").c_str(), per_period ? "every period" : "as its states arrive");
  std::fflush(stdout);

  Device::State h, y, mr;
  Wrench::State w;
  if (!ReadUntil(hand, 0, o.timeout_s + kConnect_s, &h)) return Stopped() ? 0 : 2;
  const double t0 = h.time, x0 = h.values[kHandX], y0 = h.values[kHandY], z0 = h.values[kHandZ];
  const double z_ref = z0 - o.string;
  double offset[3] = {0, 0, 0}, fz0 = 0;  // mirror start - hand start; static load
  // (written by its own thread: the loop never waits for the disk)
  std::unique_ptr<RowLog> log;
  if (!o.log.empty()) {
    log = RowLog::Open(o.log, {{"time", 3},
                               {"hand_z", 6},
                               {"yoyo_z", 6},
                               {"string_force", 5},
                               {"swing_top_z", 6},
                               {"level_z", 6},
                               {"stroke", 5},
                               {"yoyo_time", 3}});
  }

  // per swing n: a_{n+1} = e2 a_n + G S_n (a: amplitude, S: the stroke); deadbeat on the
  // model with G estimated by a scalar recursive least squares (forgetting kForget)
  enum Phase { kFalling, kPulse, kClimbing } phase = kFalling;
  double gain = kGain0, p_rls = kP0, stroke = 0, amp_prev = NAN, stroke_prev = 0;
  double bias = 0, t_pred = 1e9, t_pulse = 0, z_from = z0, z_cmd = z0, t_top = 0, top = -1e9, z_low = z0;
  double s_t = -1, s_d = 0, s_rate = 0, rate_before = 0, last_top = NAN;  // the last sighting; its predecessor's rate
  // sightings in a row below the top and falling that end a swing: a camera's sighting can be
  // a misreading (one low frame while the yo-yo still climbs), a period's ground truth cannot
  const int end_sightings = per_period ? 1 : 2;
  int falling = 0;
  double next_keepalive = 1.0, t = 0;
  std::vector<Swing> swings;
  std::deque<HandAt> past;  // the hand over the last kPast periods
  bool first = true;
  do {
    t = h.time - t0;
    bool fresh = false;
    if (!ReadYoyo(yoyo, per_period, h.seq, o.timeout_s, &y, &fresh)) break;
    if (force && !ReadUntil(*force, h.seq, o.timeout_s, &w)) break;
    if (mirror && !ReadUntil(*mirror, h.seq, o.timeout_s, &mr)) break;
    if (first && mirror) {
      const int xyz[3] = {kHandX, kHandY, kHandZ};
      for (int i = 0; i < 3; ++i) offset[i] = mr.values[xyz[i]] - h.values[xyz[i]];
    }
    if (first && force) fz0 = w.wrench(2);
    first = false;
    const double hz = h.values[kHandZ], hvz = h.values[kHandVz];
    const bool have_y = !y.values.empty();  // not yet: a camera's first frame still to come
    const double yz = have_y ? y.values[kYoyoZ] - offset[2] : NAN, yvz = have_y ? y.values[kYoyoVz] : 0.0;
    const double f = force ? std::abs(w.wrench(2) - fz0) : have_y ? y.values[kYoyoForce] : NAN;
    past.push_back({t, hz, hvz});
    if (past.size() > kPast) past.pop_front();
    if (fresh) {  // the sample's depth and rate: against the hand at the sample's time
      rate_before = s_rate;
      s_t = per_period ? t : y.time - t0;
      const HandAt& at = *std::min_element(past.begin(), past.end(), [&](const HandAt& a, const HandAt& b) {
        return std::abs(a.t - s_t) < std::abs(b.t - s_t);
      });
      s_d = at.z - yz, s_rate = at.vz - yvz;
    }

    if (phase == kFalling && s_t >= 0 && s_rate > 0.05) {  // predict the bottom from the last sample
      const double rest = std::max(0.0, o.string - s_d);
      const double tau = (-s_rate + std::sqrt(s_rate * s_rate + 2 * kDescent * rest)) / kDescent;
      t_pred = s_t + tau + bias;
      if (t >= t_pred - kUp_s / 2 - kLead) phase = kPulse, t_pulse = t, z_from = z_cmd;
    } else if (phase == kPulse && fresh && s_rate < -0.05 && rate_before < -0.05) {  // rising: the bottom is past
      // back to d = L on the climb's deceleration: L - d = v tau + a tau^2 / 2, v = -s_rate
      const double v = -s_rate, rest = std::max(0.0, o.string - s_d);
      const double t_bottom = s_t - (-v + std::sqrt(v * v + 2 * kDescent * rest)) / kDescent;
      bias = std::clamp(bias + 0.5 * (t_bottom - t_pred), -0.1, 0.1);
      phase = kClimbing, top = -1e9, falling = 0;
    } else if (phase == kPulse && t > t_pulse + kUp_s + 0.3) {
      phase = kClimbing, top = -1e9, falling = 0;
    } else if (phase == kClimbing && fresh) {
      if (yvz > 0 || top > -1e8) top = std::max(top, yz);
      falling = top > -1e8 && yz < top - 0.005 && yvz < 0 ? falling + 1 : 0;
      if (falling >= end_sightings) {  // past the top: the swing is done
        swings.push_back({static_cast<int>(swings.size()) + 1, t, top});
        last_top = top;
        const double amp = top - z_ref;
        if (std::isfinite(amp_prev) && stroke_prev > 0.02) {  // RLS on G from (a_n, S_n, a_{n+1})
          const double x = stroke_prev, yv = amp - kE2 * amp_prev;
          const double k = p_rls * x / (kForget + x * p_rls * x);
          gain = std::clamp(gain + k * (yv - gain * x), kGainMin, kGainMax);
          p_rls = std::min((p_rls - k * x * p_rls) / kForget, kP0);
        }
        const double target = amp + kDamp * (o.level - amp);  // the next top aimed at
        stroke = std::clamp((target - kE2 * amp) / gain, 0.0, kMaxStroke);
        amp_prev = amp, stroke_prev = stroke;
        phase = kFalling, t_top = t, z_from = z_cmd, z_low = z0 - kLowFrac * stroke;
        if (!o.quiet)
          std::printf("swing %zu: top %.4f m (amplitude %.4f m), t = %.2f s, G %.3f, next stroke %.4f m\n",
                      swings.size(), top, amp, t, gain, stroke);
      }
    }
    if (phase == kFalling) {
      z_cmd = Cosine(z_from, z_low, t - t_top, kPre_s);
    } else if (t - t_pulse < kUp_s) {
      z_cmd = Cosine(z_from, z_low + stroke, t - t_pulse, kUp_s);
    } else {
      z_cmd = Cosine(z_low + stroke, z0, t - t_pulse - kUp_s, kRet_s);
    }
    z_cmd = std::clamp(z_cmd, z0 - 0.15, z0 + 0.15);
    hand.WriteFields({{"x", x0}, {"y", y0}, {"z", z_cmd}}, h.seq);
    if (mirror) {
      mirror->WriteFields(
          {{"x", h.values[kHandX] + offset[0]}, {"y", h.values[kHandY] + offset[1]}, {"z", hz + offset[2]}}, mr.seq);
    }
    if (t >= next_keepalive) {
      yoyo.KeepAlive();
      if (force) force->KeepAlive();
      next_keepalive = t + 1.0;
    }
    if (log) {
      const double row[] = {t, hz, yz, f, last_top, z_ref + o.level, stroke, s_t >= 0 ? s_t : NAN};
      log->Add(row);
    }
  } while (ReadUntil(hand, h.seq + 1, o.timeout_s, &h));
  if (log && !log->Finish()) throw std::runtime_error(log->error());
  if (log && log->dropped() > 0) {
    std::printf("yoyo_control: %ld log rows lost (the disk kept the writer waiting)\n", log->dropped());
  }

  if (o.check_from < 0) return 0;
  double worst = 0;
  int checked = 0;
  for (const Swing& s : swings) {
    if (s.t < o.check_from || s.t > o.check_from + o.check_for) continue;
    const double error = std::abs(s.top - z_ref - o.level) / o.level;
    ++checked, worst = std::max(worst, error);
    if (error > kTolerance) {
      std::printf("amplitude check failed: swing %d (top at t = %.2f s) amplitude %.4f m, level %.4f m (%.1f %%)\n",
                  s.n, s.t, s.top - z_ref, o.level, 100 * error);
      return 1;
    }
  }
  if (checked == 0 || t < o.check_from + o.check_for) {
    std::printf("amplitude check failed: the run ended at t = %.2f s with %d swings in [%g, %g] s\n", t, checked,
                o.check_from, o.check_from + o.check_for);
    return 1;
  }
  std::printf("amplitude check passed: %d swings in [%g, %g] s, amplitude error %.4f (max |top - level| / level)\n",
              checked, o.check_from, o.check_from + o.check_for, worst);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  if (!ParseOptions(argc, argv, &options)) {
    std::fprintf(stderr,
                 "usage: %s --hand HOST:PORT --yoyo HOST:PORT [--force HOST:PORT] [--mirror HOST:PORT] [--level M]\n"
                 "       [--string M] [--log FILE] [--check-from S --check-for S] [--timeout S] [--quiet]\n",
                 argv[0]);
    return 2;
  }
  return vlab::bridge::program::Main("yoyo_control", [&] { return Run(options); });
}
