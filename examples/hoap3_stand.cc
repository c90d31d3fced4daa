// hoap3_stand: a standing, squatting and waving script for the Fujitsu HOAP-3, an
// external program that talks to the robot only through the vlab client library
// (bridge/bridge_client.h, bridge/bridge_client_device.h).
//
//   hoap3_stand [--arm HOST:PORT] [--feet HOST:PORT] [--stand S] [--max-error E]
//               [--timeout S] [--quiet]
//
// It reads the arm's first state (28 joints, SL names: mjcf/hoap3/README.md) and
// holds that pose, in position mode, like the HOAP-3's own 1 kHz servo interface:
//   0 .. S        stand (S = --stand, 30 s by default)
//   S .. S+5      squat: knees +0.8 rad in 2 s, hold 1 s, up in 2 s; the hips and
//                 ankles turn half as much each, so the soles stay flat
//   S+6 .. S+11   right-arm wave: the upper arm swings out and turns the forearm up
//                 in 1 s, the elbow waves 0.4 rad at 1 Hz for 3 s, the arm comes back
//   then          stand, until the device stops sending
// Time is the state's simulated time relative to the first state's, so the same
// program runs against a lockstep server (which waits for each command) and a
// realtime one (paced by the wall clock); each period it answers the newest state.
// With --feet it also reads the feet device (8 FSR forces, N) and reports their sum.
//
// It ends when no state arrives for --timeout seconds (2 s by default: the run is
// over) or on SIGTERM / SIGINT, and prints "max tracking error: X rad" (the
// largest |q_des - q| of any joint after the first 0.5 s). Exit 0; 1 when
// --max-error is given and exceeded; 2 on a bridge error (printed) or bad arguments.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <string>

#include <Eigen/Core>

#include "bridge/bridge_client.h"
#include "bridge/bridge_client_device.h"
#include "bridge/bridge_program.h"

namespace {

using Eigen::VectorXd;
using vlab::bridge::Arm;
using vlab::bridge::ArmMode;
using vlab::bridge::Device;

using vlab::bridge::program::Address;
using vlab::bridge::program::ParseAddress;
using vlab::bridge::program::ReadNext;
using vlab::bridge::program::Stopped;

struct Options {
  Address arm{"127.0.0.1", 50020};
  Address feet;             // port 0: no feet client
  double stand_s = 30.0;    // standing before the squat, s
  double max_error = -1.0;  // rad; < 0: not checked
  double timeout_s = 2.0;   // silence that ends the run, s
  bool quiet = false;
};

constexpr double kSettle_s = 0.5;   // the pads sink into the floor at first
constexpr double kConnect_s = 5.0;  // describe reply wait

bool ParseOptions(int argc, char** argv, Options* o) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--quiet") {
      o->quiet = true;
      continue;
    }
    if (i + 1 >= argc) return false;
    const std::string value = argv[++i];
    if (arg == "--arm") {
      if (!ParseAddress(value, &o->arm)) return false;
    } else if (arg == "--feet") {
      if (!ParseAddress(value, &o->feet)) return false;
    } else if (arg == "--stand") {
      o->stand_s = std::atof(value.c_str());
    } else if (arg == "--max-error") {
      o->max_error = std::atof(value.c_str());
    } else if (arg == "--timeout") {
      o->timeout_s = std::atof(value.c_str());
    } else {
      return false;
    }
  }
  return o->stand_s >= 0 && o->timeout_s > 0;
}

// quintic time scaling on [0, 1]: zero velocity and acceleration at both ends
double Quintic(double s) {
  s = std::clamp(s, 0.0, 1.0);
  return s * s * s * (10 - 15 * s + 6 * s * s);
}

// The script: joint indices by SL name and the start pose.
struct Script {
  VectorXd q0;
  double stand_s = 30;
  int rl3 = -1, rl4 = -1, rl5 = -1, ll3 = -1, ll4 = -1, ll5 = -1, ra2 = -1, ra3 = -1, ra4 = -1;

  // desired joint positions at time t after the first state, rad
  void Sample(double t, VectorXd* q) const {
    *q = q0;
    // squat: knees bend by 0.8 rad, hips and ankles by 0.4 rad (soles stay flat)
    const double ts = t - stand_s;
    const double s = ts < 3 ? Quintic(ts / 2) : 1 - Quintic((ts - 3) / 2);
    (*q)[rl3] += 0.4 * s, (*q)[rl4] += 0.8 * s, (*q)[rl5] -= 0.4 * s;
    (*q)[ll3] -= 0.4 * s, (*q)[ll4] -= 0.8 * s, (*q)[ll5] += 0.4 * s;
    // wave: arm out and forearm up, the elbow waves at 1 Hz (eased in and out), back
    const double tw = t - stand_s - 6;
    const double out = tw < 4 ? Quintic(tw) : 1 - Quintic(tw - 4);
    const double envelope = Quintic((tw - 1) / 0.5) * (1 - Quintic((tw - 3.5) / 0.5));
    const double swing = envelope * 0.4 * std::sin(2 * M_PI * (tw - 1));
    (*q)[ra2] -= 1.3 * out, (*q)[ra3] += 1.3 * out, (*q)[ra4] += 0.8 * out + swing;
  }
};

int Index(const Arm& arm, const std::string& joint) {
  const auto& names = arm.joint_names();
  const auto it = std::find(names.begin(), names.end(), joint);
  return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}

int Run(const Options& o) {
  Arm arm = Arm::Connect(o.arm.host, o.arm.port, kConnect_s);
  std::unique_ptr<Device> feet;
  if (o.feet.port > 0) {
    feet = std::make_unique<Device>(
        Device::Connect(vlab::bridge::DeviceKind::kFeet, o.feet.host, o.feet.port, kConnect_s));
  }
  Script script;
  script.stand_s = o.stand_s;
  int* indices[] = {&script.rl3, &script.rl4, &script.rl5, &script.ll3, &script.ll4,
                    &script.ll5, &script.ra2, &script.ra3, &script.ra4};
  const char* names[] = {"RL_J3", "RL_J4", "RL_J5", "LL_J3", "LL_J4", "LL_J5", "RA_J2", "RA_J3", "RA_J4"};
  for (int i = 0; i < 9; ++i) {
    *indices[i] = Index(arm, names[i]);
    if (*indices[i] < 0) {
      std::fprintf(stderr, "hoap3_stand: %s has no joint %s: not a HOAP-3\n", arm.Label().c_str(), names[i]);
      return 2;
    }
  }
  const std::size_t n = static_cast<std::size_t>(arm.joints());
  if (arm.position_min().size() != n || arm.position_max().size() != n) {
    std::fprintf(stderr, "hoap3_stand: %s describes no position limits\n", arm.Label().c_str());
    return 2;
  }
  if (!o.quiet) {
    std::printf("connected to %s (%d joints)%s\n", arm.Label().c_str(), arm.joints(), feet ? ", feet" : "");
    std::fflush(stdout);
  }

  Arm::State state;
  if (!ReadNext(arm, o.timeout_s + kConnect_s, &state)) {
    std::fprintf(stderr, "hoap3_stand: no state from %s\n", arm.Label().c_str());
    return Stopped() ? 0 : 2;
  }
  const double t0 = state.time;
  script.q0 = state.q;
  const Eigen::Map<const VectorXd> lower(arm.position_min().data(), arm.joints());
  const Eigen::Map<const VectorXd> upper(arm.position_max().data(), arm.joints());
  VectorXd q_des(arm.joints());
  double max_error = 0, sum_min = std::numeric_limits<double>::infinity(), sum_max = 0, next_keepalive = 1.0;
  const char* phases[] = {"squat", "wave", "stand"};
  const double phase_start[] = {o.stand_s, o.stand_s + 6, o.stand_s + 11};
  int phase = 0;
  do {
    const double t = state.time - t0;
    script.Sample(t, &q_des);
    q_des = q_des.cwiseMax(lower).cwiseMin(upper);  // a command beyond a limit would be refused
    if (t >= kSettle_s) max_error = std::max(max_error, (q_des - state.q).cwiseAbs().maxCoeff());
    arm.Write(ArmMode::kPosition, q_des, state.seq);
    if (feet) {
      try {
        const Device::State f = feet->ReadLatest(0.01);  // published with the arm's state
        double sum = 0;
        for (double v : f.values) sum += v;
        if (t >= kSettle_s) sum_min = std::min(sum_min, sum), sum_max = std::max(sum_max, sum);
      } catch (const vlab::bridge::TimeoutError&) {
      }
      if (t >= next_keepalive) {  // a client that never writes stays subscribed
        feet->KeepAlive();
        next_keepalive = t + 1.0;
      }
    }
    while (!o.quiet && phase < 3 && t >= phase_start[phase]) {
      std::printf("t = %.3f s: %s; max tracking error so far %.6f rad\n", t, phases[phase++], max_error);
      std::fflush(stdout);
    }
  } while (ReadNext(arm, o.timeout_s, &state));

  std::printf("max tracking error: %.6f rad\n", max_error);
  if (feet && sum_max > 0) std::printf("FSR sum: min %.3f N, max %.3f N\n", sum_min, sum_max);
  if (o.max_error >= 0 && max_error > o.max_error) {
    std::printf("exceeds --max-error %g rad\n", o.max_error);
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  if (!ParseOptions(argc, argv, &options)) {
    std::fprintf(stderr,
                 "usage: %s [--arm HOST:PORT] [--feet HOST:PORT] [--stand S] [--max-error E (rad)] "
                 "[--timeout S] [--quiet]\n",
                 argv[0]);
    return 2;
  }
  return vlab::bridge::program::Main("hoap3_stand", [&] { return Run(options); });
}
