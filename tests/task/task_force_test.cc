// Guards (direction, torque, stop_if), search and force mode's admittance on the fake
// devices of task_runtime_fixture.h: a perfect servo and a wrench whose reading the test
// sets period by period. (Force mode against the physics: task_force_mode_test.cc.)
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "task_runtime_fixture.h"

namespace vlab::task {
namespace {

class ForceTest : public RuntimeTest {
 protected:
  // runs `script` on robot pa10 for up to `periods`, calling at(k) before period k; the
  // period the program ended in (-1: it did not); fails the test on an error
  int Run(const std::string& script, int periods, const std::function<void(int)>& at = nullptr) {
    auto r = Make({{"pa10", script}});
    for (int k = 0; k < periods; ++k) {
      if (at) at(k);
      EXPECT_TRUE(r->Step(k * kPeriod, nullptr)) << r->error();
      if (r->finished()) return k;
    }
    return -1;
  }
  // the error of `script` (run until it fails), "" when it ran to its end
  std::string ErrorOf(const std::string& script) {
    auto r = Make({{"pa10", script}});
    for (int k = 0; k < 5000; ++k) {
      if (!r->Step(k * kPeriod, nullptr)) return r->error();
      if (r->finished()) return "";
    }
    return "";
  }
  // the last command sent to the arm is the one sent `back` commands before it
  bool HeldFor(std::size_t back) const {
    const auto& c = arm_->commands();
    return c.size() > back && c.back() == c[c.size() - 1 - back];
  }
};

// The tool points down at the ready pose (its z is the world's -z); the sensor's axes are
// the tool site's. A reading change dF (sensor frame) is the world's push on the tool, so
// the tool exerts -R dF: dF = (8, 0, 0) is a lateral 8 N (the tool exerts it along world
// +x), dF = (0, 0, -6) is 6 N pressed down (along world -z).
TEST_F(ForceTest, DirectionGuardFiresOnTheComponentNotTheNorm) {
  const Eigen::Vector3d weight = wrench_.force;
  const std::string script = "print(movel(pose() * trans(0, 0, 0.05), {v = 0.02, force = 5, dir = vec3(0, 0, -1)}))\n";
  const int ended = Run(script, 4000, [&](int k) {
    if (k == 100) wrench_.force = weight + Eigen::Vector3d(8, 0, 0);   // 8 N across: the norm is over 5
    if (k == 300) wrench_.force = weight + Eigen::Vector3d(8, 0, -6);  // 6 N along dir
  });
  ASSERT_EQ(printed_.size(), 1u);
  EXPECT_EQ(printed_[0], "pa10@301: contact");
  EXPECT_EQ(ended, 301);
  EXPECT_TRUE(HeldFor(1));
  // the norm guard fires on the lateral force alone
  printed_.clear();
  wrench_.force = weight;
  const int ended_norm = Run("print(movel(pose() * trans(0, 0, 0.05), {v = 0.02, force = 5}))\n", 4000, [&](int k) {
    if (k == 100) wrench_.force = weight + Eigen::Vector3d(8, 0, 0);
  });
  ASSERT_EQ(printed_.size(), 1u);
  EXPECT_EQ(printed_[0], "pa10@101: contact");
  EXPECT_EQ(ended_norm, 101);
}

TEST_F(ForceTest, TorqueGuardFiresOnTheTorquesChange) {
  const Eigen::Vector3d moment = wrench_.torque;
  const std::string script = "print(movel(pose() * trans(0, 0, 0.05), {v = 0.02, torque = 0.5}))\n";
  Run(script, 4000, [&](int k) {
    if (k == 50) wrench_.torque = moment + Eigen::Vector3d(0, 0.4, 0);  // below the limit
    if (k == 100) wrench_.torque = moment + Eigen::Vector3d(0, 0.4, 0.4);
  });
  ASSERT_EQ(printed_.size(), 1u);
  EXPECT_EQ(printed_[0], "pa10@101: torque");
}

TEST_F(ForceTest, StopIfStopsTheMoveInThePeriodItComesTrue) {
  const std::string script =
      "local n = 0\n"
      "local out = movel(pose() * trans(0, 0, 0.05), {v = 0.02, stop_if = function() n = n + 1 return n == 50 end})\n"
      "print(out, n)\n"
      "wait(0.1)\n";
  Run(script, 4000);
  ASSERT_EQ(printed_.size(), 1u);
  EXPECT_EQ(printed_[0], "pa10@49: condition\t50");
  EXPECT_TRUE(HeldFor(50));  // at rest where it stopped, through the wait
  EXPECT_NE(ErrorOf("movel(pose() * trans(0, 0, 0.05), {stop_if = function() wait(0.1) end})\n")
                .find("pa10.lua:1: stop_if: the condition must not wait"),
            std::string::npos);
}

// search along a direction: "contact" and the planned pose where the guard fired, or
// "done" and nil at max
TEST_F(ForceTest, SearchReturnsWhereItsGuardFired) {
  const Eigen::Vector3d weight = wrench_.force;
  const std::string script =
      "local z0 = planned().z\n"
      "local out, at = search(vec3(0, 0, -1), {force = 5, max = 0.05, v = 0.02})\n"
      "print(out, string.format('%.6f', z0 - at.z), string.format('%.6f', z0 - planned().z))\n";
  Run(script, 4000, [&](int k) {
    if (k == 200) wrench_.force = weight + Eigen::Vector3d(0, 0, -6);  // pressed down by 6 N
  });
  // the guard fires in period 200, after 200 samples (0.4 s) of a trapezoid at 0.02 m/s with
  // a ramp of 0.04 s (0.5 m/s^2): 0.02 * (0.4 - 0.02) = 7.6 mm down; planned() is that sample
  ASSERT_EQ(printed_.size(), 1u);
  EXPECT_EQ(printed_[0], "pa10@201: contact\t0.007600\t0.007600");
  printed_.clear();
  wrench_.force = weight;
  Run("local z0 = planned().z\n"
      "local out, at = search(vec3(0, 0, -1), {force = 5, max = 0.05, v = 0.02})\n"
      "print(out, at, string.format('%.6f', z0 - planned().z))\n",
      4000);
  ASSERT_EQ(printed_.size(), 1u);
  EXPECT_NE(printed_[0].find(": done\tnil\t0.050000"), std::string::npos) << printed_[0];
}

// Without contact the admittance moves the tool toward the target force at k F (k = 2e-3
// m/s per N: 4 mm/s for 2 N), its speed ramped at the accel() setting (0.5 m/s^2: 1 mm/s
// more each 2 ms period), along the held axis only. Its sign: +fz of the tool frame is the
// tool pushing along its z (down here); -fz of the base frame is the same.
TEST_F(ForceTest, ForceModeMovesAlongTheHeldAxisOnly) {
  for (const char* mode : {"force_mode({fz = 2})", "force_mode({fz = -2}, {frame = 'base'})"}) {
    printed_.clear();
    const std::string script = std::string("local p0 = planned()\n") + mode +
                               "\n"
                               "wait(1.0)\n"
                               "local d = planned().pos - p0.pos\n"
                               "print(string.format('%.6f', d.z), math.abs(d.x) < 1e-8 and math.abs(d.y) < 1e-8)\n"
                               "end_force_mode()\n";
    Run(script, 1000);
    ASSERT_EQ(printed_.size(), 1u) << mode;
    // 500 periods: 1, 2, 3 mm/s, then 497 at 4 mm/s: 2 ms * 1.994 m/s
    EXPECT_NE(printed_[0].find(": -0.003988\ttrue"), std::string::npos) << mode << " " << printed_[0];
  }
  // the speed limit v: 100 N asks for 0.2 m/s, v = 0.01 holds it to 10 mm/s (ramp 1..9 mm/s)
  printed_.clear();
  Run("local z0 = planned().z\nforce_mode({fz = 100}, {v = 0.01})\nwait(1.0)\n"
      "print(string.format('%.6f', z0 - planned().z))\n",
      1000);
  ASSERT_EQ(printed_.size(), 1u);
  EXPECT_NE(printed_[0].find(": 0.009910"), std::string::npos) << printed_[0];
}

// stop() in force mode halts the move on its path (the plan's tool poses, which the
// admittance moves along the held axes): on the line, short of its end (at 0.3 s the tool
// has gone 20 mm at 0.1 m/s, and stops within some mm), "stopped"
TEST_F(ForceTest, StopHaltsAMoveInForceModeOnItsPath) {
  const std::string script =
      "local p0 = planned()\n"
      "force_mode({fz = 0})\n"
      "local out = movel_rel(trans(0.05, 0, 0), {rel = 'base', at = {{t = 0.3, call = function() stop() end}}})\n"
      "wait(0.2)\n"
      "local d = planned().pos - p0.pos\n"
      "print(out, d.x > 0.02 and d.x < 0.045, math.abs(d.y) < 1e-8 and math.abs(d.z) < 1e-8)\n";
  Run(script, 2000);
  ASSERT_EQ(printed_.size(), 1u);
  EXPECT_NE(printed_[0].find(": stopped\ttrue\ttrue"), std::string::npos) << printed_[0];
  EXPECT_TRUE(HeldFor(20));
}

// a pose the admittance drives out of reach ends force mode: an error at the script's wait
TEST_F(ForceTest, ForceModeOutOfReachIsAnErrorAtTheWait) {
  const std::string error = ErrorOf("force_mode({fz = 1000}, {v = 0.5})\nwait(5)\n");
  EXPECT_NE(error.find("pa10.lua:2: force mode: "), std::string::npos) << error;
  EXPECT_NE(error.find("force mode has ended, the arm holds its last command"), std::string::npos) << error;
}

TEST_F(ForceTest, BadTargetsAndOptionsAreErrorsAtTheirLine) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"force_mode(10)", "pa10.lua:1: force_mode: argument 1 must be a table of the forces to hold"},
      {"force_mode({})", "pa10.lua:1: force_mode: the target holds no axis"},
      {"force_mode({tz = 1})", "force_mode: target: option 'tz' is not supported: force mode holds forces only"},
      {"force_mode({fz = 'x'})", "force_mode: target: option fz must be a number, got string"},
      {"force_mode({fz = 0/0})", "force_mode: target: option fz is not finite"},
      {"force_mode({fw = 1})", "force_mode: target: unknown option 'fw' (options: fx, fy, fz)"},
      {"force_mode({fz = 1}, {v = 0})", "force_mode: option v (the speed limit along a held axis) must be > 0"},
      {"force_mode({fz = 1}, {frame = 'table'})", "force_mode: option frame: no user frame 'table'"},
      {"force_mode({fz = 1}, {frame = 3})", "force_mode: option frame must be \"tool\", \"base\" or a user frame's"},
      {"force_mode({fz = 1}, {wrench = 'gripper'})", "force_mode: option wrench: no wrench device named 'gripper'"},
      {"force_mode({fz = 1}, {k = 1})", "force_mode: unknown option 'k' (options: frame, v, wrench)"},
      {"force_mode({fz = 1})\nmovej({0, 30, 0, 60, 0, 90, 0})", "pa10.lua:2: movej: not in force mode"},
      {"force_mode({fz = 1})\nselfmove{by = 10, t = 1}", "pa10.lua:2: selfmove: not in force mode"},
      {"force_mode({fz = 1})\nservoj({0, 30, 0, 60, 0, 90, 0})", "pa10.lua:2: servoj: not in force mode"},
      {"force_mode({fz = 1})\nmovel(pose() * trans(0.01, 0, 0), {r = 0.001})",
       "pa10.lua:2: movel: a move in force mode cannot blend (r = 0.001 m)"},
      {"movel(pose(), {dir = vec3(0, 0, 1)})", "movel: option dir is the direction of the force guard: give force"},
      {"movel(pose(), {force = 1, dir = vec3(0, 0, 0)})", "movel: option dir must be a finite, non-zero direction"},
      {"movel(pose(), {force = 1, dir = 1})", "movel: option dir must be a vec3 (a direction in the base frame)"},
      {"movel(pose(), {torque = -1})", "movel: option torque must be > 0 N m"},
      {"movel(pose(), {stop_if = true})", "movel: option stop_if must be a function (called once per period)"},
      {"movel(pose(), {stop_if = function() end, async = true})", "movel: option stop_if is called while the move's"},
      {"movel(pose(), {stop_if = function() end, r = 0.01})", "movel: a guarded move (force, torque, stop_if) stops"},
      {"movej({0, 30, 0, 60, 0, 90, 0}, {torque = 1})", "movej: option 'torque' is not supported"},
      {"movep({pose()}, {stop_if = function() end})", "movep: option 'stop_if' is not supported"},
      {"search(vec3(0, 0, -1), {max = 0.1})", "search: needs a guard to stop it"},
      {"search(vec3(0, 0, -1), {force = 5})", "search: a search along a direction needs max"},
      {"search(vec3(0, 0, 0), {force = 5, max = 0.1})", "search: the direction must be finite and non-zero"},
      {"search(vec3(0, 0, -1), {force = 5, max = 0.1, dir = vec3(1, 0, 0)})", "search: along a direction the force"},
      {"search(pose(), {force = 5, max = 0.1})", "search: option max is for a search along a direction"},
      {"search(3, {force = 5})", "search: argument 1 must be a direction (a vec3, base frame) or a target frame"},
      {"search(vec3(0, 0, -1), {force = 5, max = 0.1, t = 1})", "search: option 't' is not supported"},
  };
  for (const auto& [script, expected] : cases) {
    const std::string error = ErrorOf(script + "\n");
    EXPECT_NE(error.find(expected), std::string::npos) << script << "\n -> " << error;
  }
}

}  // namespace
}  // namespace vlab::task
