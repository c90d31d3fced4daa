// vlab follow (src/cli/cli_follow.cc) end to end: the real vlab executable between two real
// vlab-kinsim processes on loopback, a test client of bridge/ commanding the source. The
// kinematic target lands exactly on a position command (src/kinsim/kinsim.h: "lands on it
// exactly"), so a copied position is checked for equality; only the wall-clock waits are loose.
#include <signal.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "bridge/bridge_client.h"
#include "kinsim/kinsim_process.h"
#include "test_process.h"
#include "test_util.h"

namespace vlab::cli {
namespace {

using bridge::Arm;
using bridge::ArmMode;
using testing::KinsimProcess;
using testing::RunCapture;
using testing::TestProcess;
using Clock = std::chrono::steady_clock;

const char* const kVlab = VLAB_BINARY_DIR "/vlab";
const char* const kReady = "0,0.523599,0,1.047198,0,1.570796,0";  // the PA10 ready pose, rad
const char* const kOther = "0.2,0.4,-0.1,1.2,0.1,1.3,0.3";        // within every joint's range

std::string Address(int port) { return "127.0.0.1:" + std::to_string(port); }

double Seconds(Clock::time_point since) { return std::chrono::duration<double>(Clock::now() - since).count(); }

// vlab follow from one kinsim to another, waiting for its start line
std::unique_ptr<TestProcess> StartFollow(int from, int to, std::vector<std::string> more = {}) {
  std::vector<std::string> args = {kVlab, "follow", "--from", Address(from), "--to", Address(to), "--connect-timeout",
                                   "5"};
  args.insert(args.end(), more.begin(), more.end());
  return std::make_unique<TestProcess>(args, 20);
}

// reads the arm's states until its own clock reaches `time` (s); false when it did not within
// 30 s of the wall (a guard against a hang: kinsim's clock runs at the wall's pace)
bool WaitForSourceTime(Arm& arm, double time) {
  Arm::State state;
  for (const Clock::time_point start = Clock::now(); Seconds(start) < 30;) {
    arm.ReadLatest(1.0, &state);
    if (state.time >= time) return true;
  }
  return false;
}

// The target ends exactly where the source was commanded to, and the follower owns the target
// while it never commands the source.
TEST(Follow, CopiesTheSourcePositionsToTheTarget) {
  KinsimProcess source({"--rate", "100"});
  KinsimProcess target({"--rate", "100", "--initial", kOther});
  ASSERT_TRUE(source.ok() && target.ok());
  // at rest error bound 1e-12 rad: after 1.5 s of rest the target (pi rad/s, < 1 rad to go)
  // has landed on the source's values, which pass through as doubles
  auto follow = StartFollow(source.port(), target.port(), {"--settle", "1.5", "--max-rest-error", "1e-12"});
  ASSERT_NE(follow->start_line().find("-> arm 'pa10'"), std::string::npos) << follow->start_line();

  // the test commands the source: it becomes the source's owner, so nobody else was
  Arm src = Arm::Connect("127.0.0.1", source.port(), 2.0);
  Eigen::VectorXd goal(7);
  goal << -0.3, 0.2, 0.25, 0.9, -0.2, 1.1, -0.4;
  Arm::State s;
  const Clock::time_point start = Clock::now();
  while (Seconds(start) < 1.5) {  // 1.5 s: every joint within 1 rad of its goal at pi rad/s
    src.ReadLatest(1.0, &s);
    src.Write(ArmMode::kPosition, goal, s.seq);
  }
  src.ReadLatest(1.0, &s);
  EXPECT_EQ(s.status & bridge::kStatusNotOwner, 0u);
  ASSERT_EQ(s.q, goal);

  // the target follows to the same values; another client cannot command it
  Arm other = Arm::Connect("127.0.0.1", target.port(), 2.0);
  Arm::State t;
  bool reached = false;
  for (const Clock::time_point wait = Clock::now(); !reached && Seconds(wait) < 5;) {
    other.ReadLatest(1.0, &t);
    other.Write(ArmMode::kHold, Eigen::VectorXd(), t.seq);
    reached = t.q == goal;
  }
  EXPECT_TRUE(reached) << "target at " << t.q.transpose() << ", source at " << goal.transpose();
  other.ReadLatest(1.0, &t);
  EXPECT_NE(t.status & bridge::kStatusNotOwner, 0u) << "another client's hold was taken: the follower is not the owner";
  EXPECT_EQ(t.q, goal) << "the hold of another client moved nothing";

  // keep the source at rest past --settle, then stop: the counters, exit 0 (bound held). The source
  // was at the goal at s.time at the latest: wait until its own clock is 1 s past the settling
  ASSERT_TRUE(WaitForSourceTime(src, s.time + 1.5 + 1.0));
  EXPECT_EQ(follow->Stop(), 0) << follow->output();
  EXPECT_NE(follow->output().find("tracking error max"), std::string::npos) << follow->output();
  EXPECT_NE(follow->output().find("0.000000 rad at rest"), std::string::npos) << follow->output();
}

// A target that cannot keep up fails the at-rest bound: exit 1 (the verdict can fail).
TEST(Follow, ExitsOneWhenTheTargetDoesNotReachTheSourceAtRest) {
  KinsimProcess source({"--rate", "100"});
  // 0.01 rad/s: 1.5 s of following closes 0.015 rad of the 0.7 rad between the poses
  KinsimProcess target({"--rate", "100", "--initial", kOther, "--max-velocity", "0.01"});
  ASSERT_TRUE(source.ok() && target.ok());
  auto follow = StartFollow(source.port(), target.port(), {"--settle", "0.2", "--max-rest-error", "0.001"});
  ASSERT_FALSE(follow->start_line().empty());
  // the source stands still from its start: wait until its own clock is 1 s past the settling
  Arm watch = Arm::Connect("127.0.0.1", source.port(), 2.0);  // a bystander: it only reads
  ASSERT_TRUE(WaitForSourceTime(watch, watch.ReadLatest(1.0).time + 0.2 + 1.0));
  EXPECT_EQ(follow->Stop(), 1) << follow->output();
  // the verdict failed on periods at rest, not for want of them
  const std::size_t at = follow->output().find(" rad at rest (");
  ASSERT_NE(at, std::string::npos) << follow->output();
  EXPECT_GT(std::stol(follow->output().substr(at + 14)), 0) << follow->output();
}

// Arms with other joints are refused with exit 2, naming both devices.
TEST(Follow, RefusesArmsWithOtherJoints) {
  KinsimProcess source({"--rate", "100"});
  KinsimProcess six({"--rate", "100", "--joints", "S1,S2,S3,E1,E2,W1", "--initial", "0,0,0,1,0,1"});
  KinsimProcess swapped({"--rate", "100", "--joints", "S1,S2,S3,E1,E2,W2,W1", "--initial", kReady});
  ASSERT_TRUE(source.ok() && six.ok() && swapped.ok());
  std::string out;
  EXPECT_EQ(RunCapture(std::string(kVlab) + " follow --from " + Address(source.port()) + " --to " + Address(six.port()),
                       &out),
            2);
  EXPECT_NE(out.find("arm 'pa10' at " + Address(source.port()) + " has 7 joints"), std::string::npos) << out;
  EXPECT_NE(out.find("arm 'pa10' at " + Address(six.port()) + " has 6"), std::string::npos) << out;
  out.clear();
  EXPECT_EQ(
      RunCapture(std::string(kVlab) + " follow --from " + Address(source.port()) + " --to " + Address(swapped.port()),
                 &out),
      2);
  EXPECT_NE(out.find("E2, W2, W1"), std::string::npos) << out;
  EXPECT_NE(out.find("same joints in the same order"), std::string::npos) << out;
}

// Bad options and an address where nothing answers: exit 2 with one line saying what.
TEST(Follow, RefusesBadOptions) {
  std::string out;
  EXPECT_EQ(RunCapture(std::string(kVlab) + " follow --from nowhere --to 127.0.0.1:1", &out), 2);
  EXPECT_NE(out.find("--from 'nowhere': expected HOST:PORT"), std::string::npos) << out;
  out.clear();
  EXPECT_EQ(RunCapture(std::string(kVlab) + " follow --from 127.0.0.1:1 --to 127.0.0.1:1 --timeout 0", &out), 2);
  EXPECT_NE(out.find("--timeout must be > 0"), std::string::npos) << out;
  out.clear();
  EXPECT_EQ(RunCapture(std::string(kVlab) + " follow --from 127.0.0.1:9 --to 127.0.0.1:9 --connect-timeout 0.3", &out),
            2);
  EXPECT_NE(out.find("--to 127.0.0.1:9: no arm answered within 0.3 s"), std::string::npos) << out;
}

// A source that goes silent ends the follower with exit 1 after --timeout.
TEST(Follow, ExitsOneWhenTheSourceFallsSilent) {
  auto source = std::make_unique<KinsimProcess>(std::vector<std::string>{"--rate", "100"});
  KinsimProcess target({"--rate", "100"});
  ASSERT_TRUE(source->ok() && target.ok());
  auto follow = StartFollow(source->port(), target.port(), {"--timeout", "0.5"});
  ASSERT_FALSE(follow->start_line().empty());
  source.reset();  // SIGKILL
  EXPECT_EQ(follow->Wait(10), 1) << follow->output();
}

}  // namespace
}  // namespace vlab::cli
