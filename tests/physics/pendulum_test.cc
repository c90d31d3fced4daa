// Pendulums against closed forms: MuJoCo's hinge dynamics, RK4 and semi-implicit Euler.
//
// 1. Simple (physical) pendulum released from rest at theta0: the exact period is
//      T = 4 sqrt(I_pivot / (m g L)) K(sin(theta0 / 2)),   I_pivot = I_c + m L^2,
//    with K the complete elliptic integral of the first kind, computed here by the
//    arithmetic-geometric mean and cross-checked against std::comp_ellint_1 and the
//    closed form K(1/sqrt 2) = Gamma(1/4)^2 / (4 sqrt(pi)).
//    With semi-implicit Euler (constant mass matrix: symplectic) the energy oscillates as the
//    modified-energy expansion predicts, E - E0 = (h/2)(P - P0) + O(h^2), with no secular change.
// 2. Passive double pendulum from a chaotic start, 20 s: the total energy MuJoCo reports
//    equals our own T + V from qpos/qvel and the body parameters; RK4 conserves it to 1e-6
//    with a fourth-order error; semi-implicit Euler (configuration-dependent mass matrix: not
//    symplectic) never gains energy but loses O(h) per unit time, first order in h.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include "mujoco_fixture.h"

namespace vlab::lab {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;
constexpr double kG = 9.81;

// ---------------------------------------------------------------------------------------
// complete elliptic integral of the first kind

double ArithmeticGeometricMean(double a, double b) {
  // converges quadratically: 6 iterations reach double precision for b/a >= 1e-3
  for (int i = 0; i < 60 && std::abs(a - b) > 1e-16 * a; ++i) {
    const double next_a = 0.5 * (a + b);
    b = std::sqrt(a * b);
    a = next_a;
  }
  return 0.5 * (a + b);
}

// K(k) = pi / (2 AGM(1, k')), k' = sqrt(1 - k^2) written as sqrt((1 - k)(1 + k)) so that
// k near 1 keeps its digits
double EllipticK(double k) { return kPi / (2.0 * ArithmeticGeometricMean(1.0, std::sqrt((1.0 - k) * (1.0 + k)))); }

TEST(EllipticK, AgmEqualsStandardLibraryAndClosedForms) {
  EXPECT_DOUBLE_EQ(EllipticK(0.0), kPi / 2);
  // lemniscatic case: K(1/sqrt 2) = Gamma(1/4)^2 / (4 sqrt(pi))
  const double lemniscatic = std::pow(std::tgamma(0.25), 2) / (4.0 * std::sqrt(kPi));
  EXPECT_NEAR(EllipticK(1.0 / std::sqrt(2.0)), lemniscatic, 1e-14 * lemniscatic);
  for (double theta0_deg : {1.0, 10.0, 45.0, 90.0, 135.0, 170.0, 179.0}) {
    const double k = std::sin(0.5 * theta0_deg * kDeg);
    const double reference = std::comp_ellint_1(k);
    // near k = 1 (179 deg: k' = 0.0087) evaluating 1 - k^2 loses ~4 digits: K is then
    // conditioned at ~1e-13, whichever way it is computed
    EXPECT_NEAR(EllipticK(k), reference, 1e-13 * reference) << "theta0 " << theta0_deg;
  }
}

// ---------------------------------------------------------------------------------------
// simple pendulum

// pivot 2 m above the floor, hinge about +y, COM kLength below the pivot; the central
// inertia is anisotropic so that picking the wrong component would change the period
constexpr double kMass = 1.3;           // kg
constexpr double kLength = 0.5;         // pivot to COM, m
constexpr double kInertiaAxis = 0.012;  // central inertia about the hinge (y), kg m^2
constexpr double kInertiaPivot = kInertiaAxis + kMass * kLength * kLength;  // 0.337 kg m^2

// Timestep: the small-angle rate w0 = sqrt(m g L / I_pivot) = 4.35 rad/s bounds the local
// linearised rate sqrt(|V''(theta)| / I_pivot) = w0 sqrt(|cos theta|) at every amplitude.
// RK4 on a harmonic oscillator advances the phase by w h (1 - (w h)^4 / 120 + ...), so the
// relative period error is (w0 h)^4 / 120 = 3e-12 at h = 1 ms, and its amplitude decays
// by (w h)^6 / 144 per step (1e-16: it cannot shift the amplitude-dependent period). The
// cubic Hermite interpolation of a crossing is off by h^4 |theta''''| / 384 in angle, i.e.
// about (w0 h)^4 / (384 * 2 pi) = 1.5e-13 of a period. Both are >= 3000x below 1e-8.
constexpr double kPendulumStep = 1e-3;

std::string SimplePendulumXml(const char* integrator, double timestep) {
  char xml[1024];
  std::snprintf(xml, sizeof(xml), R"(
<mujoco model="simple_pendulum">
  <option timestep="%.17g" integrator="%s" gravity="0 0 %.17g"/>
  <worldbody>
    <body name="bob" pos="0 0 2">
      <joint name="hinge" type="hinge" axis="0 1 0"/>
      <inertial pos="0 0 %.17g" mass="%.17g" diaginertia="0.031 %.17g 0.027"/>
    </body>
  </worldbody>
</mujoco>)",
                timestep, integrator, -kG, -kLength, kMass, kInertiaAxis);
  return xml;
}

// root in [0, 1] of the cubic Hermite interpolant through (0, y0, slope d0) and (1, y1, d1),
// y0 > 0 >= y1 (slopes per unit of s); bisection to machine precision
double HermiteRoot(double y0, double d0, double y1, double d1) {
  const auto p = [&](double s) {
    const double s2 = s * s, s3 = s2 * s;
    return (2 * s3 - 3 * s2 + 1) * y0 + (s3 - 2 * s2 + s) * d0 + (-2 * s3 + 3 * s2) * y1 + (s3 - s2) * d1;
  };
  double lo = 0.0, hi = 1.0;
  for (int i = 0; i < 200 && hi - lo > 1e-17; ++i) {
    const double mid = 0.5 * (lo + hi);
    (p(mid) > 0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// mean time between downward zero crossings of theta over `periods` periods
double MeasurePeriod(const mjModel* model, mjData* data, double theta0, int periods, double expected_period) {
  mj_resetData(model, data);
  data->qpos[0] = theta0;
  const double h = model->opt.timestep;
  const long max_steps = static_cast<long>((periods + 1.5) * expected_period / h);
  std::vector<double> crossings;
  for (long step = 0; step < max_steps && static_cast<int>(crossings.size()) <= periods; ++step) {
    const double theta_a = data->qpos[0], omega_a = data->qvel[0];
    mj_step(model, data);
    const double theta_b = data->qpos[0], omega_b = data->qvel[0];
    if (theta_a > 0 && theta_b <= 0) {
      // times from the step count (no accumulated round-off in data->time)
      const double s = HermiteRoot(theta_a, omega_a * h, theta_b, omega_b * h);
      crossings.push_back((static_cast<double>(step) + s) * h);
    }
  }
  if (static_cast<int>(crossings.size()) != periods + 1) {
    ADD_FAILURE() << "theta0 " << theta0 / kDeg << " deg: " << crossings.size() << " downward crossings, expected "
                  << periods + 1;
    return 0.0;
  }
  return (crossings.back() - crossings.front()) / periods;
}

using SimplePendulum = vlab::test::MujocoTest;

TEST_F(SimplePendulum, PeriodEqualsEllipticIntegralClosedForm) {
  const mjModel* model = LoadModelFromString("simple_pendulum.xml", SimplePendulumXml("RK4", kPendulumStep));
  mjData* data = MakeData(model);
  ASSERT_EQ(model->nv, 1);
  ASSERT_EQ(model->opt.integrator, mjINT_RK4);
  // the body is what we wrote: no inertia from geoms, no armature, damping or friction
  ASSERT_DOUBLE_EQ(model->body_mass[1], kMass);
  ASSERT_DOUBLE_EQ(model->body_inertia[3 * 1 + 1], kInertiaAxis);
  ASSERT_EQ(model->dof_armature[0], 0.0);
  ASSERT_EQ(model->dof_damping[0], 0.0);
  ASSERT_EQ(model->dof_frictionloss[0], 0.0);

  const double small_angle_period = 2 * kPi * std::sqrt(kInertiaPivot / (kMass * kG * kLength));
  for (double theta0_deg : {10.0, 90.0, 170.0}) {
    const double theta0 = theta0_deg * kDeg;
    const double exact = 4.0 * std::sqrt(kInertiaPivot / (kMass * kG * kLength)) * EllipticK(std::sin(0.5 * theta0));
    const double measured = MeasurePeriod(model, data, theta0, 6, exact);
    const double relative_error = (measured - exact) / exact;
    std::cout << "theta0 " << theta0_deg << " deg: T exact " << exact << " s (" << exact / small_angle_period
              << " x small-angle), measured " << measured << " s, relative error " << relative_error << "\n";
    EXPECT_LT(std::abs(relative_error), 1e-8) << "theta0 " << theta0_deg << " deg";
  }
}

// ---------------------------------------------------------------------------------------
// double pendulum

// upper link: pivot 2 m above the floor, hinge +y, COM 0.3 m below it; lower link hinged
// 0.6 m below the pivot, COM 0.25 m below its hinge. Anisotropic central inertias.
struct Link {
  double mass, com, inertia_y;
};
constexpr Link kUpper{1.0, 0.3, 0.03};
constexpr Link kLower{0.7, 0.25, 0.02};
constexpr double kUpperLength = 0.6;  // pivot to elbow hinge, m
constexpr double kPivotHeight = 2.0;

std::string DoublePendulumXml(const char* integrator, double timestep) {
  char xml[2048];
  std::snprintf(xml, sizeof(xml), R"(
<mujoco model="double_pendulum">
  <option timestep="%.17g" integrator="%s" gravity="0 0 %.17g">
    <flag energy="enable"/>
  </option>
  <worldbody>
    <body name="upper" pos="0 0 %.17g">
      <joint name="shoulder" type="hinge" axis="0 1 0"/>
      <inertial pos="0 0 %.17g" mass="%.17g" diaginertia="0.02 %.17g 0.01"/>
      <body name="lower" pos="0 0 %.17g">
        <joint name="elbow" type="hinge" axis="0 1 0"/>
        <inertial pos="0 0 %.17g" mass="%.17g" diaginertia="0.015 %.17g 0.005"/>
      </body>
    </body>
  </worldbody>
</mujoco>)",
                timestep, integrator, -kG, kPivotHeight, -kUpper.com, kUpper.mass, kUpper.inertia_y, -kUpperLength,
                -kLower.com, kLower.mass, kLower.inertia_y);
  return xml;
}

struct Energy {
  double kinetic, potential;
  double total() const { return kinetic + potential; }
};

// Our own energy of the planar double pendulum. A hinge about +y by theta maps a point
// (0, 0, -a) to (-a sin theta, 0, -a cos theta); the lower link turns by theta1 + theta2.
Energy OwnEnergy(double th1, double th2, double w1, double w2) {
  const double w12 = w1 + w2;
  // COM velocities (x, z)
  const double v1x = -kUpper.com * std::cos(th1) * w1, v1z = kUpper.com * std::sin(th1) * w1;
  const double v2x = -kUpperLength * std::cos(th1) * w1 - kLower.com * std::cos(th1 + th2) * w12;
  const double v2z = kUpperLength * std::sin(th1) * w1 + kLower.com * std::sin(th1 + th2) * w12;
  // COM heights
  const double z1 = kPivotHeight - kUpper.com * std::cos(th1);
  const double z2 = kPivotHeight - kUpperLength * std::cos(th1) - kLower.com * std::cos(th1 + th2);
  Energy e;
  e.kinetic = 0.5 * kUpper.mass * (v1x * v1x + v1z * v1z) + 0.5 * kUpper.inertia_y * w1 * w1 +
              0.5 * kLower.mass * (v2x * v2x + v2z * v2z) + 0.5 * kLower.inertia_y * w12 * w12;
  e.potential = kG * (kUpper.mass * z1 + kLower.mass * z2);
  return e;
}

struct EnergyRecord {
  std::vector<double> total;     // MuJoCo's energy[0] + energy[1] at every step start
  double max_gravity_power = 0;  // max |dV/dt| along the run, W
  double max_own_mismatch = 0;   // max |MuJoCo - own| / (|T| + |V|) at the sample instants
};

class DoublePendulum : public vlab::test::MujocoTest {
 protected:
  // `duration` s from theta = (120, -150) deg at rest; MuJoCo's energy is read after mj_forward at the
  // start of each step (RK4's stage evaluations overwrite d->energy inside mj_step)
  EnergyRecord RunDoublePendulum(const char* integrator, double timestep, double duration);
};

EnergyRecord DoublePendulum::RunDoublePendulum(const char* integrator, double timestep, double duration) {
  EnergyRecord record;
  const mjModel* model = LoadModelFromString("double_pendulum.xml", DoublePendulumXml(integrator, timestep));
  mjData* data = MakeData(model);
  const bool energy_enabled = model->opt.enableflags & mjENBL_ENERGY;
  if (model->nv != 2 || !energy_enabled) {
    ADD_FAILURE() << "model: nv " << model->nv << ", energy flag " << energy_enabled;
    return record;
  }
  data->qpos[0] = 120 * kDeg;
  data->qpos[1] = -150 * kDeg;
  const long steps = std::lround(duration / timestep);
  const long sample_every = std::max(1L, steps / 7);
  for (long step = 0; step <= steps; ++step) {
    mj_forward(model, data);
    record.total.push_back(data->energy[0] + data->energy[1]);
    const double *q = data->qpos, *v = data->qvel;
    // dV/dt = g (m1 dz1/dt + m2 dz2/dt)
    const double power =
        kG *
        (kUpper.mass * kUpper.com * std::sin(q[0]) * v[0] +
         kLower.mass * (kUpperLength * std::sin(q[0]) * v[0] + kLower.com * std::sin(q[0] + q[1]) * (v[0] + v[1])));
    record.max_gravity_power = std::max(record.max_gravity_power, std::abs(power));
    if (step % sample_every == 0) {
      const Energy own = OwnEnergy(q[0], q[1], v[0], v[1]);
      const double scale = std::abs(own.kinetic) + std::abs(own.potential);
      const double mismatch =
          std::max(std::abs(data->energy[0] - own.potential), std::abs(data->energy[1] - own.kinetic)) / scale;
      record.max_own_mismatch = std::max(record.max_own_mismatch, mismatch);
      EXPECT_LT(mismatch, 1e-10) << integrator << " t=" << data->time << ": MuJoCo T " << data->energy[1] << " V "
                                 << data->energy[0] << ", own T " << own.kinetic << " V " << own.potential;
    }
    if (step < steps) mj_step(model, data);
  }
  return record;
}

// max |E - E0| over the samples [begin, end)
double MaxDeviation(const std::vector<double>& e, size_t begin, size_t end) {
  double worst = 0;
  for (size_t i = begin; i < end; ++i) worst = std::max(worst, std::abs(e[i] - e[0]));
  return worst;
}

// RK4 on a harmonic oscillator keeps |R(i w h)|^2 = 1 - (w h)^6 / 72 + ...: a relative energy
// loss of (w h)^6 / 72 per step. The fastest rate in this run is the elbow spinning at up to
// ~20 rad/s (w h = 0.02 at 1 ms): 9e-13 per step, 2e-8 over 20 000 steps if every step lost
// at that worst rate. The 1e-6 bound leaves a factor 50 for the nonlinearity; a wrong
// integrator (Euler loses 5 % here) or a non-conservative force fails it by orders.
TEST_F(DoublePendulum, Rk4ConservesEnergyToFourthOrder) {
  const double h = 1e-3;
  const EnergyRecord run = RunDoublePendulum("RK4", h, 20.0);
  ASSERT_EQ(run.total.size(), 20001u);
  const double e0 = run.total.front();
  const double drift = MaxDeviation(run.total, 0, run.total.size()) / std::abs(e0);
  std::cout << "RK4 h=1ms: E0 " << e0 << " J, max |E - E0| / |E0| over 20 s " << drift << ", max gravity power "
            << run.max_gravity_power << " W, own-energy mismatch " << run.max_own_mismatch << "\n";
  EXPECT_LT(drift, 1e-6);
  // chaotic, not a quiet swing: the links exchange a lot of energy with gravity
  EXPECT_GT(run.max_gravity_power, 10.0);

  // fourth order: halving h divides the energy error by 2^4 = 16. Over the first second the
  // runs at h and h/2 still follow the same trajectory (chaos has not separated them yet).
  const double first_second = MaxDeviation(run.total, 0, 1001);
  const EnergyRecord half = RunDoublePendulum("RK4", h / 2, 1.0);
  const double first_second_half = MaxDeviation(half.total, 0, half.total.size());
  const double ratio = first_second / first_second_half;
  std::cout << "RK4 max |E - E0| over the first 1 s: h=1ms " << first_second << " J, h=0.5ms " << first_second_half
            << " J, ratio " << ratio << " (4th order: 16)\n";
  EXPECT_GT(ratio, 12.0);
  EXPECT_LT(ratio, 20.0);
}

// MuJoCo's Euler is semi-implicit: v' = v + h a(q, v), q' = q + h v'. With a constant mass
// matrix (one hinge) this is the symplectic Euler method, which exactly conserves a modified
// energy E~ = E - (h/2) P + O(h^2), P = qdot . dV/dq (the power flowing into the potential;
// for a harmonic oscillator E~ = (q^2 + p^2)/2 - (h/2) p q is conserved exactly). Hence
//   E(t) - E(0) = (h/2) (P(t) - P(0)) + O(h^2):
// a bounded oscillation of amplitude (h/2) max|P|, the same in the first and last 5 s.
TEST_F(SimplePendulum, SemiImplicitEulerOscillatesAroundModifiedEnergy) {
  const double h = 1e-3;
  const mjModel* model = LoadModelFromString("simple_pendulum_euler.xml", SimplePendulumXml("Euler", h));
  mjData* data = MakeData(model);
  ASSERT_EQ(model->opt.integrator, mjINT_EULER);
  data->qpos[0] = 120 * kDeg;
  const long steps = 20000;
  std::vector<double> deviation, power;
  double e0 = 0, p0 = 0;
  for (long step = 0; step <= steps; ++step) {
    mj_forward(model, data);
    const double theta = data->qpos[0], omega = data->qvel[0];
    // own energy and power: COM height -L cos(theta) below the pivot
    const double e = 0.5 * kInertiaPivot * omega * omega - kMass * kG * kLength * std::cos(theta);
    const double p = omega * kMass * kG * kLength * std::sin(theta);
    if (step == 0) e0 = e, p0 = p;
    deviation.push_back(e - e0);
    power.push_back(p);
    if (step < steps) mj_step(model, data);
  }
  double max_power = 0, max_residual = 0, first = 0, last = 0;
  for (size_t i = 0; i < deviation.size(); ++i) {
    max_power = std::max(max_power, std::abs(power[i]));
    max_residual = std::max(max_residual, std::abs(deviation[i] - 0.5 * h * (power[i] - p0)));
    if (i <= 5000) first = std::max(first, std::abs(deviation[i]));
    if (i >= deviation.size() - 5001) last = std::max(last, std::abs(deviation[i]));
  }
  const double amplitude = 0.5 * h * max_power;
  std::cout << "simple pendulum, Euler h=1ms, 120 deg: max |E - E0| first 5 s " << first << " J, last 5 s " << last
            << " J, (h/2) max|P| " << amplitude << " J, |E - E0 - (h/2)(P - P0)| <= " << max_residual << " J\n";
  // the first-order modified energy explains the oscillation; the O(h^2) rest is of relative
  // size ~ (w0 h)^2 ~ 2e-5 per unit of energy swing (m g L = 6.4 J): ~1e-4 J, well below 10 %
  EXPECT_LT(max_residual, 0.1 * amplitude);
  EXPECT_LT(first, 1.1 * amplitude);
  EXPECT_LT(last, 1.1 * amplitude);
  // no secular change: the envelope is the same at the start and after 15 s
  EXPECT_NEAR(last, first, 0.01 * first);
}

// With a configuration-dependent mass matrix (two hinges) the velocity-form semi-implicit
// Euler is no longer symplectic: the energy is not bounded by the oscillation above but loses
// O(h) per unit time (numerical dissipation). Checked: it never gains energy beyond the
// symplectic oscillation (h/2) max|P|, the loss converges at first order (halving h halves
// it over the first second, before the chaotic runs separate), and it grows at most linearly
// in time: a constant loss rate gives a last-5-s deviation (window ending at 20 s) at most 4x
// the first-5-s one; an unstable or energy-pumping integrator exceeds that.
TEST_F(DoublePendulum, SemiImplicitEulerNeverGainsAndLosesAtFirstOrder) {
  const double h = 1e-3;
  const EnergyRecord run = RunDoublePendulum("Euler", h, 20.0);
  ASSERT_EQ(run.total.size(), 20001u);
  const double e0 = run.total.front();
  double max_gain = 0;
  for (double e : run.total) max_gain = std::max(max_gain, e - e0);
  const double first = MaxDeviation(run.total, 0, 5001);
  const double last = MaxDeviation(run.total, run.total.size() - 5001, run.total.size());
  const double oscillation = 0.5 * h * run.max_gravity_power;
  std::cout << "double pendulum, Euler h=1ms: E0 " << e0 << " J, max gain " << max_gain << " J, max |E - E0| first 5 s "
            << first << " J, last 5 s " << last << " J (" << last / std::abs(e0) << " of E0), (h/2) max|P| "
            << oscillation << " J, own-energy mismatch " << run.max_own_mismatch << "\n";
  EXPECT_LE(max_gain, oscillation);
  EXPECT_LT(last, 4.0 * first);

  double previous = MaxDeviation(run.total, 0, 1001);
  for (double divisor : {2.0, 4.0}) {
    const EnergyRecord finer = RunDoublePendulum("Euler", h / divisor, 1.0);
    const double loss = MaxDeviation(finer.total, 0, finer.total.size());
    std::cout << "Euler max |E - E0| over the first 1 s at h = " << h / divisor << ": " << loss << " J, ratio "
              << previous / loss << " (1st order: 2)\n";
    EXPECT_GT(previous / loss, 1.8) << "h / " << divisor;
    EXPECT_LT(previous / loss, 2.2) << "h / " << divisor;
    previous = loss;
  }
}

}  // namespace
}  // namespace vlab::lab
