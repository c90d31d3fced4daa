// fk, ik and reachable from a script (task_api.cc) on the fake PA10 of the
// runtime fixture: their values and errors at the script's line, and no motion
// (every command the arm gets is the pose it started at).
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "task_runtime_fixture.h"

namespace vlab::task {
namespace {

TEST_F(RuntimeTest, KinematicsQueriesDoNotMoveTheRobot) {
  auto r = Make({{"pa10",
                  "local f = fk(joints())\n"
                  "print((f.pos - pose().pos):norm() < 1e-9, f.rot:angle(pose().rot) < 1e-9)\n"
                  "local q = ik(f * trans(0, 0.05, 0))\n"
                  "print(#q, (fk(q).pos - (f * trans(0, 0.05, 0)).pos):norm() < 1e-9)\n"
                  "local all = ik(f, {all = true, seed = {0, 30, 10, 60, 0, 90, 0}})\n"
                  "print(#all >= 1, string.format('%.6f', all[1][3]), reachable(f), reachable(frame(2, 0, 0.3) * "
                  "rpy(180, 0, 0)))\n"
                  "print(select(2, pcall(fk, {0, 30, 0, 150, 0, 90, 0})))\n"
                  "print(select(2, pcall(ik, f, {v = 1})))\n"
                  "print(select(2, pcall(ik, frame(1e308, 0, 0) * trans(1e308, 0, 0))))\n"
                  "print(select(2, pcall(ik, frame(2, 0, 0.3))))\n"
                  "print(select(2, pcall(reachable, f, {all = true})))\n"
                  "sync()\n"}});
  ASSERT_TRUE(RunFor(*r, 10)) << r->error();
  ASSERT_EQ(printed_.size(), 8u);
  EXPECT_EQ(printed_[0], "pa10@0: true\ttrue");
  EXPECT_EQ(printed_[1], "pa10@0: 7\ttrue");
  EXPECT_EQ(printed_[2], "pa10@0: true\t10.000000\ttrue\tfalse");
  EXPECT_NE(printed_[3].find("pa10.lua:7: fk: joint E1 = 150 deg is beyond its upper limit 137 deg"), std::string::npos)
      << printed_[3];
  EXPECT_NE(printed_[4].find("pa10.lua:8: ik: option 'v' is not supported: it moves nothing"), std::string::npos)
      << printed_[4];
  EXPECT_NE(printed_[5].find("pa10.lua:9: ik: the target position (inf, 0, 0) m is not finite"), std::string::npos)
      << printed_[5];
  EXPECT_NE(printed_[6].find("pa10.lua:10: ik: out of reach: the wrist centre would be "), std::string::npos)
      << printed_[6];
  EXPECT_NE(printed_[7].find("pa10.lua:11: reachable: option 'all' is not supported"), std::string::npos)
      << printed_[7];
  // no motion: every command the arm got is the pose it started at
  Eigen::VectorXd ready(7);
  ready << 0, 0.523599, 0, 1.047198, 0, 1.570796, 0;
  for (const Eigen::VectorXd& q : arm_->history()) EXPECT_EQ(q, ready);
  EXPECT_EQ(arm_->q(), ready);
}

// option ref: the target of ik and reachable given in a user frame, fk's result given in it;
// the same joints and frames, to the bit, as composing with frame_of(name) in the script
TEST_F(RuntimeTest, KinematicsQueriesTakeAUserFrame) {
  auto r = Make({{"pa10",
                  "local here = pose()\n"
                  "frame_def('table', frame(here.pos) * trans(0.02, -0.03, -0.10) * rpy(0, 0, 30))\n"
                  "local T = trans(0.01, 0.02, 0.05) * rpy(180, 0, 10)\n"
                  "local a, b = ik(T, {ref = 'table'}), ik(frame_of('table') * T)\n"
                  "local same = true\n"
                  "for i = 1, 7 do same = same and a[i] == b[i] end\n"
                  "print(same, reachable(T, {ref = 'table'}), reachable(trans(2, 0, 0), {ref = 'table'}))\n"
                  "local f, g = fk(a, {ref = 'table'}), frame_of('table'):inv() * fk(a)\n"
                  "print(f.pos == g.pos, f.rot:angle(g.rot) == 0, (f.pos - T.pos):norm() < 1e-9)\n"
                  "local all = ik(T, {ref = 'table', all = true})\n"
                  "print(#all >= 1, (fk(all[1], {ref = 'table'}).pos - T.pos):norm() < 1e-9)\n"
                  "print(select(2, pcall(fk, a, {ref = 'bin'})))\n"
                  "print(select(2, pcall(ik, T, {ref = 3})))\n"
                  "print(select(2, pcall(fk, a, {seed = a})))\n"
                  "sync()\n"}});
  ASSERT_TRUE(RunFor(*r, 10)) << r->error();
  ASSERT_EQ(printed_.size(), 6u);
  EXPECT_EQ(printed_[0], "pa10@0: true\ttrue\tfalse");
  EXPECT_EQ(printed_[1], "pa10@0: true\ttrue\ttrue");
  EXPECT_EQ(printed_[2], "pa10@0: true\ttrue");
  EXPECT_NE(printed_[3].find("pa10.lua:12: fk: no user frame 'bin' (defined: 'table')"), std::string::npos)
      << printed_[3];
  EXPECT_NE(printed_[4].find("pa10.lua:13: ik: option ref must be the name of a user frame (frame_def), got number"),
            std::string::npos)
      << printed_[4];
  EXPECT_NE(printed_[5].find("pa10.lua:14: fk: unknown option 'seed' (options: ref)"), std::string::npos)
      << printed_[5];
}

}  // namespace
}  // namespace vlab::task
