// The yo-yo model (mjcf/yoyo/) on its string, hand fixed, against DATASHEET §6.
//
// Taut string (DS §6.3): the string leaves the axle at radius r, so d = L - r theta and
//   (m + J / r^2) dd'' = m g   =>   a = g m r^2 / (m r^2 + J),   T = m (g - a) = m g J / (J + m r^2).
// Slack string: no constraint, free fall (d'' = g, theta' constant) and no force. When it
// goes taut again the string jerk is plastic and acts along the string only, so the
// momentum r m d' - J theta' (about the point where the string leaves the axle) changes
// only by gravity's r m g t; once taut (d' = -r theta') that gives d'(t) = (a / g) (d'0 + g t).
// Every closed form uses m, J, r, L and g read back from the compiled model.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <Eigen/Dense>

#include "yoyo/yoyo_scene.h"

namespace vlab::yoyo::testing {
namespace {

using YoyoModel = YoyoTest;

TEST_F(YoyoModel, LoadsQuietlyWithTheDatasheetYoyo) {
  const mjModel* m = model_;
  EXPECT_EQ(m->nq, 2);
  EXPECT_EQ(m->nv, 2);
  // DS §6.1 textbook yo-yo: m = 50 g, J = m R^2 / 2 with R = 35 mm, r_min = 8 mm, L = 1 m
  EXPECT_NEAR(yoyo_.mass, 0.050, 1e-12);
  EXPECT_NEAR(yoyo_.spin_inertia, 0.5 * 0.050 * 0.035 * 0.035, 1e-15);
  EXPECT_NEAR(yoyo_.axle_radius, 0.008, 1e-12);
  EXPECT_NEAR(yoyo_.length, 1.0, 1e-12);
  EXPECT_NEAR(yoyo_.gravity, 9.81, 1e-12) << "the slide must point down, along gravity";
  // the closed forms reproduce DS §6.3's numbers for r = 8 mm: e = 0.81, a = 0.93 m/s^2
  EXPECT_NEAR(yoyo_.Restitution(), 0.81, 0.005);
  EXPECT_NEAR(yoyo_.Descent(), 0.93, 0.005);
  // the closed forms assume no joint damping, armature or friction
  for (int v = 0; v < m->nv; ++v) {
    EXPECT_EQ(m->dof_damping[v], 0.0);
    EXPECT_EQ(m->dof_armature[v], 0.0);
    EXPECT_EQ(m->dof_frictionloss[v], 0.0);
  }
  // the other tendon is the mirror image: d - r theta within the same +/- L
  const int minus = mj_name2id(m, mjOBJ_TENDON, "yoyo_string_minus");
  ASSERT_GE(minus, 0);
  EXPECT_EQ(TendonCoef(m, minus, mj_name2id(m, mjOBJ_JOINT, "yoyo_spin")), -yoyo_.axle_radius);
  EXPECT_EQ(m->tendon_range[2 * minus + 1], yoyo_.length);
  EXPECT_EQ(m->tendon_range[2 * minus], -yoyo_.length);
  // qpos0 is wound up and taut, and the centre site hangs d below the string attachment
  const mjData* d = data_;
  EXPECT_NEAR(Stretch(yoyo_, d), 0.0, 1e-9);
  const int attach = mj_name2id(m, mjOBJ_SITE, "yoyo_string_attach");
  const int centre = mj_name2id(m, mjOBJ_SITE, "yoyo_centre");
  ASSERT_GE(attach, 0);
  ASSERT_GE(centre, 0);
  EXPECT_EQ(m->site_bodyid[attach], mj_name2id(m, mjOBJ_BODY, "hand"));
  const double drop = d->qpos[yoyo_.drop_qpos];
  EXPECT_NEAR(d->site_xpos[3 * centre + 2], d->site_xpos[3 * attach + 2] - drop, 1e-12);
  EXPECT_NEAR(d->site_xpos[3 * centre], d->site_xpos[3 * attach], 1e-12);
  // saturated red discs, for the colour-blob tracker
  for (const char* name : {"yoyo_disc_left", "yoyo_disc_right"}) {
    const int geom = mj_name2id(m, mjOBJ_GEOM, name);
    ASSERT_GE(geom, 0) << name;
    const int mat = m->geom_matid[geom];
    const float* rgba = mat >= 0 ? m->mat_rgba + 4 * mat : m->geom_rgba + 4 * geom;
    EXPECT_GE(rgba[0], 0.8f) << name;
    EXPECT_LE(rgba[1], 0.1f) << name;
    EXPECT_LE(rgba[2], 0.1f) << name;
  }
  // one second from each keyframe without a runtime warning (checked at tear-down)
  for (int key = 0; key < m->nkey; ++key) {
    mj_resetDataKeyframe(m, data_, key);
    StepFor(m, data_, 1.0, [](const mjData*) {});
  }
}

// d(t) and the string tension while falling from the wound start, sampled from 0.1 s (the
// start-up jerk of the string has died out after ~20 ms) to 0.1 s before the bottom
struct Descent {
  std::vector<double> time, drop, tension;
  double max_coupling_error = 0;  // max |d' + r theta'|, m/s
};

Descent RunDescent(const mjModel* m, mjData* d, const Yoyo& y) {
  Descent run;
  mj_resetData(m, d);
  const double bottom_time = std::sqrt(2 * (y.length - d->qpos[y.drop_qpos]) / y.Descent());
  StepFor(m, d, bottom_time - 0.1, [&](const mjData* d) {
    EXPECT_GE(Tension(y, d), 0.0) << "the string pushes at t " << d->time;
    if (d->time < 0.1) return;
    run.tension.push_back(Tension(y, d));
    run.time.push_back(d->time);
    run.drop.push_back(d->qpos[y.drop_qpos]);
    const double coupling = d->qvel[y.drop_dof] + y.axle_radius * d->qvel[y.spin_dof];
    run.max_coupling_error = std::max(run.max_coupling_error, std::abs(coupling));
  });
  return run;
}

// least-squares parabola through d(t): d = c0 + c1 t + c2 t^2, a = 2 c2 (semi-implicit
// Euler adds a term h a t / 2, linear in t: the curvature is unaffected)
double FitAcceleration(const Descent& run) {
  Eigen::MatrixXd basis(run.time.size(), 3);
  Eigen::VectorXd drop(run.time.size());
  for (size_t i = 0; i < run.time.size(); ++i) {
    basis.row(i) << 1.0, run.time[i], run.time[i] * run.time[i];
    drop(i) = run.drop[i];
  }
  const Eigen::Vector3d c = basis.colPivHouseholderQr().solve(drop);
  return 2 * c(2);
}

TEST_F(YoyoTest, DescentAccelerationIsTheClosedForm) {
  const Descent run = RunDescent(model_, data_, yoyo_);
  ASSERT_GT(run.time.size(), 1000u);
  const double measured = FitAcceleration(run), expected = yoyo_.Descent();
  const double error = (measured - expected) / expected;
  std::printf("descent: a measured %.9f m/s^2, closed form %.9f, relative error %.2e; max |d' + r theta'| %.2e m/s\n",
              measured, expected, error, run.max_coupling_error);
  // closed form to 1e-4 (measured 6.4e-9: the semi-implicit step's error is linear in t and
  // leaves the curvature alone); 1e-4 of a is a 1.1e-4 error in J (d ln a / d ln J = -0.905)
  EXPECT_LT(std::abs(error), 1e-4);
  // winding: the string leaves the axle at r, d' = -r theta' (to 1e-4 of the speed reached;
  // what is left is the tail of the start-up jerk, ~1e-6 m/s)
  EXPECT_LT(run.max_coupling_error, 1e-4 * yoyo_.Descent() * run.time.back());
}

TEST_F(YoyoTest, StringTensionIsTheClosedForm) {
  const Descent run = RunDescent(model_, data_, yoyo_);
  ASSERT_GT(run.tension.size(), 1000u);
  const double expected = yoyo_.Tension();
  double worst = 0, sum = 0;
  for (double t : run.tension) {
    worst = std::max(worst, std::abs(t - expected) / expected);
    sum += t;
  }
  const double mean = sum / run.tension.size();
  std::printf("tension: mean %.9f N, closed form %.9f N (weight %.6f N), worst relative error %.2e\n", mean, expected,
              yoyo_.mass * yoyo_.gravity, worst);
  // closed form to 1e-4 (measured 6.3e-6 at worst: the tail of the start-up jerk)
  EXPECT_LT(worst, 1e-4);
  // and the readout is the force that decelerates the fall measured from d(t): T = m (g - d'')
  const double newton = yoyo_.mass * (yoyo_.gravity - FitAcceleration(run));
  EXPECT_NEAR(mean, newton, 1e-3 * newton);
}

TEST_F(YoyoTest, SlackStringExertsNoForceAndTakesUpPlastically) {
  const Yoyo& y = yoyo_;
  // half unwound and taut, thrown upward at 1 m/s without extra spin: the yo-yo rises
  // faster than the (non-spinning) axle rewinds, so the string goes slack at once
  const double drop0 = 0.5 * y.length, up = -1.0;
  SetState(drop0, (y.length - drop0) / y.axle_radius, up, 0.0);
  const double slack_time = 2 * -up / y.gravity;  // free flight back to drop0
  const double h = y.timestep;
  double taut_again = -1, worst_free_fall = 0;
  int slack_steps = 0;
  StepFor(model_, data_, slack_time + 0.3, [&](const mjData* d) {
    const double t = d->time - h;  // sensors, qacc and nefc belong to the step's start
    const double force = Tension(y, d);
    EXPECT_GE(force, 0.0) << "the string pushes at t " << t;
    if (taut_again < 0 && force > 0) taut_again = t;
    if (t < slack_time - 2 * h) {
      ++slack_steps;
      EXPECT_EQ(force, 0.0) << "slack string pulls at t " << t;
      EXPECT_EQ(d->nefc, 0) << "constraint rows on a slack string at t " << t;
      worst_free_fall = std::max(worst_free_fall, std::abs(d->qacc[y.drop_dof] - y.gravity));
      EXPECT_EQ(d->qvel[y.spin_dof], 0.0) << "spin changed while slack";
    }
  });
  std::printf(
      "slack: %d steps with string force exactly 0, max |d'' - g| %.2e m/s^2; taut again at %.4f s "
      "(free flight %.4f s)\n",
      slack_steps, worst_free_fall, taut_again, slack_time);
  EXPECT_GT(slack_steps, 150);
  EXPECT_LT(worst_free_fall, 1e-9);
  EXPECT_NEAR(taut_again, slack_time, 2 * h);
  // after the jerk: on the string again, at (a/g) times the free-fall speed
  const double t = data_->time;
  const double expected = y.Descent() / y.gravity * (up + y.gravity * t);
  const double measured = data_->qvel[y.drop_dof];
  std::printf(
      "after take-up: d' %.6f m/s at %.3f s, closed form %.6f, relative error %.2e; tension %.6f N "
      "(closed form %.6f)\n",
      measured, t, expected, (measured - expected) / expected, Tension(y, data_), y.Tension());
  // the momentum argument holds step by step (constraint impulses along (1, r), gravity
  // exactly h m g per step), so the timing of the jerk does not matter; what is left is
  // the string's stretch rate d' + r theta', which the overdamped limit has removed
  EXPECT_NEAR(measured, expected, 1e-4 * std::abs(expected));
  EXPECT_NEAR(Tension(y, data_), y.Tension(), 0.01 * y.Tension());
}

}  // namespace
}  // namespace vlab::yoyo::testing
