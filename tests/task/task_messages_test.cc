// What the task language says when a script asks for something it cannot do:
// every move option is honoured or refused by name at the script's line; NaN
// and inf targets are refused before any inverse kinematics; a target out of
// reach says how far (m, the IK's final residual); a singularity is named
// with its joint; a program that died is not "ended" in the log.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "control/robot_model.h"
#include "task/task_motion.h"
#include "task_runtime_fixture.h"

namespace vlab::task {
namespace {

using MessagesTest = RuntimeTest;

#define EXPECT_HAS(text, part) EXPECT_NE((text).find(part), std::string::npos) << (text)

TEST_F(MessagesTest, EveryMoveRefusesAnOptionItWouldIgnoreByName) {
  const struct {
    const char* code;
    const char* message;
  } refused[] = {
      {"movej({0, 30, 0, 60, 0, 90, 0}, {w = 90})", "pa10.lua:1: movej: option 'w' is not supported: movej"},
      {"movej({0, 30, 0, 60, 0, 90, 0}, {v = 10, jv = 10})", "pa10.lua:1: movej: options 'v' and 'jv' together"},
      {"movej({0, 30, 0, 60, 0, 90, 0}, {t = 1, a = 10})", "pa10.lua:1: movej: options 't' and 'a' together"},
      {"movej({0, 30, 0, 60, 0, 90, 0}, {a = 0})", "pa10.lua:1: movej: option a must be > 0"},
      {"movej({0, 30, 0, 60, 0, 90, 0}, {r = 0.01})", "pa10.lua:1: movej: option 'r' is not supported"},
      {"movej({0, 30, 0, 60, 0, 90, 0}, {speed = 1})",
       "pa10.lua:1: movej: unknown option 'speed' (options: v, a, jv, t, ref, at, async)"},
      {"movej({0, 30, 0, 60, 0, 90, 0}, {t = 1, jv = 10})", "pa10.lua:1: movej: options 't' and 'jv' together"},
      {"movel(pose() * trans(0, 0, 0.01), {jv = 10})", "pa10.lua:1: movel: option 'jv' is not supported"},
      {"movel(pose() * trans(0, 0, 0.01), {vel = 1})", "pa10.lua:1: movel: unknown option 'vel'"},
      {"movel(pose() * trans(0, 0, 0.01), {t = 1, v = 0.1})", "pa10.lua:1: movel: options 't' and 'v' together"},
      {"movel(pose() * trans(0, 0, 0.01), {wrench = 'jr3'})", "pa10.lua:1: movel: option 'wrench' names the sensor"},
      {"movel(pose() * trans(0, 0, 0.01), {t = 0})", "pa10.lua:1: movel: option t must be > 0 s"},
      {"movel(pose() * trans(0, 0, 0.01), {v = 0})", "pa10.lua:1: movel: option v must be > 0"},
      {"movec(vec3(0.5, 0, 0.6), pose(), {jv = 1})", "pa10.lua:1: movec: option 'jv' is not supported"},
      {"movec(vec3(0.5, 0, 0.6), pose(), {z = 1})", "pa10.lua:1: movec: unknown option 'z'"},
      {"movec(vec3(0.5, 0, 0.6), pose(), {t = 1, w = 9})", "pa10.lua:1: movec: options 't' and 'w' together"},
      {"selfmove{joint = 3, by = 5, t = 1, v = 1}", "pa10.lua:1: selfmove: option 'v' is not supported"},
      {"selfmove{joint = 3, by = 5, t = 1, r = 1}", "pa10.lua:1: selfmove: option 'r' is not supported"},
      {"selfmove{joint = 3, by = 5, t = 1, speed = 1}", "pa10.lua:1: selfmove: unknown option 'speed'"},
  };
  for (const auto& c : refused) {
    auto r = Make({{"pa10", std::string(c.code) + "\n"}});
    EXPECT_FALSE(RunFor(*r, 20)) << c.code;
    EXPECT_HAS(r->error(), c.message);
  }
  // the options each move honours still work
  const char* honoured[] = {
      "movej({0, 31, 0, 60, 0, 90, 0}, {jv = 60})",
      "movej({0, 31, 0, 60, 0, 90, 0}, {v = 60, a = 120})",
      "movej({0, 30, 0, 60, 0, 90, 0}, {t = 0.1})",
      "movel(pose() * trans(0, 0, 0.005), {v = 0.2, a = 1, w = 90})",
      "movel(pose() * trans(0, 0, 0.005), {t = 0.1})",
      "movel(pose() * trans(0, 0, 0.005), {v = 0.05, force = 50, wrench = 'jr3'})",
      "selfmove{joint = 3, by = 2, t = 0.1}",
  };
  for (const char* code : honoured) {
    auto r = Make({{"pa10", std::string(code) + "\n"}});
    EXPECT_TRUE(RunFor(*r, 2000)) << code << ": " << r->error();
    EXPECT_TRUE(r->finished()) << code;
  }
}

TEST_F(MessagesTest, TimingOptionsOfMovejChangeItsDuration) {
  // jv and t are honoured: the same joint move takes as long as they say
  auto periods_of = [this](const std::string& options) {
    auto r = Make({{"pa10", "movej({0, 30, 0, 60, 0, 120, 0}" + options + ")\n"}});
    int ran = 0;
    EXPECT_TRUE(RunFor(*r, 10000, &ran)) << r->error();
    return ran;
  };
  const int plain = periods_of(""), fast = periods_of(", {jv = 60}"), timed = periods_of(", {t = 0.5}");
  EXPECT_LT(fast, plain);
  EXPECT_NEAR(timed, 0.5 / kPeriod, 2);
}

TEST_F(MessagesTest, NotFiniteInputIsRefusedByNameBeforeAnyIk) {
  const struct {
    const char* code;
    const char* message;
  } cases[] = {
      {"movej({0, 0/0, 0, 60, 0, 90, 0})", "pa10.lua:1: movej: joint 2 is"},
      {"movej({0, 30, 0, 1/0, 0, 90, 0})", "pa10.lua:1: movej: joint 4 is inf, not a finite angle"},
      {"movel(frame(vec3(1, 0, 0) / 0))", "pa10.lua:1: movel: the target position (inf, "},
      {"movej(frame(vec3(1, 0, 0) / 0 - vec3(1, 0, 0) / 0))", "pa10.lua:1: movej: the target position (-nan, "},
      {"movec(vec3(0, 0, 1) / 0, pose())", "pa10.lua:1: movec: the via point ("},
  };
  for (const auto& c : cases) {
    auto r = Make({{"pa10", std::string(c.code) + "\n"}});
    EXPECT_FALSE(RunFor(*r, 5)) << c.code;
    EXPECT_HAS(r->error(), c.message);
    EXPECT_EQ(r->error().find("limit"), std::string::npos) << r->error();
  }
}

TEST_F(MessagesTest, AnUnreachableTargetSaysHowFarInMetres) {
  // 2 m from the base: about 0.8 m beyond the PA10's reach
  auto r = Make({{"pa10", "movel(frame(2.0, 0, 0.5) * rpy(180, 0, 0))\n"}});
  EXPECT_FALSE(RunFor(*r, 10));
  EXPECT_HAS(r->error(), "pa10.lua:1: movel: the target is out of reach: the IK's closest pose is ");
  EXPECT_HAS(r->error(), " m from the target position");
  EXPECT_HAS(r->error(), "(final residual after");
  // the residual is the distance beyond reach, not the first failing sample's
  const auto at = r->error().find("closest pose is ");
  const double residual_m = std::stod(r->error().substr(at + 16));
  EXPECT_GT(residual_m, 0.5);  // (measured 1.11 m: the arm stretched out towards it, E1 = 0)
  EXPECT_LT(residual_m, 1.5);
  auto j = Make({{"pa10", "movej(frame(2.0, 0, 0.5) * rpy(180, 0, 0))\n"}});
  EXPECT_FALSE(RunFor(*j, 10));
  EXPECT_HAS(j->error(), "pa10.lua:1: movej: out of reach: the IK's closest pose is 1.");
}

TEST_F(MessagesTest, TheWristSingularityIsNamedWithItsJoint) {
  auto chain = control::RobotModel::Create(model_, {"world", "tool"});
  MotionPlanner planner(chain.get(), kPeriod);
  Eigen::VectorXd q(7);
  q << 0, 0.5236, 0, 1.0472, 0, 0.5 * M_PI / 180, 0;  // W1 = 0.5 deg: E2 and W2 nearly in line
  EXPECT_EQ(planner.Singularity(q), "wrist singularity near W1 = 0.5 deg (the axes of E2 and W2 line up)");
  q[5] = M_PI / 2;  // the ready pose: none
  EXPECT_EQ(planner.Singularity(q), "");
  q[3] = 0.2 * M_PI / 180;  // E1 = 0.2 deg: the arm stretched out, S3 and E2 in line
  EXPECT_EQ(planner.Singularity(q), "elbow singularity near E1 = 0.2 deg (the axes of S3 and E2 line up)");
}

TEST_F(MessagesTest, AProgramThatDiedIsNotEndedInTheLog) {
  auto r = Make({{"pa10", "print('start')\n\nerror('stop here')\n"}});
  std::vector<double> columns(r->Columns().size(), -7);
  EXPECT_FALSE(r->Step(0, columns.data()));
  EXPECT_EQ(columns[0], 3);  // task.pa10.line: where it died, not 0 ("ended")
  auto ok = Make({{"pa10", "print('start')\n"}});
  EXPECT_TRUE(ok->Step(0, columns.data()));
  EXPECT_EQ(columns[0], 0);
}

}  // namespace
}  // namespace vlab::task
