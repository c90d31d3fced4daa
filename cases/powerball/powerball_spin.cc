// powerball_spin: spins a PowerBall held at the PA10's JR3 up from its start spin by a
// circular wrist motion phase-locked to the rotor. An external 1 kHz program that talks to
// the devices only through the vlab client library; the same binary in every stage.
//
//   powerball_spin --arm ADDR --jr3 ADDR --counter ADDR [--target-rpm RPM] [--alpha-max DEG]
//                  [--delta DEG] [--wrist-speed RAD_S] [--start-at S] [--stop-at S] [--log FILE]
//                  [--timeout S] [--quiet]
//
// Devices: --arm, the PA10 (arm; its states pace the loop, one velocity command per state);
// --jr3, the wrench device at the ball's mount (filter 1 or 2: filter 4's 7.8 Hz cut-off
// would eat the rotating couple); --counter, the ball's own speed counter (counter kind:
// rpm, sample-and-hold at its gate rate, quantised). Lockstep: state k of the arm, then
// period k's states of the others; realtime: the arm's newest state, then the others' of
// that period or later.
//
// Geometry (cases/powerball/README.md, mjcf/pa10/pa10_powerball.xml): the groove normal e3
// is the flange's +x; the JR3's frame is the flange's. The wrist joints tilt e3: W1 by +t
// towards the flange's +z, W2 by +t towards its +y, so a cone of half-angle alpha at phase
// psi (measured in the groove plane from the flange's y towards its z) is
//   W1 = W1_0 + alpha sin psi,  W2 = W2_0 + alpha cos psi.
// The axle a = (0, cos phi, sin phi) in the same plane; its precession nu is positive about e3.
//
// 1. Rate: nu_ff = (r/R) omega, omega from the counter (rolling: omega = (R/r) nu).
// 2. Axle angle from the JR3: the walls' couple on the rotor I_s omega nu b, b = e3 x a,
//    reaches the sensor as -dH/dt of the tool side (the JR3 reads the load the tool side
//    applies). Gravity and the tool side's linear inertia go out exactly by subtracting
//    c x F (c: the tool side's centre of mass from the sensor, F the measured force, so
//    M - c x F = -dH_c/dt); its rotational inertia by adding I_c Omega', Omega' the cone's
//    own joint accelerations, -nu^2 times the tilts (analytic: a second difference of the
//    commands would feed the estimate's noise back amplified by 1 / dt^2). Then
//    b = -(M - c x F + I_c Omega') / |.|, phi = atan2(-b_y, b_z) in the groove plane (y, z),
//    after a first-order low-pass (kSmooth) of the two
//    components, delayed by that low-pass, the JR3 filter's group delay and a period.
// 3. Phase lock: a phase-locked loop phi_hat' = nu_ff + kPll wrap(phi_meas - phi_hat) (the
//    correction clipped to +-kPllMax: a stale or disturbed reading must not jerk the wrist), run
//    only once the couple stands out (|M| > kMinCouple); before, phi_hat free-runs at nu_ff
//    from the start estimate. The cone phase psi = phi_hat + s (delta - 90 deg) (s = sign of
//    nu; delta = 0 puts the axle on the groove's line of nodes, the law's optimum; the
//    spin-up law omega' = (r/R) omega nu sin(alpha) cos(delta), mjcf/powerball/README.md).
// 4. Cone angle: alpha = min(alpha_max, v_wrist / |nu|) (the wrist's joint speed alpha nu
//    stays under --wrist-speed), times a speed regulator (1 at and below target - kRegulatorBand
//    rpm, 0 at the target) so the rotor holds near the target instead of running away (the
//    law blows up in finite time), ramped in over the first kRamp_s and rate-limited
//    (kAlphaRate) so the tips are never slammed. With --start-at S the wrist is held still for
//    S s after the first state (the rotor coasts) and the ramp begins then. With --stop-at S
//    the drive stops at S s after the first state, as a user who stops turning the wrist: the
//    cone closes at the same rate, back onto the start pose, and the wrist is held still; the
//    rotor then coasts on its losses (a spin-down to identify them from: docs/identify.md).
// 5. Command: joint velocities, the cone's rate plus kPull times the position error (the
//    others held at the start pose); held still (not driving, the cone closed), 0, so that the
//    servo's reference stays put and the wrist gives to the rotor's couple on its own (a pull
//    would answer that wobble, and drive or brake the rotor with it). Clipped to
//    kMaxJointSpeed, changing by at most
//    kMaxVelocityStep from one command to the next.
// Logs FILE (CSV): time, counter rpm, nu_ff, alpha commanded and measured (deg, from W1 and
// W2), phi_hat, psi, |M| (N m).
// Ends when the arm is silent for --timeout s or on SIGTERM/SIGINT; exit 0; 2 on bridge errors.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>

#include <Eigen/Core>

#include <nlohmann/json.hpp>

#include "bridge/bridge_client.h"
#include "bridge/bridge_client_device.h"
#include "bridge/bridge_layouts.h"
#include "bridge/bridge_program.h"
#include "bridge/bridge_row_log.h"

namespace {

using vlab::bridge::Arm;
using vlab::bridge::Device;
using vlab::bridge::DeviceKind;
using vlab::bridge::Wrench;

using vlab::bridge::program::Address;
using vlab::bridge::program::kPoll_s;
using vlab::bridge::program::ParseAddress;
using vlab::bridge::program::ReadUntil;
using vlab::bridge::program::Stopped;

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;
constexpr double kConnect_s = 5.0;
constexpr int kCounterRpm = vlab::bridge::StateIndex(DeviceKind::kCounter, "rpm");
// the ball and its mount (mjcf/powerball/README.md, mjcf/pa10/pa10_powerball.xml)
constexpr double kRollRatio = 0.0012 / 0.027;  // r / R
// tool side beyond the JR3's measuring plane: JR3 half 0.085 kg at 6.25 mm, tool 0.1928 kg at
// 23.5 mm, ball 0.25 kg at 62.5 mm: centre of mass 39.2 mm out; inertia about it across the
// axis 5.2e-4 kg m^2 (README "Controller") [DERIVED]
constexpr double kComOffset_m = 0.0392, kToolInertia = 5.2e-4;
constexpr int kW1 = 5, kW2 = 6;                 // joint indices of W1 and W2 in the arm
constexpr double kPll = 4.0;                    // rad/s: phase-locked loop gain
constexpr double kPllMax = 2.0;                 // rad/s: its largest correction of the phase rate
constexpr double kSmooth = 2.0 * kPi * 20.0;    // rad/s: first-order low-pass of the couple
constexpr double kMinCouple = 0.02;             // N m: the axle angle is read above this
constexpr double kFilterDelay_s = 0.3 / 125.0;  // JR3 filter 2's group delay (sensors/sensor_wrench.h)
constexpr double kAlphaRate = 3.0 * kDeg;       // rad/s: how fast the cone angle may change
constexpr double kRamp_s = 3.0;                 // s: the cone angle's ramp at the start
constexpr double kRegulatorBand = 2500.0;       // rpm below the target where alpha tapers to 0
constexpr double kPull = 20.0;                  // 1/s: velocity per position error
constexpr double kMaxJointSpeed = 6.0;          // rad/s: under the arm's 2 pi wrist limit
// rad/s: the largest change from one command to the next. The cone needs alpha nu^2 dt, at
// most 0.22 rad/s per 1 ms period (12,000 rpm, 4.1 deg); a command after a stall of the
// loop (realtime, a loaded machine: 21 ms seen) would step by that times the stall, and a
// velocity step of dv costs the servo kd dv of torque (a 15 N m spike on W1)
constexpr double kMaxVelocityStep = 0.5;

struct Options {
  Address arm, jr3, counter;
  double target_rpm = 12000, alpha_max_deg = 10, delta_deg = 0, wrist_speed = 4.0, timeout_s = 2.0;
  double start_at_s = 0.0;  // s: the drive starts then
  double stop_at_s = -1.0;  // s: the drive stops then; < 0: never
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
    if (arg == "--arm")
      ok = ParseAddress(v, &o->arm);
    else if (arg == "--jr3")
      ok = ParseAddress(v, &o->jr3);
    else if (arg == "--counter")
      ok = ParseAddress(v, &o->counter);
    else if (arg == "--target-rpm")
      o->target_rpm = std::atof(v.c_str());
    else if (arg == "--alpha-max")
      o->alpha_max_deg = std::atof(v.c_str());
    else if (arg == "--delta")
      o->delta_deg = std::atof(v.c_str());
    else if (arg == "--wrist-speed")
      o->wrist_speed = std::atof(v.c_str());
    else if (arg == "--start-at")
      ok = (o->start_at_s = std::atof(v.c_str())) >= 0.0;
    else if (arg == "--stop-at")
      ok = (o->stop_at_s = std::atof(v.c_str())) >= 0.0;
    else if (arg == "--log")
      o->log = v;
    else if (arg == "--timeout")
      o->timeout_s = std::atof(v.c_str());
    else
      return false;
    if (!ok) return false;
  }
  return o->arm.port > 0 && o->jr3.port > 0 && o->counter.port > 0 && o->target_rpm > 0 && o->alpha_max_deg > 0 &&
         o->alpha_max_deg <= 15 && o->wrist_speed > 0 && o->timeout_s > 0;
}

double Wrap(double angle) { return std::remainder(angle, 2.0 * kPi); }

// the arm's next state: period seq + 1 in lockstep, else the newest one after `a`
bool NextArmState(Arm& arm, bool per_period, double timeout_s, Arm::State* a) {
  if (per_period) return ReadUntil(arm, a->seq + 1, timeout_s, a);
  for (double waited = 0; !Stopped() && waited < timeout_s; waited += kPoll_s) {
    try {
      const std::int64_t last = a->seq;
      arm.ReadLatest(kPoll_s, a);
      if (a->seq > last) return true;
    } catch (const vlab::bridge::TimeoutError&) {
    }
  }
  return false;
}

int Run(const Options& o) {
  Arm arm = Arm::Connect(o.arm.host, o.arm.port, kConnect_s);
  Wrench jr3 = Wrench::Connect(o.jr3.host, o.jr3.port, kConnect_s);
  Device counter = Device::Connect(DeviceKind::kCounter, o.counter.host, o.counter.port, kConnect_s);
  if (arm.joints() != 7) {
    std::fprintf(stderr, "powerball_spin: arm '%s' has %d joints, not the PA10's 7\n", arm.name().c_str(),
                 arm.joints());
    return 2;
  }
  // lockstep: every period in turn; otherwise (realtime) the newest state, skipping any the
  // loop fell behind on, so that a command never answers an old state
  const bool per_period = arm.describe().value("clock", "") == "lockstep";
  Arm::State a;
  Wrench::State w;
  Device::State c;
  if (!ReadUntil(arm, 0, o.timeout_s + kConnect_s, &a)) return Stopped() ? 0 : 2;
  const Eigen::VectorXd q0 = a.q;
  const double t0 = a.time;
  // (written by its own thread: the loop never waits for the disk)
  std::unique_ptr<vlab::bridge::program::RowLog> log;
  if (!o.log.empty()) {
    log = vlab::bridge::program::RowLog::Open(o.log, {{"time", 4},
                                                      {"counter_rpm", 1},
                                                      {"nu_ff", 4},
                                                      {"alpha_deg", 4},
                                                      {"alpha_measured_deg", 4},
                                                      {"phi_hat", 4},
                                                      {"psi", 4},
                                                      {"couple", 5}});
  }

  const double delta = o.delta_deg * kDeg, alpha_max = o.alpha_max_deg * kDeg;
  double phi_hat = 0, alpha = 0, t_prev = 0, next_keepalive = 1.0, t = 0;
  double accel[2] = {0, 0}, m_y = 0, m_z = 0;
  bool locked = false, first = true;
  Eigen::VectorXd v_cmd = Eigen::VectorXd::Zero(7);
  double alpha_prev = 0;
  do {
    t = a.time - t0;
    if (!ReadUntil(jr3, a.seq, o.timeout_s, &w)) break;
    if (!ReadUntil(counter, a.seq, o.timeout_s, &c)) break;
    const double dt = first ? 0.0 : t - t_prev;
    t_prev = t;
    const double omega = c.values[kCounterRpm] * 2.0 * kPi / 60.0;
    const double nu_ff = kRollRatio * omega;
    const double s = nu_ff >= 0 ? 1.0 : -1.0;

    // 2. the rotor's couple in the groove plane (flange y, z), gravity and inertia removed
    const Eigen::Matrix<double, 6, 1>& f = w.wrench;
    const double raw_y = f(4) - kComOffset_m * f(0) - kToolInertia * accel[0];  // W1 turns about -y
    const double raw_z = f(5) + kToolInertia * accel[1];                        // W2 turns about +z
    const double smooth = first ? 1.0 : 1.0 - std::exp(-kSmooth * dt);
    m_y += smooth * (raw_y - m_y);
    m_z += smooth * (raw_z - m_z);
    const double couple = std::hypot(m_y, m_z);
    // b = -M / |M|; a = b x e3 (e3 = x): phi = atan2(-b_y, b_z) = atan2(m_y, -m_z)
    const double lag = nu_ff * (kFilterDelay_s + dt) + std::atan(nu_ff / kSmooth);
    const double phi_meas = std::atan2(m_y, -m_z) + lag;
    // 3. phase lock
    if (first) phi_hat = phi_meas;
    if (couple > kMinCouple) locked = true;
    const double pull = couple > kMinCouple ? std::clamp(kPll * Wrap(phi_meas - phi_hat), -kPllMax, kPllMax) : 0.0;
    phi_hat += dt * (nu_ff + pull);
    phi_hat = Wrap(phi_hat);
    // 4. cone angle: wrist speed cap, speed regulator, ramp, rate limit
    const double rpm = std::abs(c.values[kCounterRpm]);
    const double cap = std::min(alpha_max, o.wrist_speed / std::max(std::abs(nu_ff), 1e-3));
    const double regulate = std::clamp((o.target_rpm - rpm) / kRegulatorBand, 0.0, 1.0);
    const bool driving = t >= o.start_at_s && (o.stop_at_s < 0.0 || t < o.stop_at_s);
    const double wanted = driving ? cap * regulate * std::min(1.0, (t - o.start_at_s) / kRamp_s) : 0.0;
    alpha += std::clamp(wanted - alpha, -kAlphaRate * dt, kAlphaRate * dt);
    // 5. velocity command: the cone's rate plus a slow pull (kPull) onto the cone and, for
    // the other joints, onto the start pose. A velocity command survives a late or missed
    // period in realtime (the drive keeps integrating it); a position command would not.
    const double phase_rate = nu_ff + pull;
    const double alpha_rate = dt > 0 ? (alpha - alpha_prev) / dt : 0.0;
    alpha_prev = alpha;
    const double psi = phi_hat + s * (delta - 0.5 * kPi);
    const double theta[2] = {alpha * std::sin(psi), alpha * std::cos(psi)};
    const double theta_rate[2] = {alpha_rate * std::sin(psi) + alpha * phase_rate * std::cos(psi),
                                  alpha_rate * std::cos(psi) - alpha * phase_rate * std::sin(psi)};
    // the cone's joint accelerations, analytic (psi turning at nu_ff): -nu^2 theta
    accel[0] = -nu_ff * nu_ff * theta[0];
    accel[1] = -nu_ff * nu_ff * theta[1];
    // not driving and the cone closed: the wrist held still, its servo's reference frozen (a
    // velocity of 0), so that the rotor coasts on its losses alone; a pull onto the pose would
    // answer the wrist's wobble under the rotor's couple and drive or brake the rotor with it
    const bool holding = !driving && alpha == 0.0;
    for (int i = 0; i < 7; ++i) {
      double target = q0(i), rate = 0.0;
      if (i == kW1) target += theta[0], rate = theta_rate[0];
      if (i == kW2) target += theta[1], rate = theta_rate[1];
      const double wanted_v =
          holding ? 0.0 : std::clamp(rate + kPull * (target - a.q(i)), -kMaxJointSpeed, kMaxJointSpeed);
      v_cmd(i) += std::clamp(wanted_v - v_cmd(i), -kMaxVelocityStep, kMaxVelocityStep);
    }
    arm.Write(vlab::bridge::ArmMode::kVelocity, v_cmd, a.seq);
    first = false;
    if (t >= next_keepalive) {
      jr3.KeepAlive();
      counter.KeepAlive();
      next_keepalive = t + 1.0;
      if (!o.quiet) {
        std::printf("t %.0f s: counter %.0f rpm, alpha %.2f deg, couple %.3f N m%s\n", t, c.values[kCounterRpm],
                    alpha / kDeg, couple, locked ? "" : " (not locked yet)");
        std::fflush(stdout);
      }
    }
    if (log) {
      // the cone the wrist made: the tilt of e3 from the measured W1, W2
      const double alpha_measured = std::hypot(a.q(kW1) - q0(kW1), a.q(kW2) - q0(kW2));
      const double row[] = {
          t, c.values[kCounterRpm], nu_ff, alpha / kDeg, alpha_measured / kDeg, phi_hat, Wrap(psi), couple};
      log->Add(row);
    }
  } while (NextArmState(arm, per_period, o.timeout_s, &a));
  if (log && !log->Finish()) throw std::runtime_error(log->error());
  if (log && log->dropped() > 0) {
    std::printf("powerball_spin: %ld log rows lost (the disk kept the writer waiting)\n", log->dropped());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  if (!ParseOptions(argc, argv, &options)) {
    std::fprintf(stderr,
                 "usage: %s --arm HOST:PORT --jr3 HOST:PORT --counter HOST:PORT [--target-rpm RPM]\n"
                 "       [--alpha-max DEG (<= 15)] [--delta DEG] [--wrist-speed RAD_S] [--start-at S] [--stop-at S]\n"
                 "       [--log FILE] [--timeout S] [--quiet]\n",
                 argv[0]);
    return 2;
  }
  return vlab::bridge::program::Main("powerball_spin", [&] { return Run(options); });
}
