// joint_control: a joint-space controller for the PA10, an external program that
// talks to the arm only through the vlab client library (bridge/bridge_client.h).
//
//   joint_control [--arm HOST:PORT] [--gain K] [--max-error E] [--duration S] [--quiet]
//
// It reads the arm's first state, then moves through a fixed set of poses along
// quintic joint paths (about 2 s each, longer when the arm's velocity limits ask
// for it) and back to the start pose, in velocity mode:
//     qd_cmd = qd_des + K (q_des - q),   K = 10 /s by default.
// Each period: read the newest state, compute, answer it with seq = state.seq.
// Time is the state's simulated time relative to the first state's, so the same
// program runs against a lockstep server (which waits for each command) and a
// realtime one (paced by the wall clock).
//
// With --duration S it repeats the round trip (which starts and ends at rest at
// the start pose) until S seconds of simulated time, e.g. for benchmarks.
//
// Output: one line per pose reached with the largest tracking error so far
// (not with --quiet), then "max tracking error: X rad". Exit 0; 1 when --max-error is given and exceeded;
// 2 on a bridge error (printed) or bad arguments.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "bridge/bridge_client.h"

namespace {

using Eigen::VectorXd;
using vlab::bridge::Arm;
using vlab::bridge::ArmMode;

struct Options {
  std::string host = "127.0.0.1";
  int port = 50010;
  double gain = 10.0;       // 1/s
  double max_error = -1.0;  // rad; < 0: not checked
  double duration = 0.0;    // s of simulated time; 0: one round trip and a short hold
  bool quiet = false;
};

constexpr double kSegment_s = 2.0;  // nominal duration of one move
constexpr double kHold_s = 0.5;     // hold at the end before stopping
constexpr double kReadTimeout_s = 1.0;

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
      const std::size_t colon = value.rfind(':');
      if (colon == std::string::npos) return false;
      o->host = value.substr(0, colon);
      if (o->host.size() > 2 && o->host.front() == '[' && o->host.back() == ']') {
        o->host = o->host.substr(1, o->host.size() - 2);  // [IPv6]:port
      }
      o->port = std::atoi(value.c_str() + colon + 1);
    } else if (arg == "--gain") {
      o->gain = std::atof(value.c_str());
    } else if (arg == "--max-error") {
      o->max_error = std::atof(value.c_str());
    } else if (arg == "--duration") {
      o->duration = std::atof(value.c_str());
    } else {
      return false;
    }
  }
  return o->gain >= 0 && o->duration >= 0;
}

// A path through waypoints: quintic time scaling s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5
// on each segment (zero velocity and acceleration at both ends).
struct Path {
  std::vector<VectorXd> poses;
  std::vector<double> end_s;  // end time of each segment, s

  double duration() const { return end_s.back(); }

  void Sample(double t, VectorXd* q_des, VectorXd* qd_des) const {
    std::size_t i = 0;
    while (i + 1 < end_s.size() && t > end_s[i]) ++i;
    const double begin = i == 0 ? 0.0 : end_s[i - 1];
    const double length = end_s[i] - begin;
    const double tau = std::clamp((t - begin) / length, 0.0, 1.0);
    const double s = tau * tau * tau * (10 - 15 * tau + 6 * tau * tau);
    const double ds = 30 * tau * tau * (1 - 2 * tau + tau * tau) / length;
    *q_des = poses[i] + s * (poses[i + 1] - poses[i]);
    *qd_des = ds * (poses[i + 1] - poses[i]);
  }
};

// start -> two poses within the PA10's limits -> start; a segment is stretched
// so that its peak speed (15/8 of the mean) stays below 80% of a velocity limit
Path MakePath(const VectorXd& start, const std::vector<double>& velocity_max) {
  Path path;
  VectorXd a(7), b(7);
  a << 0.3, 0.2, 0.2, 1.2, -0.3, 1.0, 0.5;
  b << -0.3, 0.4, -0.2, 0.9, 0.3, 1.4, -0.5;
  path.poses = {start, a, b, start};
  double t = 0;
  for (std::size_t i = 0; i + 1 < path.poses.size(); ++i) {
    double length = kSegment_s;
    for (int j = 0; j < 7 && !velocity_max.empty(); ++j) {
      const double distance = std::abs(path.poses[i + 1][j] - path.poses[i][j]);
      length = std::max(length, 1.875 * distance / (0.8 * velocity_max[j]));
    }
    t += length;
    path.end_s.push_back(t);
  }
  return path;
}

int Run(const Options& o) {
  Arm arm = Arm::Connect(o.host, o.port, kReadTimeout_s);
  if (arm.joints() != 7) {
    std::fprintf(stderr, "joint_control: %s has %d joints, this controller drives 7\n", arm.Label().c_str(),
                 arm.joints());
    return 2;
  }
  if (!o.quiet) std::printf("connected to %s\n", arm.Label().c_str());

  Arm::State state = arm.Read(kReadTimeout_s);
  const double t0 = state.time;
  const Path path = MakePath(state.q, arm.velocity_max());
  VectorXd q_des(7), qd_des(7), qd_cmd(7);
  double max_error = 0;
  std::size_t poses_reported = 0;

  const double end = o.duration > 0 ? o.duration : path.duration() + kHold_s;
  for (;;) {
    const double t = state.time - t0;
    // the round trip starts and ends at rest at the start pose: it repeats seamlessly
    path.Sample(o.duration > 0 ? std::fmod(t, path.duration()) : t, &q_des, &qd_des);
    max_error = std::max(max_error, (q_des - state.q).cwiseAbs().maxCoeff());
    // one line per pose reached
    while (!o.quiet && poses_reported < path.end_s.size() && t >= path.end_s[poses_reported]) {
      ++poses_reported;
      std::printf("pose %zu of %zu at t = %.3f s: max tracking error so far %.6f rad\n", poses_reported,
                  path.end_s.size(), t, max_error);
    }
    if (t >= end) break;

    qd_cmd = qd_des + o.gain * (q_des - state.q);
    for (int j = 0; j < 7 && !arm.velocity_max().empty(); ++j) {
      const double limit = 0.95 * arm.velocity_max()[j];
      qd_cmd[j] = std::clamp(qd_cmd[j], -limit, limit);
    }
    arm.Write(ArmMode::kVelocity, qd_cmd, state.seq);
    arm.ReadLatest(kReadTimeout_s, &state);  // lockstep: the next one; realtime: the newest
  }
  arm.Write(ArmMode::kHold, VectorXd(), state.seq);

  std::printf("max tracking error: %.6f rad\n", max_error);
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
                 "usage: %s [--arm HOST:PORT] [--gain K (1/s)] [--max-error E (rad)] [--duration S] [--quiet]\n",
                 argv[0]);
    return 2;
  }
  try {
    return Run(options);
  } catch (const vlab::bridge::BridgeError& e) {
    std::fprintf(stderr, "joint_control: %s\n", e.what());
    return 2;
  }
}
