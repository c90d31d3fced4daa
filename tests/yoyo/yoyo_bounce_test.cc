// The yo-yo (mjcf/yoyo/) at the end of its string, hand fixed, against DATASHEET §6.3.
//
// At the bottom (theta through 0) the string switches to the other side of the axle. With
// the new side's string taut at once (a plastic jerk along d - r theta, no force along the
// motion that keeps d - r theta fixed) the angular momentum about the new contact point is
// conserved: (J - m r^2) w- = (J + m r^2) w+, so the spin keeps its sense, w+ = e w-,
// e = (J - m r^2) / (J + m r^2), the yo-yo climbs at d' = -r |w+|, and the kinetic energy
// drops to e^2 of its value: the energy lost is (1 - e^2) KE-. The climb then stops at
// d_top = L - e^2 (L - d_start) and the yo-yo falls again.
// Every closed form uses m, J, r, L and g read back from the compiled model.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include "yoyo/yoyo_scene.h"

namespace vlab::yoyo::testing {
namespace {

struct Sample {
  double time, drop, spin, drop_rate, spin_rate, energy, tension, stretch;
};

struct Bounce {
  int index;  // first sample with theta on the new side
};

// `duration` s from qpos0 (wound up, taut, at rest); one sample per step, state at the
// end of the step, tension (a sensor) from its start
std::vector<Sample> RunFromWound(const mjModel* m, mjData* d, const Yoyo& y, double duration) {
  std::vector<Sample> run;
  mj_resetData(m, d);
  StepFor(m, d, duration, [&](const mjData* d) {
    run.push_back({d->time, d->qpos[y.drop_qpos], d->qpos[y.spin_qpos], d->qvel[y.drop_dof], d->qvel[y.spin_dof],
                   Energy(y, d), Tension(y, d), Stretch(y, d)});
  });
  return run;
}

std::vector<Bounce> FindBounces(const std::vector<Sample>& run) {
  std::vector<Bounce> bounces;
  for (size_t i = 1; i < run.size(); ++i) {
    if ((run[i - 1].spin > 0) != (run[i].spin > 0)) bounces.push_back({static_cast<int>(i)});
  }
  return bounces;
}

// first bottom speed of the fall from qpos0, m/s: v^2 = 2 a (L - d0)
double FirstBottomSpeed(const mjModel* m, const Yoyo& y) {
  return std::sqrt(2 * y.Descent() * (y.length - m->qpos0[y.drop_qpos]));
}

constexpr int kBottoms = 3;  // bottoms checked (1.4, 3.8, 5.6 s with the DS yo-yo)
constexpr int kBefore = 20;  // samples before a bounce: still falling on the old side
constexpr int kAfter = 100;  // samples after it: climbing, the string's jerk over

// run length that holds kBottoms bottoms and the apex after the last, from the closed form:
// the fall from rest takes t1 = v1 / a, each climb and fall after bottom k takes e^k t1, so
// the apex after bottom n is at t1 (1 + 2 e + ... + 2 e^(n-1) + e^n); 20 % margin for the
// string's stretch and the jerk's step (measured: the three bottoms within 1 ms of it)
double Horizon(const mjModel* m, const Yoyo& y) {
  const double e = y.Restitution(), t1 = FirstBottomSpeed(m, y) / y.Descent();
  double t = t1, power = 1;
  for (int k = 1; k < kBottoms; ++k) t += 2 * t1 * (power *= e);
  return 1.2 * (t + t1 * power * e);
}

// Energy lost at each bottom = (1 - e^2) KE-. The energies are taken in the constant-force
// phases before and after (where Energy() is exact to round-off), so the tolerance covers
// only where the jerk happens: the solver applies it at the first step whose state has the
// new side stretched, i.e. somewhere in the last step of travel past the corner d = L,
// theta = 0. That moves the impact by up to v h along the string, which changes the
// measured loss by at most m g v h (height) plus m g v h (the half-step height offset of
// Energy() switches sign with d'): 2 m g v h = 1.3e-3 J at the first bottom, 0.8 % of the
// 0.16 J lost. A wrong e (say the string bouncing elastically, or the constraint leaking
// energy) misses it by far more: e = 0.81 vs 0.82 is 4e-3 J.
TEST_F(YoyoTest, EnergyLostAtTheBottomIsTheEquivalentRestitution) {
  const Yoyo& y = yoyo_;
  const std::vector<Sample> run = RunFromWound(model_, data_, y, Horizon(model_, y));
  const std::vector<Bounce> bounces = FindBounces(run);
  ASSERT_GE(bounces.size(), static_cast<size_t>(kBottoms)) << "in " << run.back().time << " s";
  const double e = y.Restitution();
  for (size_t k = 0; k < kBottoms; ++k) {
    const int i = bounces[k].index;
    ASSERT_GE(i - kBefore, 0);
    ASSERT_LT(i + kAfter, static_cast<int>(run.size()));
    const double before = run[i - kBefore].energy, after = run[i + kAfter].energy;
    const double kinetic = before + y.mass * y.gravity * y.length;  // KE- at d = L
    const double v = std::sqrt(kinetic / y.RollingEnergy(1.0));
    const double lost = before - after, expected = (1 - e * e) * kinetic;
    const double tolerance = 2 * y.mass * y.gravity * v * y.timestep;
    std::printf(
        "bottom %zu at %.3f s: v %.4f m/s, KE- %.6f J, lost %.6f J, closed form %.6f J (error %+.2e J, "
        "tolerance %.2e); e measured %.5f, closed form %.5f\n",
        k + 1, run[i].time, v, kinetic, lost, expected, lost - expected, tolerance,
        std::sqrt((after + kinetic - before) / kinetic), e);
    EXPECT_NEAR(lost, expected, tolerance) << "bottom " << k + 1;
  }
}

TEST_F(YoyoTest, ReboundsAndClimbsWithTheOtherWinding) {
  const Yoyo& y = yoyo_;
  const std::vector<Sample> run = RunFromWound(model_, data_, y, Horizon(model_, y));
  const std::vector<Bounce> bounces = FindBounces(run);
  ASSERT_GE(bounces.size(), static_cast<size_t>(kBottoms)) << "in " << run.back().time << " s";
  const double e2 = y.Restitution() * y.Restitution();
  double start = model_->qpos0[y.drop_qpos];  // where the current fall began
  for (size_t k = 0; k < kBottoms; ++k) {
    SCOPED_TRACE("bottom " + std::to_string(k + 1));
    const int i = bounces[k].index;
    ASSERT_GE(i - kBefore, 0);
    ASSERT_LT(i + kAfter, static_cast<int>(run.size())) << "the run ends " << kAfter << " steps after the bottom";
    const Sample& fall = run[i - kBefore];
    const Sample& climb = run[i + kAfter];
    // theta changes sign (the other winding), the spin keeps its sense, d turns round
    EXPECT_LT(fall.spin * climb.spin, 0);
    EXPECT_GT(fall.spin_rate * climb.spin_rate, 0);
    EXPECT_GT(fall.drop_rate, 0);
    EXPECT_LT(climb.drop_rate, 0);
    // wound on the string again: d' = -r |theta'|, up to the stretch rate left by the bottom
    // (<= 2 v h of stretch relaxing at the overdamped limit's slow rate, ~67/s: ~2e-4 of d'
    // after 0.1 s)
    EXPECT_NEAR(climb.drop_rate, y.axle_radius * -std::abs(climb.spin_rate), 1e-3 * std::abs(climb.drop_rate));
    // climbing on a taut string from the bottom to the apex: the jerk does not throw the
    // yo-yo off the string (it does with dampratio 1: slack for ~0.1 s)
    size_t apex = i + kAfter;
    while (apex + 1 < run.size() && run[apex + 1].drop_rate < 0) ++apex;
    ASSERT_LT(apex + 1, run.size()) << "no apex";
    for (size_t j = i; j <= apex; ++j) ASSERT_GT(run[j].tension, 0) << "slack at " << run[j].time;
    // apex: kinetic energy e^2 of what the fall from `start` gave
    const double expected = y.length - e2 * (y.length - start);
    // the energy test's tolerance 2 m g v h, as a height
    const double tolerance = 2 * FirstBottomSpeed(model_, y) * y.timestep;
    std::printf("bottom %zu: fell from %.5f m, climbs to %.5f m below the hand, closed form %.5f (error %+.2e m)\n",
                k + 1, start, run[apex].drop, expected, run[apex].drop - expected);
    EXPECT_NEAR(run[apex].drop, expected, tolerance);
    start = run[apex].drop;
  }
}

// d <= L - r |theta| (and |d| <= L - r |theta| in general) up to the solver's softness:
// a taut string stretches by steady_stretch = (1 - d_imp) g (tc dampratio)^2 (1.6 um) under
// the yo-yo's weight; at the bottom the new side is found stretched by up to one step of
// its approach speed, 2 v h (d - r theta grows at d' - r theta' = 2 v), and the critically
// fast limit (b h = 1) stops it within that step. Bound: 2 (v + g h) h + steady_stretch
// with v the fastest bottom speed (the first), 2.7 mm for the DS yo-yo at h = 1 ms.
TEST_F(YoyoTest, StringLengthHoldsWithinTheSolverSoftness) {
  const Yoyo& y = yoyo_;
  const std::vector<Sample> run = RunFromWound(model_, data_, y, Horizon(model_, y));
  double worst = -1, worst_time = 0, min_tension = 0;
  for (const Sample& s : run) {
    if (s.stretch > worst) worst = s.stretch, worst_time = s.time;
    min_tension = std::min(min_tension, s.tension);
  }
  const double v = FirstBottomSpeed(model_, y), h = y.timestep;
  const double bound = 2 * (v + y.gravity * h) * h + y.steady_stretch;
  double taut_stretch = 0;  // during the first fall, long after the start
  for (const Sample& s : run) {
    if (s.time > 0.2 && s.time < 1.2) taut_stretch = std::max(taut_stretch, s.stretch);
  }
  std::printf("max |d| + r|theta| - L = %.3e m at %.3f s (bound %.3e m); taut stretch %.3e m (steady %.3e m)\n", worst,
              worst_time, bound, taut_stretch, y.steady_stretch);
  EXPECT_LE(worst, bound);
  EXPECT_NEAR(taut_stretch, y.steady_stretch, 0.05 * y.steady_stretch);
  EXPECT_GE(min_tension, 0.0) << "the string pushed";
}

}  // namespace
}  // namespace vlab::yoyo::testing
