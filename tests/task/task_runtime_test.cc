// The task runtime on fake devices: a perfect position servo per arm (the
// state's q is the last commanded position) and a settable wrench. Checks
// the sandbox, the instruction budget, errors with file:line, seeded random
// numbers, sorted pairs, waits, guarded moves, limits before a move, and two
// robot programs synchronising through a signal.
#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "control/robot_model.h"
#include "core/core_errors.h"
#include "mujoco_fixture.h"
#include "task/task_motion.h"
#include "task/task_runtime.h"
#include "task_runtime_fixture.h"
#include "test_util.h"

namespace vlab::task {
namespace {

TEST_F(RuntimeTest, SandboxRefusesTheMachine) {
  auto r = Make({{"",
                  "assert(io == nil and os == nil and dofile == nil and loadfile == nil and debug == nil)\n"
                  "assert(string.dump == nil and package == nil)\n"
                  "local ok, e = pcall(require, '../secret')\n"
                  "print(ok, e)\n"}});
  ASSERT_TRUE(RunFor(*r, 10)) << r->error();
  ASSERT_EQ(printed_.size(), 1u);
  EXPECT_NE(printed_[0].find("main.lua:3: require: '../secret' is not a module name of the script's folder"),
            std::string::npos)
      << printed_[0];
}

TEST_F(RuntimeTest, RequireLoadsFromTheScriptFolder) {
  testing::WriteFile(dir_ / "helpers.lua", "return {answer = 42}\n");
  auto r = Make({{"", "print(require('helpers').answer)\n"}});
  ASSERT_TRUE(RunFor(*r, 10)) << r->error();
  EXPECT_EQ(printed_, std::vector<std::string>{"main.lua@0: 42"});
}

TEST_F(RuntimeTest, RunawayLoopIsAnErrorAtItsLine) {
  auto r = Make({{"", "local n = 0\nwhile true do\n  n = n + 1\nend\n"}}, 1, 100'000);
  EXPECT_FALSE(r->Step(0, nullptr));
  EXPECT_NE(r->error().find("main.lua:3: instruction budget exceeded: 100000 instructions without a wait"),
            std::string::npos)
      << r->error();
  // a loop that waits is fine
  auto ok =
      Make({{"", "for i = 1, 50 do\n  local x = 0\n  for j = 1, 5000 do x = x + j end\n  sync()\nend\n"}}, 1, 100'000);
  EXPECT_TRUE(RunFor(*ok, 100)) << ok->error();
}

TEST_F(RuntimeTest, SyntaxErrorIsAnInputErrorBeforeAnythingRuns) {
  try {
    Make({{"", "print('never')\nif x then\n"}});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("main.lua:3:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("syntax error: nothing has run"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(printed_.empty());
}

TEST_F(RuntimeTest, RuntimeErrorGivesLineAndTraceback) {
  auto r = Make({{"", "local function f(t)\n  return t.x.y\nend\nwait(0.01)\nf({})\n"}});
  int ran = 0;
  EXPECT_FALSE(RunFor(*r, 100, &ran));
  EXPECT_EQ(ran, 5);  // periods 0..4 waited (0.01 s), period 5 failed
  EXPECT_NE(r->error().find("main.lua:2: attempt to index a nil value (field 'x')"), std::string::npos) << r->error();
  EXPECT_NE(r->error().find("stack traceback:"), std::string::npos);
  EXPECT_NE(r->error().find("main.lua:5: in main chunk"), std::string::npos) << r->error();
}

// Lua 5.4 seeds its string hash per run, so the raw pairs order varies between
// runs (notes/task-language.md); the sandbox's pairs is sorted: this order is the
// only one it can give, whatever the hash.
TEST_F(RuntimeTest, PairsAndNextIterateInSortedOrder) {
  auto r = Make({{"",
                  "local t = {pear = 1, apple = 2, fig = 3, [10] = 4, [2] = 5, banana = 6, [true] = 7}\n"
                  "local keys = {}\n"
                  "for k in pairs(t) do keys[#keys + 1] = tostring(k) end\n"
                  "local k, n = next(t), {}\n"
                  "while k ~= nil do n[#n + 1] = tostring(k); k = next(t, k) end\n"
                  "print(table.concat(keys, ','), table.concat(n, ','))\n"}});
  ASSERT_TRUE(RunFor(*r, 10)) << r->error();
  EXPECT_EQ(printed_,
            std::vector<std::string>{"main.lua@0: 2,10,apple,banana,fig,pear,true\t2,10,apple,banana,fig,pear,true"});
}

TEST_F(RuntimeTest, RandomIsSeededFromTheScenarioSeed) {
  const char* script = "print(math.random(1, 1000000), math.random())\n";
  std::vector<std::string> runs;
  for (std::uint64_t seed : {7, 7, 8}) {
    printed_.clear();
    auto r = Make({{"", script}}, seed);
    ASSERT_TRUE(RunFor(*r, 2));
    runs.push_back(printed_.at(0));
  }
  EXPECT_EQ(runs[0], runs[1]);
  EXPECT_NE(runs[0], runs[2]);
}

// PARAMS: the program's parameters, typed from their text (a scenario's `params`, vlab
// task --param): whole numbers and decimals are numbers, true/false booleans, the rest strings
TEST_F(RuntimeTest, ParamsReachTheScriptTyped) {
  auto r = Make({{"", "for k, v in pairs(PARAMS) do print(k, type(v), v) end\n"}}, 1, 1'000'000,
                {{"word", "FACE"},
                 {"gain", "2.5"},
                 {"n", "4"},
                 {"fast", "true"},
                 {"list", "1,2"},
                 {"blank", " 7"},
                 {"empty", ""}});
  ASSERT_TRUE(RunFor(*r, 2)) << r->error();
  EXPECT_EQ(printed_, (std::vector<std::string>{"main.lua@0: blank\tstring\t 7", "main.lua@0: empty\tstring\t",
                                                "main.lua@0: fast\tboolean\ttrue", "main.lua@0: gain\tnumber\t2.5",
                                                "main.lua@0: list\tstring\t1,2", "main.lua@0: n\tnumber\t4",
                                                "main.lua@0: word\tstring\tFACE"}));
  EXPECT_EQ(ParseParam("word=FACE=1"), (std::pair<std::string, std::string>{"word", "FACE=1"}));
  EXPECT_THROW(ParseParam("word"), InputError);
  EXPECT_THROW(ParseParam("2x=1"), InputError);
  EXPECT_THROW(ParseParam("a-b=1"), InputError);
}

TEST_F(RuntimeTest, WaitCountsPeriodsAndConditionsTimeOut) {
  auto r = Make({{"",
                  "wait(0.1)\nprint('a')\n"
                  "local v = wait(function() return nil end, 0.05)\nprint('b', v)\n"
                  "local w = wait(function() return now() >= 0.2 and 'yes' end)\nprint('c', w)\n"}});
  ASSERT_TRUE(RunFor(*r, 1000)) << r->error();
  // 0.1 s = 50 periods; the condition times out after 25 more; now() >= 0.2 at period 100
  EXPECT_EQ(printed_, (std::vector<std::string>{"main.lua@50: a", "main.lua@75: b\tnil", "main.lua@100: c\tyes"}));
}

TEST_F(RuntimeTest, LimitsAreCheckedBeforeTheMoveStarts) {
  auto r = Make({{"pa10", "movej({0, 30, 0, 60, 0, 90, 0})\nmovej({0, 100, 0, 60, 0, 90, 0})\n"}});
  EXPECT_FALSE(RunFor(*r, 5000));
  EXPECT_NE(r->error().find("pa10.lua:2: movej: the target: joint S2 = 100 deg is beyond its upper limit 94 deg"),
            std::string::npos)
      << r->error();
  // the arm never got a command beyond the limit
  for (const Eigen::VectorXd& q : arm_->history()) EXPECT_LE(q[1], 94 * M_PI / 180);
  auto far = Make({{"pa10b", "movel(frame(2.0, 0, 0.5) * rpy(180, 0, 0))\n"}});
  EXPECT_FALSE(RunFor(*far, 10));
  EXPECT_NE(far->error().find("pa10b.lua:1: movel: the target is out of reach: "), std::string::npos) << far->error();
  EXPECT_NE(far->error().find("% of the path"), std::string::npos) << far->error();
  EXPECT_TRUE(arm2_->history().empty());  // not one command: the plan failed before the move
}

// a guarded movel stops at the period after the force (tared at the start) exceeds the threshold
TEST_F(RuntimeTest, GuardedMoveStopsOnForce) {
  auto r = Make({{"pa10",
                  "local start = pose()\n"
                  "local hit = movel(start * trans(0, 0, 0.1), {force = 5, v = 0.02})\n"
                  "print(hit, (pose().pos - start.pos):norm())\n"}});
  int k = 0;
  for (; k < 5000 && !r->finished(); ++k) {
    if (k == 200) wrench_.force.z() += 6;  // contact at 0.4 s
    ASSERT_TRUE(r->Step(k * kPeriod, nullptr)) << r->error();
  }
  ASSERT_EQ(printed_.size(), 1u);
  EXPECT_EQ(printed_[0].substr(0, 20), "pa10@201: contact\t0.") << printed_[0];
  // distance at 0.4 s on the trapezoid (v 0.02 m/s, a 0.5 m/s^2): 0.02 (0.4 - 0.04 / 2) = 7.6 mm
  const double d = std::stod(printed_[0].substr(printed_[0].find('\t') + 1));
  EXPECT_NEAR(d, 0.0076, 0.02 * kPeriod * 2);
}

// two robot programs: pa10b waits for pa10's signal; programs resume in order
// (pa10 first), so pa10b's first sample is in the very period pa10's move has
// ended (period 250); shared values travel by value.
TEST_F(RuntimeTest, TwoRobotProgramsSynchroniseThroughASignal) {
  auto r = Make({{"pa10", "movej({8, 30, 0, 60, 0, 90, 0}, {t = 0.5})\nshared.where = pose()\nsignal('done')\n"},
                 {"pa10b",
                  "wait_signal('done')\nprint('go', shared.where.pos.x > 0)\n"
                  "movej({-8, 30, 0, 60, 0, 90, 0}, {t = 0.5})\n"}});
  ASSERT_TRUE(RunFor(*r, 2000)) << r->error();
  EXPECT_EQ(printed_, std::vector<std::string>{"pa10b@250: go\ttrue"});
  // pa10 reached its goal at period 249 (250 samples of 2 ms); pa10b had not moved until then
  const auto& a = arm_->history();
  const auto& b = arm2_->history();
  ASSERT_GE(a.size(), 250u);
  EXPECT_NEAR(a[249][0], 8 * M_PI / 180, 1e-12);
  for (int k = 0; k < 250; ++k) EXPECT_EQ(b[k][0], 0.0) << k;
  EXPECT_LT(b[250][0], 0.0);
  EXPECT_NEAR(arm2_->q()[0], -8 * M_PI / 180, 1e-12);
}

// gripper(name) and device(name): commands by field name, re-sent every period
// until changed; states by field name
TEST_F(RuntimeTest, GripperAndDevicesByName) {
  auto r = Make({{"",
                  "local g = gripper('gripper')\n"
                  "print(g:opening(), g:grasped())\n"
                  "g:close(20)\n"
                  "local ok = wait(function() return g:grasped() end, 1.0)\n"
                  "print(ok, device('gripper'):get('opening'), device('gripper'):read().grasped)\n"
                  "device('gripper'):send{mode = 0, value = 0.07}\n"
                  "wait(0.1)\n"
                  "print(g:opening())\n"
                  "local ok2, e = pcall(device, 'camera')\n"
                  "print(e)\n"}});
  ASSERT_TRUE(RunFor(*r, 1000)) << r->error();
  // 0.08 -> 0.05 at 0.1 m/s: 0.3 s = 150 periods; then toward 0.07 for 0.1 s (50 periods): 0.06
  ASSERT_EQ(printed_.size(), 4u);
  EXPECT_EQ(printed_[0], "main.lua@0: 0.08\tfalse");
  EXPECT_EQ(printed_[1], "main.lua@150: true\t0.05\t1.0");
  EXPECT_NEAR(std::stod(printed_[2].substr(14)), 0.06, 1e-12) << printed_[2];
  EXPECT_NE(printed_[3].find("main.lua:9: device: no device named 'camera'"), std::string::npos) << printed_[3];
  EXPECT_EQ(gripper_.commands.front(), (std::vector<double>{1, 20}));
  EXPECT_EQ(gripper_.commands.back(), (std::vector<double>{0, 0.07}));
  EXPECT_EQ(gripper_.commands.size(), 201u);  // one per period from the close on (periods 0..200)
}

// ---- blending (movel's r, blend()): a right-angle corner B, from the ready pose 0.10 m
// along -x to B, then 0.10 m along +y to C; speed 0.1 m/s, acceleration 0.5 m/s^2 (the defaults)
class BlendTest : public RuntimeTest {
 protected:
  // the tool positions the arm was commanded to, one per period (forward kinematics)
  std::vector<Eigen::Vector3d> ToolPath() {
    auto fk = control::RobotModel::Create(model_, {"world", "tool"});
    MotionPlanner planner(fk.get(), kPeriod);
    std::vector<Eigen::Vector3d> out;
    for (const Eigen::VectorXd& q : arm_->history()) out.push_back(planner.ToolPose(q).p);
    return out;
  }
  static constexpr const char* kCorner =
      "local a = pose()\n"
      "B = frame(a.pos + vec3(-0.10, 0, 0), a.rot)\n"
      "C = frame(a.pos + vec3(-0.10, 0.10, 0), a.rot)\n";
  const double r_ = 0.02, v_ = 0.1;
};

TEST_F(BlendTest, MovelWithRadiusPassesTheCornerWithinItWithoutStoppingAndEndsOnTarget) {
  auto run = [this](const std::string& moves, std::vector<Eigen::Vector3d>* path, Eigen::Vector3d* B,
                    Eigen::Vector3d* C) {
    Eigen::VectorXd ready(7);  // both runs start from the ready pose
    ready << 0, 0.523599, 0, 1.047198, 0, 1.570796, 0;
    arm_ = std::make_unique<FakeArm>("pa10", ready);
    devices_.channels["pa10"] = arm_.get();
    auto r = Make({{"pa10", std::string(kCorner) + moves + "print(B.x, B.y, B.z, C.x, C.y, C.z)\n"}});
    printed_.clear();
    ASSERT_TRUE(RunFor(*r, 5000)) << r->error();
    for (int k = 0; k < 1500; ++k) ASSERT_TRUE(r->Step((5000 + k) * kPeriod, nullptr));  // the blended motion ends
    *path = ToolPath();
    std::istringstream in(printed_.back().substr(printed_.back().find(": ") + 2));
    in >> (*B)[0] >> (*B)[1] >> (*B)[2] >> (*C)[0] >> (*C)[1] >> (*C)[2];
  };
  std::vector<Eigen::Vector3d> blended, stopped;
  Eigen::Vector3d B, C;
  run("movel(B, {r = 0.02})\nmovel(C)\n", &blended, &B, &C);
  run("movel(B)\nmovel(C)\n", &stopped, &B, &C);

  auto closest = [&](const std::vector<Eigen::Vector3d>& p) {
    double d = 1e9;
    for (const auto& x : p) d = std::min(d, (x - B).norm());
    return d;
  };
  // the quadratic Bezier P1 B P2 (|P1 - B| = |P2 - B| = d, a right angle) passes B at
  // 0.25 |2B - P1 - P2| = 0.25 sqrt(2) d = 0.354 d; the blend is entered at the first period
  // within r of B, so d is in (r - v T, r]: the closest approach is in (0.353 r, 0.354 r]
  const double d_min = closest(blended);
  EXPECT_LE(d_min, r_);
  EXPECT_GT(d_min, 0.30 * r_) << "it cuts the corner more than a blend of radius r does";
  EXPECT_NEAR(d_min, 0.3536 * r_, 0.0005 * r_ + 0.36 * v_ * kPeriod);
  EXPECT_LT(closest(stopped), 1e-9);  // without r the path goes through B

  // speed between the moves: within 2 r of B the blended path keeps the cruise speed (no stop;
  // the entry is at cruise: r > v^2 / (2 a) = 10 mm), the stopped one comes to rest at B
  auto slowest_near_b = [&](const std::vector<Eigen::Vector3d>& p) {
    double v_min = 1e9;
    for (std::size_t k = 1; k < p.size(); ++k) {
      if ((p[k] - B).norm() < 2 * r_) v_min = std::min(v_min, (p[k] - p[k - 1]).norm() / kPeriod);
    }
    return v_min;
  };
  EXPECT_GT(slowest_near_b(blended), 0.95 * v_);
  EXPECT_LT(slowest_near_b(stopped), 0.05 * v_);
  // velocity continuous: speed changes by at most the acceleration limit per period (plus rounding)
  for (std::size_t k = 2; k < blended.size(); ++k) {
    const double v1 = (blended[k - 1] - blended[k - 2]).norm() / kPeriod,
                 v2 = (blended[k] - blended[k - 1]).norm() / kPeriod;
    ASSERT_LE(std::abs(v2 - v1), 0.5 * kPeriod * 1.01 + 1e-9) << "period " << k;
  }
  // the final target is reached as without blend: C, to the IK tolerance (1e-9 m)
  EXPECT_LT((blended.back() - C).norm(), 1e-8);
  EXPECT_LT((stopped.back() - C).norm(), 1e-8);
  // and it takes less time: no stop at B
  std::size_t arrive_blended = 0, arrive_stopped = 0;
  while (arrive_blended + 1 < blended.size() && (blended[arrive_blended] - C).norm() > 1e-8) ++arrive_blended;
  while (arrive_stopped + 1 < stopped.size() && (stopped[arrive_stopped] - C).norm() > 1e-8) ++arrive_stopped;
  EXPECT_LT(arrive_blended, arrive_stopped);
}

// movec's r: a quarter circle (radius 0.1 m, centre 0.1 m along -x of the ready pose) to B,
// blended into a line at a right angle to the arc's end tangent
TEST_F(BlendTest, MovecWithRadiusBlendsIntoTheNextLineAlongItsTangent) {
  auto r = Make({{"pa10",
                  "local a = pose()\n"
                  "local o = a.pos + vec3(-0.1, 0, 0)\n"
                  "B = frame(o + vec3(0, 0.1, 0), a.rot)\n"
                  "C = frame(o + vec3(0, 0.2, 0), a.rot)\n"
                  "movec(o + vec3(0.1 / math.sqrt(2), 0.1 / math.sqrt(2), 0), B, {r = 0.02})\n"
                  "movel(C)\n"
                  "print(B.x, B.y, B.z, C.x, C.y, C.z)\n"}});
  ASSERT_TRUE(RunFor(*r, 5000)) << r->error();
  for (int k = 0; k < 1500; ++k) ASSERT_TRUE(r->Step((5000 + k) * kPeriod, nullptr));
  Eigen::Vector3d B, C;
  std::istringstream in(printed_.back().substr(printed_.back().find(": ") + 2));
  in >> B[0] >> B[1] >> B[2] >> C[0] >> C[1] >> C[2];
  const std::vector<Eigen::Vector3d> p = ToolPath();
  double d_min = 1e9, v_near = 1e9, turn_max = 0;
  for (std::size_t k = 0; k < p.size(); ++k) d_min = std::min(d_min, (p[k] - B).norm());
  for (std::size_t k = 2; k < p.size(); ++k) {
    const Eigen::Vector3d v1 = (p[k - 1] - p[k - 2]) / kPeriod, v2 = (p[k] - p[k - 1]) / kPeriod;
    if ((p[k] - B).norm() < 2 * r_) v_near = std::min(v_near, v2.norm());
    if (v1.norm() > 0.5 * v_ && v2.norm() > 0.5 * v_)
      turn_max = std::max(turn_max, std::acos(std::clamp(v1.normalized().dot(v2.normalized()), -1.0, 1.0)));
  }
  EXPECT_LE(d_min, r_);
  EXPECT_GT(d_min, 0.25 * r_);
  EXPECT_GT(v_near, 0.95 * v_);  // no stop at B
  // the direction of motion turns smoothly: on the arc by v T / R = 2 mrad per period; a blend
  // that left the arc along the chord to B instead of its tangent would turn by about
  // r / (2 R) = 0.1 rad at once; the curve's own sharpest bend is about v T / (0.35 r) = 0.03 rad
  EXPECT_LT(turn_max, 0.05);
  EXPECT_LT((p.back() - C).norm(), 1e-8);
  std::printf("movec blend: closest %.3f mm, slowest near B %.4f m/s, sharpest turn %.4f rad per period\n", d_min * 1e3,
              v_near, turn_max);
}

TEST_F(BlendTest, RadiusOverHalfASegmentIsAnErrorAtItsLine) {
  // the first segment is 0.10 m long: r = 0.06 m is more than half of it
  auto first = Make({{"pa10", std::string(kCorner) + "movel(B, {r = 0.06})\nmovel(C)\n"}});
  EXPECT_FALSE(RunFor(*first, 5000));
  EXPECT_NE(first->error().find("pa10.lua:4: movel: the blend radius r = 0.06 m is larger than half of this move "
                                "(0.1 m): at most 0.05 m"),
            std::string::npos)
      << first->error();
  // the second one, 0.05 m from B, cannot take the 0.04 m radius of the first (blend() sets it)
  auto second = Make({{"pa10b", std::string(kCorner) + "blend(0.04)\nmovel(B)\nblend(0)\n"
                                                       "movel(frame(B.pos + vec3(0, 0.05, 0), B.rot))\n"}});
  EXPECT_FALSE(RunFor(*second, 5000));
  EXPECT_NE(second->error().find("pa10b.lua:7: movel: the blend radius r = 0.04 m of the move before is larger "
                                 "than half of this move (0.05 m from the corner): at most 0.025 m"),
            std::string::npos)
      << second->error();
}

// movep from a script: through B and C of the blend corner and back towards the start, the
// corner B passed at PathCornerGap(r, 90 deg), the commanded tool speed constant (2 %) between
// the ramps, "done" on the last point; the options it does not take named at the line
TEST_F(BlendTest, MovepHoldsTheToolSpeedThroughThePointsFromAScript) {
  auto r = Make({{"pa10", std::string(kCorner) + "D = frame(a.pos + vec3(0, 0.10, 0), a.rot)\n"
                                                 "print(movep({B, C, D}, {r = 0.02, v = 0.1}))\n"
                                                 "print((pose().pos - D.pos):norm() < 1e-9)\n"
                                                 "print(select(2, pcall(movep, {B, C}, {t = 2})))\n"
                                                 "print(select(2, pcall(movep, {B, 3})))\n"
                                                 "print(select(2, pcall(movep, B)))\n"
                                                 "print(select(2, pcall(movep, {B, C}, {r = 0})))\n"
                                                 "print(B.x, B.y, B.z)\n"}});
  ASSERT_TRUE(RunFor(*r, 5000)) << r->error();
  ASSERT_EQ(printed_.size(), 7u);
  EXPECT_NE(printed_[0].find(": done"), std::string::npos) << printed_[0];
  EXPECT_NE(printed_[1].find(": true"), std::string::npos) << printed_[1];
  EXPECT_NE(printed_[2].find("pa10.lua:7: movep: option 't' is not supported: movep holds the tool speed v"),
            std::string::npos)
      << printed_[2];
  EXPECT_NE(printed_[3].find("pa10.lua:8: movep: point 2: expected a frame, got number"), std::string::npos)
      << printed_[3];
  EXPECT_NE(printed_[4].find("pa10.lua:9: movep: expected a list of frames, got one frame"), std::string::npos)
      << printed_[4];
  EXPECT_NE(printed_[5].find("pa10.lua:10: movep: the corner radius r must be > 0 m, got 0"), std::string::npos)
      << printed_[5];
  std::istringstream in(printed_[6].substr(printed_[6].find(": ") + 2));
  Eigen::Vector3d B;
  in >> B[0] >> B[1] >> B[2];
  const std::vector<Eigen::Vector3d> path = ToolPath();
  double nearest = 1, worst = 0;
  const double ramp = v_ / 0.5;
  std::size_t first = path.size(), last = 0;  // the samples that move
  for (std::size_t i = 1; i < path.size(); ++i) {
    if ((path[i] - path[i - 1]).norm() > 1e-12) first = std::min(first, i), last = i;
  }
  for (std::size_t i = first; i <= last; ++i) {
    nearest = std::min(nearest, (path[i] - B).norm());
    const double t = (i - first) * kPeriod, left = (last - i) * kPeriod;
    if (t > ramp + 2 * kPeriod && left > ramp + 2 * kPeriod) {
      worst = std::max(worst, std::abs((path[i] - path[i - 1]).norm() / kPeriod - v_) / v_);
    }
  }
  EXPECT_NEAR(nearest, PathCornerGap(r_, M_PI / 2), 2e-4);
  EXPECT_LT(worst, 0.02);
}

// triggers (option at): along movel's 0.10 m from the ready pose to B, a signal at d = 0.05 m
// (another program takes it) and a call at t = 0.6 s; each fires in the period after the sample
// it names was commanded: the planned tool is then 0.05 m along (within one period's travel,
// 0.2 mm at 0.1 m/s), and now() is 0.6 s after the start within one period. Triggers beyond
// the move, with a blend, or malformed are errors at the line, before the arm moves.
TEST_F(BlendTest, TriggersFireWithinAPeriodOfTheirDistanceAndTime) {
  auto r = Make({{"pa10", std::string(kCorner) +
                              "local t0, called, at_d, at_t = now()\n"
                              "local function along() at_d, at_t = (planned().pos - a.pos):norm(), now() end\n"
                              "print(movel(B, {at = {{d = 0.03, signal = 'near'}, {d = 0.03, call = along},\n"
                              "                      {t = 0.6, call = function() called = now() - t0 end}}}))\n"
                              "print(string.format('%.9f %.6f %.6f', at_d, at_t, called))\n"
                              "print(select(2, pcall(movel, C, {at = {{d = 0.5, signal = 'x'}}})))\n"
                              "print(select(2, pcall(movel, C, {r = 0.02, at = {{t = 0, signal = 'x'}}})))\n"
                              "print(select(2, pcall(movel, C, {at = {{t = 0, d = 0, signal = 'x'}}})))\n"
                              "print(select(2, pcall(movej, C, {at = {{d = 0, signal = 'x'}}})))\n"
                              "print(select(2, pcall(movel, C, {at = {{t = 0}}})))\n"
                              "print((planned().pos - B.pos):norm() < 1e-9)\n"},
                 {"", "wait_signal('near')\nprint(string.format('%.6f', now()))\n"}});
  ASSERT_TRUE(RunFor(*r, 2000)) << r->error();
  ASSERT_EQ(printed_.size(), 9u);
  // the signal's receiver and the call at the same distance ran in the same period, when the
  // planned tool was 0.03 m along, past it by at most one period's travel (0.1 m/s x 2 ms)
  const std::string received = printed_[0].substr(printed_[0].find(": ") + 2);
  EXPECT_EQ(printed_[0].rfind("main.lua@", 0), 0u) << printed_[0];
  std::istringstream in(printed_[2].substr(printed_[2].find(": ") + 2));
  double at_d = 0, at_t = 0, called = 0;
  in >> at_d >> at_t >> called;
  EXPECT_GE(at_d, 0.03);
  EXPECT_LE(at_d, 0.03 + v_ * kPeriod);
  EXPECT_NEAR(std::stod(received), at_t, 1e-9);
  // the call at t = 0.6 s: in the period after the sample of 0.6 s was commanded
  EXPECT_GE(called, 0.6 - 1e-9);
  EXPECT_LE(called, 0.6 + kPeriod + 1e-9);
  EXPECT_NE(printed_[1].find(": done"), std::string::npos) << printed_[1];
  const char* errors[] = {
      "pa10.lua:9: movel: trigger 1: d = 0.5 m is beyond the move's path (0.1 m)",
      "pa10.lua:10: movel: a move with triggers (at) cannot blend (r = 0.02 m): give r = 0 (or blend(0))",
      "pa10.lua:11: movel: trigger 1: give d (m along the path) or t (s from the start), one of them",
      "pa10.lua:12: movej: trigger 1: d is a length along the tool's path: a joint move takes t",
      "pa10.lua:13: movel: trigger 1: give signal (a name) or call (a function), one of them"};
  for (int k = 0; k < 5; ++k) EXPECT_NE(printed_[3 + k].find(errors[k]), std::string::npos) << printed_[3 + k];
  // the refused moves did not move the arm: it is still at B
  EXPECT_NE(printed_[8].find(": true"), std::string::npos) << printed_[8];
}

// stop(name) from another program: the PA10's 0.3 m movel at 0.1 m/s is halted 0.5 s in, on
// its line, every joint's commanded acceleration within its limit, the tool at rest within
// the tool speed's fall at the path acceleration the joints allow; movel returns "stopped",
// and a trigger it did not reach does not fire. Unknown names are errors at the line.
TEST_F(BlendTest, StopHaltsAnotherProgramsMoveOnItsPathWithinTheJointLimits) {
  auto r = Make(
      {{"pa10", std::string(kCorner) + "local far = frame(a.pos + vec3(-0.30, 0, 0), a.rot)\n"
                                       "local late = false\n"
                                       "print(movel(far, {at = {{d = 0.25, call = function() late = true end}}}))\n"
                                       "print(late)\n"},
       {"", "wait(0.5)\nstop('pa10')\nprint(select(2, pcall(stop, 'pa11')))\nprint(select(2, pcall(stop)))\n"}});
  ASSERT_TRUE(RunFor(*r, 3000)) << r->error();
  ASSERT_EQ(printed_.size(), 4u);
  EXPECT_NE(printed_[0].find("main.lua:3: stop: no robot named 'pa11' (robots: 'pa10')"), std::string::npos)
      << printed_[0];
  EXPECT_NE(printed_[1].find("main.lua:4: stop: this program has no robot"), std::string::npos) << printed_[1];
  EXPECT_NE(printed_[2].find(": stopped"), std::string::npos) << printed_[2];
  EXPECT_NE(printed_[3].find(": false"), std::string::npos) << printed_[3];
  // the commands: on the line from the start along -x, joint accelerations within the limits
  const std::vector<Eigen::VectorXd>& q = arm_->history();
  const std::vector<Eigen::Vector3d> path = ToolPath();
  ASSERT_GT(q.size(), 260u);
  const JointRateLimits limits = DefaultRateLimits(7);
  double worst = 0, off_line = 0;
  for (std::size_t i = 2; i < q.size(); ++i) {
    const Eigen::VectorXd acc = (q[i] - 2 * q[i - 1] + q[i - 2]) / (kPeriod * kPeriod);
    for (int j = 0; j < 7; ++j) worst = std::max(worst, std::abs(acc[j]) / limits.a_rps2[j]);
  }
  for (const Eigen::Vector3d& p : path) {
    off_line = std::max(off_line, std::hypot(p.y() - path.front().y(), p.z() - path.front().z()));
  }
  EXPECT_LE(worst, 1.0 + 1e-9);
  EXPECT_LT(off_line, 1e-6);
  // halted: where it stopped it stays, short of the 0.25 m the trigger wanted
  std::size_t moving = 0;
  for (std::size_t i = 1; i < path.size(); ++i) {
    if ((path[i] - path[i - 1]).norm() > 1e-12) moving = i;
  }
  const double travelled = (path[moving] - path.front()).norm();
  EXPECT_LT(travelled, 0.25);
  EXPECT_GT(travelled, 0.03);  // it ran 0.5 s, of which 0.2 s speeding up: 0.04 m
  std::printf("stop: worst acceleration %.3f of its limit, halted %.1f ms after the request, at %.4f m\n", worst,
              (moving * kPeriod - 0.5) * 1e3, travelled);
}

// asynchronous moves (option async): the call returns a handle at once, the program runs on
// while the arm moves (m:done() polls, wait(m) or m:wait() gives the outcome), an asynchronous
// move's triggers fire at the program's other waits (here waiting for the trigger's own
// signal), and a next move lets the running one end first.
TEST_F(BlendTest, AsynchronousMovesRunWhileTheProgramGoesOn) {
  auto r =
      Make({{"pa10", std::string(kCorner) + "local m = movel(B, {async = true})\n"
                                            "local periods = 0\n"
                                            "while not m:done() do periods = periods + 1; sync() end\n"
                                            "print(periods, m:wait(), wait(m))\n"
                                            "local m2 = movel(C, {async = true, at = {{d = 0.05, signal = 'mid'}}})\n"
                                            "wait_signal('mid')\n"
                                            "print(string.format('%.4f', (planned().pos - B.pos):norm()), m2:done())\n"
                                            "print(wait(m2), (planned().pos - C.pos):norm() < 1e-9)\n"
                                            "movel(B, {async = true})\n"
                                            "print(movel(C), (planned().pos - C.pos):norm() < 1e-9)\n"
                                            "print(select(2, pcall(movel, B, {async = 1})))\n"
                                            "print(select(2, pcall(wait, m, 1)))\n"}});
  ASSERT_TRUE(RunFor(*r, 4000)) << r->error();
  ASSERT_EQ(printed_.size(), 6u);
  // 0.10 m at 0.1 m/s, 0.5 m/s^2: 1.2 s = 600 periods, the program polled through them
  EXPECT_NE(printed_[0].find(": 600\tdone\tdone"), std::string::npos) << printed_[0];
  // the trigger fired at 0.05 m along (within one period's 0.2 mm), the move still running
  EXPECT_NE(printed_[1].find(": 0.050"), std::string::npos) << printed_[1];
  EXPECT_NE(printed_[1].find("\tfalse"), std::string::npos) << printed_[1];
  EXPECT_NE(printed_[2].find(": done\ttrue"), std::string::npos) << printed_[2];
  EXPECT_NE(printed_[3].find(": done\ttrue"), std::string::npos) << printed_[3];
  EXPECT_NE(printed_[4].find("pa10.lua:14: movel: option async must be true or false, got number"), std::string::npos)
      << printed_[4];
  EXPECT_NE(printed_[5].find("wait: a move takes no timeout"), std::string::npos) << printed_[5];
}

}  // namespace
}  // namespace vlab::task
