// The PowerBall case study's scene (scenes/pa10_powerball.xml): its arm is pa10.xml's up to
// the JR3, the ball sits at the tool with its groove normal along the flange's x, the
// keyframe starts the rotor rolling, and the ball's solver options stay in this scene.
#include <algorithm>
#include <cmath>
#include <string>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include "lab/devices/powerball_truth.h"
#include "mujoco_fixture.h"

namespace vlab::lab {
namespace {

constexpr char kScene[] = "scenes/pa10_powerball.xml";
using PowerballScene = vlab::test::MujocoTest;

// every body, joint and motor of pa10.xml's arm has the same numbers, except tool_body (the
// holder instead of the pointer: mjcf/pa10/pa10_powerball.xml)
TEST_F(PowerballScene, TheArmIsPa10xmlsArmUpToTheJr3) {
  const mjModel* ball = LoadModel(kScene);
  const mjModel* plain = LoadModel("scenes/pa10.xml");
  auto same = [](const mjtNum* x, const mjtNum* y, int n) { return std::equal(x, x + n, y); };
  int compared = 0;
  for (int b = 1; b < plain->nbody; ++b) {
    const std::string name = mj_id2name(plain, mjOBJ_BODY, b);
    const int y = mj_name2id(ball, mjOBJ_BODY, name.c_str());
    ASSERT_GE(y, 0) << name;
    if (name == "tool_body") continue;
    EXPECT_EQ(plain->body_mass[b], ball->body_mass[y]) << name;
    EXPECT_TRUE(same(plain->body_inertia + 3 * b, ball->body_inertia + 3 * y, 3)) << name;
    EXPECT_TRUE(same(plain->body_ipos + 3 * b, ball->body_ipos + 3 * y, 3)) << name;
    EXPECT_TRUE(same(plain->body_pos + 3 * b, ball->body_pos + 3 * y, 3)) << name;
    EXPECT_TRUE(same(plain->body_quat + 4 * b, ball->body_quat + 4 * y, 4)) << name;
    ++compared;
  }
  EXPECT_EQ(compared, plain->nbody - 2);
  ASSERT_EQ(plain->njnt + 3, ball->njnt);  // + precess, tilt, spin
  for (int j = 0; j < plain->njnt; ++j) {
    EXPECT_TRUE(same(plain->jnt_range + 2 * j, ball->jnt_range + 2 * j, 2));
    EXPECT_TRUE(same(plain->jnt_axis + 3 * j, ball->jnt_axis + 3 * j, 3));
    EXPECT_EQ(plain->dof_armature[j], ball->dof_armature[j]);
    EXPECT_EQ(plain->dof_damping[j], ball->dof_damping[j]);
  }
  ASSERT_EQ(plain->nu, ball->nu);
  EXPECT_TRUE(same(plain->actuator_ctrlrange, ball->actuator_ctrlrange, 2 * plain->nu));
  // the ball's options here, the arm scene's own there (README "Scene options")
  EXPECT_EQ(ball->opt.timestep, 1e-4);
  EXPECT_EQ(ball->opt.solver, mjSOL_PGS);
  EXPECT_EQ(ball->opt.cone, mjCONE_ELLIPTIC);
  EXPECT_EQ(plain->opt.timestep, 1e-3);
  EXPECT_EQ(plain->opt.solver, mjSOL_NEWTON);
  EXPECT_EQ(plain->opt.cone, mjCONE_PYRAMIDAL);
}

// keyframe spin2000: e3 = the flange's +x points up, the ball's centre is the tool site
// 50 mm out of the sensor's tool face, the rotor rolls at 2,000 rpm on the upper wall and the
// walls carry I_s omega nu (the controller's premise)
TEST_F(PowerballScene, TheKeyframeHoldsTheBallUpAndTheRotorRolling) {
  const mjModel* m = LoadModel(kScene);
  mjData* d = MakeData(m);
  const int key = mj_name2id(m, mjOBJ_KEY, "spin2000");
  ASSERT_GE(key, 0);
  mj_resetDataKeyframe(m, d, key);
  mj_forward(m, d);
  const PowerballBinding ball = PowerballBinding::Bind(*m, kScene);
  const double* shell = d->xmat + 9 * ball.shell_body;
  const double* flange = d->site_xmat + 9 * mj_name2id(m, mjOBJ_SITE, "flange");
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(shell[3 * i + 2], flange[3 * i], 1e-6) << "e3 = flange x, row " << i;
    EXPECT_NEAR(shell[3 * i + 2], i == 2 ? 1.0 : 0.0, 1e-6) << "e3 up, row " << i;
  }
  const int tool = mj_name2id(m, mjOBJ_SITE, "tool");
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(d->site_xpos[3 * tool + i], d->xpos[3 * ball.shell_body + i], 1e-12);
  // hold the arm still (its joints' velocities zeroed every step) for 0.2 s
  for (int step = 0; step < 2000; ++step) {
    for (int j = 0; j < 7; ++j) d->qvel[j] = 0.0;
    mj_step(m, d);
    ASSERT_FALSE(vlab::test::AnyWarning(*d));
  }
  const PowerballTruth t = MeasurePowerball(*m, *d, ball);
  EXPECT_NEAR(t.Rpm(), 2000.0, 0.01 * 2000.0);
  EXPECT_LT(t.slip, 0.01);
  EXPECT_NEAR(t.CoupleNorm() / (ball.spin_inertia * t.omega * t.nu), 1.0, 0.05);
}

}  // namespace
}  // namespace vlab::lab
