// The settings' getter forms, the planned pose (planned(), planned_joints()), named user
// frames (frame_def, frame_of, a move's ref option) and relative moves (movel_rel) from a
// script (task_api.cc) on the fake arms of the runtime fixture, and on an arm whose servo
// lags its command.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "task/task_motion.h"
#include "task_runtime_fixture.h"

namespace vlab::task {
namespace {

constexpr double kDegree = M_PI / 180.0;

// the number after "NAME=" in a printed line
double Field(const std::string& line, const std::string& name) {
  const auto at = line.find(name + "=");
  EXPECT_NE(at, std::string::npos) << name << " in " << line;
  return at == std::string::npos ? NAN : std::stod(line.substr(at + name.size() + 1));
}

// the Lua helpers of the scripts: largest position and rotation difference of two frames
const std::string kDiff =
    "local function dpos(a, b) return (a.pos - b.pos):norm() end\n"
    "local function drot(a, b)\n"
    "  local p, q = a.rot, b.rot\n"
    "  local s = (p.w * q.w + p.x * q.x + p.y * q.y + p.z * q.z) < 0 and -1 or 1\n"
    "  return math.max(math.abs(p.w - s * q.w), math.abs(p.x - s * q.x), math.abs(p.y - s * q.y),\n"
    "                  math.abs(p.z - s * q.z))\n"
    "end\n";

TEST_F(RuntimeTest, EachSettingsGetterGivesTheDefaultThenWhatWasSet) {
  auto r = Make({{"pa10",
                  "local f = '%.12g'\n"
                  "local function show(...) local t = {...} for i, v in ipairs(t) do t[i] = string.format(f, v) end "
                  "return table.concat(t, ' ') end\n"
                  "print(show(speed()), show(accel()), show(jspeed()), show(blend()), limits(), tool(), base())\n"
                  "speed(0.25, 90) accel(1.5, 270) jspeed(60, 120) blend(0.02) limits('refuse')\n"
                  "local t, b = trans(0, 0, 0.1) * rotz(90), frame(1, 0.5, 0) * rpy(0, 0, 45)\n"
                  "tool(t) base(b)\n"
                  "print(show(speed()), show(accel()), show(jspeed()), show(blend()), limits())\n"
                  "print(tool().pos == t.pos, tostring(tool()) == tostring(t), base().pos == b.pos,\n"
                  "      tostring(base()) == tostring(b))\n"
                  "speed(0.3) accel(2) jspeed(10)\n"  // the second value stays
                  "print(show(speed()), show(accel()), show(jspeed()))\n"
                  "speed(speed()) accel(accel()) jspeed(jspeed()) blend(blend()) limits(limits())\n"
                  "print(show(speed()), show(accel()), show(jspeed()), show(blend()), limits())\n"
                  "print(select(2, pcall(speed, nil)))\n"
                  "print(select(2, pcall(tool, 3)))\n"}});
  ASSERT_TRUE(RunFor(*r, 10)) << r->error();
  ASSERT_EQ(printed_.size(), 7u);
  // the defaults, in the setters' units (MotionLimits holds radians: 0.7854 rad/s is 45.0001 deg/s)
  const MotionLimits d;
  char defaults[256];
  std::snprintf(defaults, sizeof defaults, "pa10@0: %.12g %.12g\t%.12g %.12g\t%.12g %.12g\t0\tslow\t", d.speed_mps,
                d.rot_speed_rps / kDegree, d.accel_mps2, d.rot_accel_rps2 / kDegree, d.joint_speed_rps / kDegree,
                d.joint_accel_rps2 / kDegree);
  EXPECT_EQ(printed_[0].substr(0, std::strlen(defaults)), defaults) << printed_[0];
  const std::string identity = "frame(pos = (0, 0, 0) m, rpy = (0, 0, 0) deg)";
  EXPECT_EQ(printed_[0].substr(std::strlen(defaults)), identity + "\t" + identity);
  EXPECT_EQ(printed_[1], "pa10@0: 0.25 90\t1.5 270\t60 120\t0.02\trefuse");
  EXPECT_EQ(printed_[2], "pa10@0: true\ttrue\ttrue\ttrue");
  EXPECT_EQ(printed_[3], "pa10@0: 0.3 90\t2 270\t10 120");
  EXPECT_EQ(printed_[4], "pa10@0: 0.3 90\t2 270\t10 120\t0.02\trefuse");
  EXPECT_NE(printed_[5].find("pa10.lua:14: speed: argument 1 must be a number, got nil"), std::string::npos)
      << printed_[5];
  EXPECT_NE(printed_[6].find("pa10.lua:15: tool: argument 1 must be a frame, got number"), std::string::npos)
      << printed_[6];
}

TEST_F(RuntimeTest, PlannedIsTheTargetWhilePoseLagsBehindTheServo) {
  Eigen::VectorXd ready(7);
  ready << 0, 0.523599, 0, 1.047198, 0, 1.570796, 0;
  // a servo that lags: each period the joints go 5 % of the way to the command (a first-order
  // lag of 40 ms at 2 ms periods)
  FakeArm lagging("pa10", ready, 0.05);
  devices_.channels["pa10"] = &lagging;
  auto r = Make({{"pa10", kDiff + "print(string.format('start pos=%.3e rot=%.3e', dpos(planned(), pose()), "
                                  "drot(planned(), pose())))\n"
                                  "local T = planned() * trans(0.04, -0.02, 0.03) * rotx(10)\n"
                                  "movel(T, {v = 0.2})\n"
                                  "local q = planned_joints()\n"
                                  "print(string.format('end pos=%.3e rot=%.3e lag=%.3e', dpos(planned(), T), "
                                  "drot(planned(), T), dpos(pose(), T)))\n"
                                  "print(string.format('joints %.17g %.17g %.17g %.17g %.17g %.17g %.17g', "
                                  "table.unpack(q)))\n"
                                  "print(string.format('measured E1=%.17g', joints()[4]))\n"
                                  // built from planned(): ends on the intended frame; built from pose(): off by the lag
                                  "local D = trans(0, 0.03, 0)\n"
                                  "movel(planned() * D)\n"
                                  "print(string.format('chained pos=%.3e', dpos(planned(), T * D)))\n"
                                  "local aim = pose() * D\n"
                                  "print(string.format('from pose off=%.3e', dpos(aim, T * D * D)))\n"}});
  ASSERT_TRUE(RunFor(*r, 5000)) << r->error();
  ASSERT_EQ(printed_.size(), 6u);
  EXPECT_EQ(Field(printed_[0], "pos"), 0.0) << printed_[0];  // at rest: the planned pose is the measured one
  EXPECT_EQ(Field(printed_[0], "rot"), 0.0) << printed_[0];
  EXPECT_LT(Field(printed_[1], "pos"), 1e-12) << printed_[1];
  EXPECT_LT(Field(printed_[1], "rot"), 1e-12) << printed_[1];
  EXPECT_GT(Field(printed_[1], "lag"), 1e-4) << printed_[1];  // the servo is still on its way
  // planned_joints(): the last command, deg; joints(): where the lagging arm is
  std::vector<double> q;
  const std::string joints = printed_[2].substr(printed_[2].find("joints ") + 7);
  for (std::size_t at = 0; at < joints.size();) {
    std::size_t used = 0;
    q.push_back(std::stod(joints.substr(at), &used));
    at += used;
  }
  ASSERT_EQ(q.size(), 7u);
  // (printed in period N, before its command: the one of period N - 1)
  const int period = std::stoi(printed_[2].substr(printed_[2].find('@') + 1));
  ASSERT_GT(period, 0);
  const Eigen::VectorXd& command = lagging.commands().at(period - 1);
  for (int i = 0; i < 7; ++i) EXPECT_NEAR(q[i], command[i] / kDegree, 1e-12) << i;
  EXPECT_GT(std::abs(Field(printed_[3], "E1") - q[3]), 1e-3) << printed_[3];
  EXPECT_LT(Field(printed_[4], "pos"), 1e-12) << printed_[4];
  EXPECT_GT(Field(printed_[5], "off"), 1e-4) << printed_[5];
}

TEST_F(RuntimeTest, PlannedDuringABlendIsTheCurrentSample) {
  auto r = Make({{"pa10",
                  "local B = planned() * trans(0.10, 0, 0)\n"
                  "movel(B, {r = 0.02})\n"
                  "local d = (planned().pos - B.pos):norm()\n"
                  "print(d <= 0.02 + 1e-12, d > 0.015)\n"
                  "movel(B * trans(0, 0.05, 0))\n"}});
  ASSERT_TRUE(RunFor(*r, 5000)) << r->error();
  ASSERT_EQ(printed_.size(), 1u);
  EXPECT_EQ(printed_[0].substr(printed_[0].find(':')), ": true\ttrue") << printed_[0];
}

// a move given in a user frame and the same move given the composed frame: the same
// commands to the bit (arm pa10: ref; arm pa10b: the script composes)
TEST_F(RuntimeTest, MovesInAUserFrameEqualMovesToTheComposedFrame) {
  const std::string setup =
      "local P = planned()\n"
      "local U = frame(P.pos) * rotz(30) * trans(0.02, -0.01, 0)\n"
      "local T1 = frame(0.03, 0.02, -0.02, rotz(-30) * frame(P.rot)) * rotx(5)\n"
      "local T2 = frame(-0.02, 0.04, 0.01, rotz(-20) * frame(P.rot))\n"
      "local V, T3 = vec3(0.0, 0.07, 0.03), frame(-0.03, 0.05, 0, rotz(-30) * frame(P.rot))\n";
  auto r = Make({{"pa10", kDiff + setup +
                              "frame_def('table', U)\n"
                              "print(tostring(frame_of('table')) == tostring(U), frame_of('table').pos == U.pos)\n"
                              "movel(T1, {ref = 'table'})\n"
                              "print(string.format('movel pos=%.3e rot=%.3e', dpos(planned(), U * T1), "
                              "drot(planned(), U * T1)))\n"
                              "movej(T2, {ref = 'table'})\n"
                              "movec(V, T3, {ref = 'table', v = 0.05})\n"
                              "print(string.format('movec pos=%.3e', dpos(planned(), U * T3)))\n"},
                 {"pa10b", setup + "movel(U * T1)\n"
                                   "movej(U * T2)\n"
                                   "movec(U * V, U * T3, {v = 0.05})\n"}});
  ASSERT_TRUE(RunFor(*r, 10000)) << r->error();
  ASSERT_TRUE(r->finished());
  ASSERT_EQ(printed_.size(), 3u);
  EXPECT_EQ(printed_[0], "pa10@0: true\ttrue");
  EXPECT_LT(Field(printed_[1], "pos"), 1e-12) << printed_[1];
  EXPECT_LT(Field(printed_[1], "rot"), 1e-12) << printed_[1];
  EXPECT_LT(Field(printed_[2], "pos"), 1e-12) << printed_[2];
  ASSERT_EQ(arm_->history().size(), arm2_->history().size());
  EXPECT_GT(arm_->history().size(), 100u);
  for (std::size_t k = 0; k < arm_->history().size(); ++k) {
    ASSERT_EQ(arm_->history()[k], arm2_->history()[k]) << "period " << k;  // to the bit
  }
  EXPECT_GT((arm_->q() - arm_->history().front()).norm(), 0.01);  // (it did move)
}

// movel_rel(delta) is movel(planned() * delta); rel = "base" offsets along the base's axes;
// after a blended move it is relative to that move's target
TEST_F(RuntimeTest, RelativeMovesStartFromThePlannedPose) {
  auto r = Make(
      {{"pa10", kDiff + "local D = trans(0.02, 0.01, -0.01) * rotz(10)\n"
                        "movel_rel(D, {v = 0.05})\n"
                        "local P = planned()\n"
                        "movel_rel(trans(0, 0, 0.03) * rotx(5), {rel = 'base'})\n"
                        "local E = frame(P.pos + vec3(0, 0, 0.03), rotx(5) * frame(P.rot))\n"
                        "print(string.format('base pos=%.3e rot=%.3e', dpos(planned(), E), drot(planned(), E)))\n"
                        "local A = planned()\n"
                        "movel_rel(trans(0.06, 0, 0), {r = 0.01})\n"
                        "movel_rel(trans(0, 0.06, 0))\n"
                        "local C = A * trans(0.06, 0, 0) * trans(0, 0.06, 0)\n"
                        "print(string.format('blend pos=%.3e rot=%.3e', dpos(planned(), C), drot(planned(), C)))\n"},
       {"pa10b", "movel(planned() * trans(0.02, 0.01, -0.01) * rotz(10), {v = 0.05})\n"}});
  ASSERT_TRUE(RunFor(*r, 20000)) << r->error();
  ASSERT_TRUE(r->finished());
  ASSERT_EQ(printed_.size(), 2u);
  EXPECT_LT(Field(printed_[0], "pos"), 1e-12) << printed_[0];
  EXPECT_LT(Field(printed_[0], "rot"), 1e-12) << printed_[0];
  EXPECT_LT(Field(printed_[1], "pos"), 1e-12) << printed_[1];
  EXPECT_LT(Field(printed_[1], "rot"), 1e-12) << printed_[1];
  // the first relative move: the commands of movel(planned() * D), to the bit, up to the
  // period pa10b's move ends in (then pa10 goes on)
  const std::vector<Eigen::VectorXd>& b = arm2_->history();
  const std::size_t end = std::find(b.begin(), b.end(), b.back()) - b.begin();
  ASSERT_GT(end, 10u);
  for (std::size_t k = 0; k <= end; ++k) ASSERT_EQ(arm_->history()[k], b[k]) << "period " << k;
  EXPECT_NE(arm_->history()[end + 1], b[end + 1]);
}

TEST_F(RuntimeTest, UserFrameAndRelativeMoveErrorsNameTheProblem) {
  auto r = Make({{"pa10",
                  "local T = planned() * trans(0.01, 0, 0)\n"
                  "print(select(2, pcall(frame_of, 'table')))\n"
                  "frame_def('table', frame(0.5, 0, 0.3)) frame_def('bin', frame(0.3, 0.4, 0.2))\n"
                  "print(select(2, pcall(frame_of, 'tabel')))\n"
                  "print(select(2, pcall(movel, T, {ref = 'tabel'})))\n"
                  "print(select(2, pcall(movel, T, {ref = 3})))\n"
                  "print(select(2, pcall(movej, {0, 30, 0, 60, 0, 90, 0}, {ref = 'table'})))\n"
                  "print(select(2, pcall(movel_rel, T, {ref = 'table'})))\n"
                  "print(select(2, pcall(movel_rel, T, {rel = 'world'})))\n"
                  "print(select(2, pcall(movel, T, {rel = 'base'})))\n"
                  "print(select(2, pcall(frame_def, 3, T)))\n"
                  "print(select(2, pcall(frame_def, 'x', vec3(1, 2, 3))))\n"
                  "print(select(2, pcall(frame_def, 'x', frame(1e308, 0, 0) * trans(1e308, 0, 0))))\n"
                  "print(select(2, pcall(movel_rel, vec3(0, 0, 1))))\n"},
                 {"", "print(select(2, pcall(planned)))\nprint(select(2, pcall(planned_joints)))\n"}});
  ASSERT_TRUE(RunFor(*r, 10)) << r->error();
  const std::vector<std::string> want = {
      "pa10.lua:2: frame_of: no user frame 'table' (none is defined: frame_def(name, frame))",
      "pa10.lua:4: frame_of: no user frame 'tabel' (defined: 'bin', 'table')",
      "pa10.lua:5: movel: no user frame 'tabel' (defined: 'bin', 'table')",
      "pa10.lua:6: movel: option ref must be the name of a user frame (frame_def), got number",
      "pa10.lua:7: movej: option ref is for a target frame: joint angles (deg) have no frame",
      "pa10.lua:8: movel_rel: option 'ref' is not supported: movel_rel's delta is relative to the planned pose",
      "pa10.lua:9: movel_rel: option rel must be \"tool\" or \"base\", got world",
      "pa10.lua:10: movel: option 'rel' is not supported: movel's target is absolute",
      "pa10.lua:11: frame_def: argument 1 must be the frame's name (a non-empty string), got number",
      "pa10.lua:12: frame_def: argument 2 must be a frame, got userdata",
      "pa10.lua:13: frame_def: the frame's position (",
      "pa10.lua:14: movel_rel: argument 1 must be a frame, got userdata",
      "main.lua:1: planned: this program has no robot",
      "main.lua:2: planned_joints: this program has no robot",
  };
  ASSERT_EQ(printed_.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) EXPECT_NE(printed_[i].find(want[i]), std::string::npos) << printed_[i];
  for (const Eigen::VectorXd& q : arm_->history()) EXPECT_EQ(q, arm_->history().front());  // nothing moved
}

}  // namespace
}  // namespace vlab::task
