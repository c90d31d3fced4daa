// vlab follow --from HOST:PORT --to HOST:PORT: makes one arm device follow another.
// Subscribes to the source arm's states (it never commands the source) and, each
// period of the target arm, sends the source's newest measured joint positions to
// the target as a position command answering the target's state. Any subsystem may
// be simulated by another program (docs/architecture.md): with vlab-kinsim as the
// source the lab's arm moves as the kinematic arm moves (lettered cubes stage 3), and
// with a real arm's driver as the source the simulator mirrors the real arm.
//
// Ports
//   input   source arm states (the newest; when none is new at a target period,
//           waited for up to 0.3 of that period); target arm states,
//           one per target period (the loop's clock: lockstep or realtime alike)
//   output  target arm commands: position mode, seq = the target state's seq
// The follower owns the target's command input (docs/protocol.md, "Ownership"):
// a target owned by another client for --timeout seconds is an error.
// Tracking error: max over joints of |q_target - q_source| per target period; "at
// rest" once the source has stood still (every |qd| <= kRestSpeed) for --settle
// seconds of its own time. --max-rest-error bounds the at-rest error (the verdict).
// Exit: 0 stopped by SIGINT/SIGTERM (and the bound held); 1 the bound was exceeded,
// or a device went silent or another client owned the target; 2 bad options, a
// device that does not answer, or source and target with other joints.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>

#include "bridge/bridge_client.h"
#include "bridge/bridge_program.h"
#include "cli/cli_commands.h"
#include "core/core_errors.h"

namespace vlab::cli {

namespace {

namespace program = bridge::program;
using bridge::Arm;
using bridge::ArmMode;
using Clock = std::chrono::steady_clock;

constexpr double kRestSpeed = 1e-3;   // rad/s: a source joint slower than this stands still
constexpr double kKeepAlive_s = 1.0;  // the source never gets commands: renew its subscription
// one connect attempt: a handshake resends its request only every 0.25 s, so to answer within
// a few tens of ms of a device's start, try afresh this often
constexpr double kConnectTry_s = 0.1;
// with no new source state at a target period, wait for one up to this fraction of the period:
// the command still reaches the target well before its next period
constexpr double kSourceWait = 0.3;

struct FollowArgs {
  std::string from, to;
  double connect_timeout_s = 10;
  double timeout_s = 2;
  double settle_s = 0.25;
  double max_rest_error = 0;  // rad; 0: no verdict
};

// what the loop counted
struct FollowCounters {
  long periods = 0, commands = 0, send_failed = 0, refused = 0, not_owner = 0, stale_source = 0;
  double max_moving = 0, max_rest = 0;  // rad
  long rest_periods = 0;
  int rest_joint = -1;
  double rest_time = 0;     // s, the target's time of max_rest
  double clock_offset = 0;  // s, source time - target time at the first command
};

// "2" or "0.5" for messages
std::string Num(double x) {
  char s[32];
  std::snprintf(s, sizeof s, "%g", x);
  return s;
}

double Seconds(Clock::time_point since) { return std::chrono::duration<double>(Clock::now() - since).count(); }

// HOST:PORT of an arm option, or exit 2 naming the option
program::Address ParseArm(const std::string& option, const std::string& text) {
  program::Address a;
  if (!program::ParseAddress(text, &a)) throw InputError("follow: " + option + " '" + text + "': expected HOST:PORT");
  return a;
}

// connects to an arm, trying until timeout_s (the device's program may be starting)
Arm ConnectArm(const std::string& option, const std::string& text, double timeout_s) {
  const program::Address a = ParseArm(option, text);
  const Clock::time_point start = Clock::now();
  for (;;) {
    try {
      return Arm::Connect(a.host, a.port, std::min(kConnectTry_s, timeout_s));
    } catch (const bridge::ProtocolError& e) {
      throw InputError("follow: " + option + " " + text + ": " + e.what());
    } catch (const bridge::BridgeError& e) {
      if (program::Stopped() || Seconds(start) >= timeout_s) {
        throw InputError("follow: " + option + " " + text + ": no arm answered within " + Num(timeout_s) + " s (" +
                         e.what() + ")");
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
}

// the newest state of `arm` within timeout_s into `state`; false when none came
bool Fresh(Arm& arm, double timeout_s, Arm::State* state) {
  try {
    arm.ReadLatest(std::max(0.0, timeout_s), state);
    return true;
  } catch (const bridge::TimeoutError&) {
    return false;
  }
}

std::string JointList(const Arm& arm) {
  std::string s;
  for (const std::string& j : arm.joint_names()) s += (s.empty() ? "" : ", ") + j;
  return s;
}

// the same joints in the same order, or exit 2 naming both devices
void CheckJoints(const Arm& from, const Arm& to) {
  if (from.joint_names() == to.joint_names()) return;
  throw InputError("follow: " + from.Label() + " has " + std::to_string(from.joints()) + " joints (" + JointList(from) +
                   "), " + to.Label() + " has " + std::to_string(to.joints()) + " (" + JointList(to) +
                   "): a follower needs the same joints in the same order");
}

int Follow(const FollowArgs& a) {
  InstallStopSignals();
  if (!(a.connect_timeout_s > 0)) throw InputError("follow: --connect-timeout must be > 0 s");
  if (!(a.timeout_s > 0)) throw InputError("follow: --timeout must be > 0 s");
  if (!(a.settle_s >= 0)) throw InputError("follow: --settle must be >= 0 s");
  if (!(a.max_rest_error >= 0)) throw InputError("follow: --max-rest-error must be >= 0 rad");
  ParseArm("--from", a.from);
  ParseArm("--to", a.to);
  // the target first: a lab in lockstep or realtime waits for its period 0 to be answered, so
  // its clock starts as soon as the source has sent a state (the source may start later)
  Arm to = ConnectArm("--to", a.to, a.connect_timeout_s);
  Arm from = ConnectArm("--from", a.from, a.connect_timeout_s);
  CheckJoints(from, to);
  Arm::State source, target;
  if (!program::ReadNext(from, a.timeout_s, &source)) {
    if (program::Stopped()) return 0;
    throw bridge::TimeoutError(from.Label() + ": no state within " + Num(a.timeout_s) + " s");
  }
  std::printf("vlab follow: %s (%d joints) -> %s\n", from.Label().c_str(), from.joints(), to.Label().c_str());
  std::fflush(stdout);

  FollowCounters c;
  Clock::time_point source_heard = Clock::now(), renewed = Clock::now(), owned = Clock::now();
  double last_target_time = -1;
  double rest_since = source.qd.cwiseAbs().maxCoeff() <= kRestSpeed ? source.time : -1;
  while (!program::Stopped()) {
    // the target's clock: its next state (lockstep: the one it waits on; realtime: the newest)
    if (!program::ReadNext(to, a.timeout_s, &target)) {
      if (program::Stopped()) break;
      throw bridge::TimeoutError(to.Label() + ": no state for " + Num(a.timeout_s) + " s");
    }
    // the source's newest state; when none came since the last period, wait for one a short
    // while (two clocks of one rate drift in and out of phase: the next state may be on its way)
    const double period_s = last_target_time < target.time ? target.time - last_target_time : 0;
    last_target_time = target.time;
    if (Fresh(from, 0.0, &source) || Fresh(from, kSourceWait * period_s, &source)) {
      source_heard = Clock::now();
      if (source.qd.cwiseAbs().maxCoeff() > kRestSpeed) {
        rest_since = -1;
      } else if (rest_since < 0) {
        rest_since = source.time;
      }
    } else {
      ++c.stale_source;
      if (Seconds(source_heard) > a.timeout_s) {
        throw bridge::TimeoutError(from.Label() + ": no state for " + Num(a.timeout_s) + " s");
      }
    }
    if (Seconds(renewed) > kKeepAlive_s) {
      from.KeepAlive();
      renewed = Clock::now();
    }
    if (to.Write(ArmMode::kPosition, source.q, target.seq)) {
      if (c.commands == 0) c.clock_offset = source.time - target.time;
      ++c.commands;
    } else {
      ++c.send_failed;
    }
    ++c.periods;
    if (target.status & bridge::kStatusRefused) ++c.refused;
    if (target.status & bridge::kStatusNotOwner) {
      ++c.not_owner;
      if (Seconds(owned) > a.timeout_s) {
        throw bridge::BridgeError(to.Label() + ": another client has owned its command input for " + Num(a.timeout_s) +
                                  " s");
      }
    } else {
      owned = Clock::now();
    }
    // tracking error of this target state against the source's newest
    Eigen::Index joint = 0;
    const double error = (target.q - source.q).cwiseAbs().maxCoeff(&joint);
    if (rest_since >= 0 && source.time - rest_since >= a.settle_s) {
      ++c.rest_periods;
      if (error > c.max_rest) {
        c.max_rest = error;
        c.rest_joint = static_cast<int>(joint);
        c.rest_time = target.time;
      }
    } else {
      c.max_moving = std::max(c.max_moving, error);
    }
  }

  std::printf(
      "vlab follow: %ld periods, %ld commands (%ld not sent), target states with refused %ld, not owner "
      "%ld; no new source state %ld; source time - target time at the first command %.3f s\n",
      c.periods, c.commands, c.send_failed, c.refused, c.not_owner, c.stale_source, c.clock_offset);
  std::printf("vlab follow: tracking error max %.6f rad while the source moved, %.6f rad at rest (%ld periods",
              c.max_moving, c.max_rest, c.rest_periods);
  if (c.rest_joint >= 0) {
    std::printf("; worst: joint %s at t = %.2f s", from.joint_names()[c.rest_joint].c_str(), c.rest_time);
  }
  std::printf(")\n");
  std::fflush(stdout);
  if (a.max_rest_error > 0 && (c.rest_periods == 0 || c.max_rest > a.max_rest_error)) {
    std::fprintf(stderr, "vlab follow: FAIL: tracking error at rest %.6f rad (%ld periods at rest), bound %.6f rad\n",
                 c.max_rest, c.rest_periods, a.max_rest_error);
    return 1;
  }
  return 0;
}

}  // namespace

Subcommand AddFollowCommand(CLI::App& app) {
  auto args = std::make_shared<FollowArgs>();
  CLI::App* cmd = app.add_subcommand(
      "follow",
      "Make one arm device follow another: each period of the --to arm, send it the --from arm's newest measured "
      "joint positions as a position command (e.g. the lab's arm following vlab-kinsim, or mirroring a real arm). "
      "Runs until SIGINT/SIGTERM, then prints its counters and tracking error. Exit: 0 stopped; 1 --max-rest-error "
      "exceeded, a device went silent or another client owned the --to arm; 2 bad options, a device that does not "
      "answer, or arms with other joints");
  cmd->add_option("--from", args->from, "Source arm, HOST:PORT: subscribed to, never commanded")->required();
  cmd->add_option("--to", args->to, "Target arm, HOST:PORT: its command input is taken")->required();
  cmd->add_option("--connect-timeout", args->connect_timeout_s,
                  "Keep trying to reach each arm this long, s (default 10)");
  cmd->add_option("--timeout", args->timeout_s,
                  "A device silent this long, or a --to arm owned by another client this long, ends the run (exit 1), "
                  "s (default 2)");
  cmd->add_option("--settle", args->settle_s,
                  "The source counts as at rest once every joint has been slower than 0.001 rad/s for this long, s "
                  "(default 0.25)");
  cmd->add_option("--max-rest-error", args->max_rest_error,
                  "Exit 1 at the end when the largest |q_to - q_from| at rest exceeds this, or no period was at rest, "
                  "rad (default 0: no bound)");
  return {cmd, [args] { return WithErrorReport([&] { return Follow(*args); }); }};
}

}  // namespace vlab::cli
