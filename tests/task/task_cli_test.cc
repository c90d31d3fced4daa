// The task language end to end, through the built executables: the same
// script (scenes/tasks/hello.lua) in process, under vlab run as an external
// controller and against vlab-kinsim; byte-identical logs from two runs;
// a guarded move stopping at the table; syntax and runtime errors; print()
// output kept in task.log (silenced on stdout by -q) and vlab task's --log; a
// script error ending vlab task at once even with --hold; program_ended failing
// for a program that died in its first period.
#include <gtest/gtest.h>

#include "../kinsim/kinsim_process.h"
#include "bridge/bridge_client.h"
#include "test_util.h"

namespace vlab::testing {
namespace {

TEST(TaskCli, HelloRunsInProcess) {
  TempDir out;
  const ProcessResult r = RunVlab("run scenes/pa10_task_hello --out '" + out.path() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("pass  came_back"), std::string::npos) << r.out;
}

TEST(TaskCli, HelloRunsAsAnExternalControllerWithTheSameMotion) {
  TempDir in, ex;
  ASSERT_EQ(RunVlab("run scenes/pa10_task_hello --out '" + in.path() + "'").exit_code, 0);
  const ProcessResult r = RunVlab("run scenes/pa10_task_hello_external --out '" + ex.path() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(ReadFile(ex / "controller.log").find("vlab task: "), std::string::npos);
  // lockstep is exact: a second run over UDP writes the same log, byte for byte
  TempDir ex2;
  ASSERT_EQ(RunVlab("run scenes/pa10_task_hello_external --out '" + ex2.path() + "'").exit_code, 0);
  EXPECT_EQ(ReadFile(ex / "log.csv"), ReadFile(ex2 / "log.csv"));
  // lockstep over UDP gives the arm the same commands as in process: the same joint columns
  const std::vector<std::string> a = Lines(ReadFile(in / "log.csv")), b = Lines(ReadFile(ex / "log.csv"));
  ASSERT_EQ(a.size(), b.size());
  const std::vector<std::string> header = SplitCsv(a[0]);
  for (std::size_t row = 1; row < a.size(); ++row) {
    const std::vector<std::string> x = SplitCsv(a[row]), y = SplitCsv(b[row]);
    for (std::size_t c = 0; c < header.size(); ++c) {
      if (header[c].rfind("pa10.q.", 0) == 0) {
        ASSERT_EQ(x[c], y[c]) << header[c] << " row " << row;
      }
    }
  }
}

// the arm's joint speed limits (max_velocity) reach the task runtime over UDP too, through the
// describe reply's limits.velocity_max: at 0.7 rad/s (1.08 unlimited) the hello task is slowed alike in process
// and as an external controller (the same joint columns), and no joint exceeds the limit
TEST(TaskCli, ArmSpeedLimitsReachTheRuntimeOverUdp) {
  const std::string slow = " --set 'devices.pa10.max_velocity=[0.7, 0.7, 0.7, 0.7, 0.7, 0.7, 0.7]'";
  TempDir in, ex;
  ASSERT_EQ(RunVlab("run scenes/pa10_task_hello --out '" + in.path() + "'" + slow).exit_code, 0);
  const ProcessResult r = RunVlab("run scenes/pa10_task_hello_external --out '" + ex.path() + "'" + slow);
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const std::vector<std::string> a = Lines(ReadFile(in / "log.csv")), b = Lines(ReadFile(ex / "log.csv"));
  ASSERT_EQ(a.size(), b.size());
  const std::vector<std::string> header = SplitCsv(a[0]);
  double fastest = 0;
  std::vector<double> before;
  for (std::size_t row = 1; row < b.size(); ++row) {
    const std::vector<std::string> x = SplitCsv(a[row]), y = SplitCsv(b[row]);
    std::vector<double> q;
    for (std::size_t c = 0; c < header.size(); ++c) {
      if (header[c].rfind("pa10.q.", 0) != 0) continue;
      ASSERT_EQ(x[c], y[c]) << header[c] << " row " << row;
      q.push_back(std::stod(y[c]));
    }
    // the servo follows the slowed reference: its joints move at most a little faster (lag)
    for (std::size_t j = 0; !before.empty() && j < q.size(); ++j) {
      fastest = std::max(fastest, std::abs(q[j] - before[j]) / 0.002);
    }
    before = q;
  }
  EXPECT_LT(fastest, 0.7 * 1.05) << "a joint moved at " << fastest << " rad/s";
  EXPECT_GT(fastest, 0.7 * 0.9) << "the move never reached the limit: the test shows nothing";
}

TEST(TaskCli, HelloRunsAgainstKinsim) {
  KinsimProcess kinsim({"--scene", "scenes/pa10.xml"});
  ASSERT_TRUE(kinsim.ok()) << kinsim.start_line();
  const ProcessResult r = RunVlab("task scenes/tasks/hello.lua --arm 127.0.0.1:" + std::to_string(kinsim.port()) +
                                      " --scene scenes/pa10.xml --tip tool",
                                  60);
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("ended after"), std::string::npos) << r.out;
  kinsim.Stop();
}

// a program's parameters: a scenario's `params` and vlab task's --param give the script the
// same PARAMS, typed from their text; a bad name is exit 2 naming where it came from
TEST(TaskCli, ParamsReachTheScriptInProcessAndStandalone) {
  // printed in name order (pairs is sorted), each line after its "[ROBOT t=...] " prefix
  const auto typed = [](const std::string& out) {
    std::string lines;
    for (const char* name : {"letters", "pitch", "verify", "word"}) {
      const std::size_t at = out.find(std::string("] param\t") + name + "\t");
      if (at == std::string::npos) return std::string("no line for ") + name;
      lines += out.substr(at + 2, out.find('\n', at) - at - 2) + "\n";
    }
    return lines;
  };
  const std::string expected =
      "param\tletters\tinteger\t4\nparam\tpitch\tfloat\t0."
      "07\nparam\tverify\tboolean\ttrue\nparam\tword\tstring\tFACE\n";
  TempDir out;
  const ProcessResult in = RunVlab("run tests/data/task/params.yaml --out '" + out.path() + "/run'");
  EXPECT_EQ(in.exit_code, 0) << in.out << in.err;
  EXPECT_EQ(typed(in.out), expected) << in.out;
  EXPECT_LT(in.out.find("] param\tletters"), in.out.find("] param\tword"));

  KinsimProcess kinsim({"--scene", "scenes/pa10.xml"});
  ASSERT_TRUE(kinsim.ok()) << kinsim.start_line();
  const std::string task = "task tests/data/task/params.lua --arm 127.0.0.1:" + std::to_string(kinsim.port()) +
                           " --scene scenes/pa10.xml --tip tool";
  const ProcessResult alone =
      RunVlab(task + " --param word=FACE --param letters=4 --param pitch=0.07 --param verify=true", 60);
  EXPECT_EQ(alone.exit_code, 0) << alone.out << alone.err;
  EXPECT_EQ(typed(alone.out), expected) << alone.out;
  const ProcessResult bad = RunVlab(task + " --param 2word=FACE", 60);
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--param '2word=FACE': parameter '2word'"), std::string::npos) << bad.err;
  kinsim.Stop();
}

// payload(): in process and over UDP (vlab-kinsim) the script sets and reads the same payload
// and gets the same errors for bad arguments; refused by the arm (another client owns it), it
// is a script error with the device's reason
TEST(TaskCli, PayloadIsSetInProcessAndOverUdp) {
  const auto lines = [](const std::string& out) {
    std::string found;
    for (const std::string& line : Lines(out)) {
      const std::size_t at = line.find("] payload");
      if (at != std::string::npos) found += line.substr(at + 2) + "\n";
    }
    return found;
  };
  TempDir out;
  const ProcessResult in = RunVlab("run tests/data/task/payload.yaml --out '" + out.path() + "/run'");
  EXPECT_EQ(in.exit_code, 0) << in.out << in.err;
  const std::string got = lines(in.out);
  EXPECT_NE(got.find("payload before\t0.0\t3\t6\n"), std::string::npos) << got;
  EXPECT_NE(got.find("payload after\t1.25\t0.1\t0.01\t0.005\t0.0\n"), std::string::npos) << got;
  for (const char* error : {"payload: argument 1 (mass) must be a finite number >= 0 kg, got -1",
                            "payload: argument 1 (mass) must be a number (kg), got string",
                            "payload: com must be {x, y, z} (m, flange frame), got 2 numbers",
                            "payload: inertia principal moments break the triangle inequality",
                            "payload: unknown option 'mass' (com, inertia)"}) {
    EXPECT_NE(got.find(error), std::string::npos) << error << "\n" << got;
  }

  KinsimProcess kinsim({"--scene", "scenes/pa10.xml"});
  ASSERT_TRUE(kinsim.ok()) << kinsim.start_line();
  const std::string arm = " --arm 127.0.0.1:" + std::to_string(kinsim.port()) + " --scene scenes/pa10.xml --tip tool";
  const ProcessResult udp = RunVlab("task tests/data/task/payload.lua" + arm, 60);
  EXPECT_EQ(udp.exit_code, 0) << udp.out << udp.err;
  EXPECT_EQ(lines(udp.out), got);  // the same lines, word for word
  kinsim.Stop();
  EXPECT_NE(kinsim.output().find("payloads 1"), std::string::npos) << kinsim.output();

  // another client owns the arm (for 30 s of silence): the script's payload is refused
  KinsimProcess owned({"--scene", "scenes/pa10.xml", "--owner-timeout", "30"});
  ASSERT_TRUE(owned.ok()) << owned.start_line();
  bridge::Arm owner = bridge::Arm::Connect("127.0.0.1", owned.port(), 5.0);
  owner.SetPayload(bridge::ArmPayloadMsg{}, 5.0);
  const ProcessResult refused =
      RunVlab("task tests/data/task/payload.lua --arm 127.0.0.1:" + std::to_string(owned.port()) +
                  " --scene scenes/pa10.xml --tip tool",
              60);
  EXPECT_EQ(refused.exit_code, 1) << refused.out << refused.err;
  EXPECT_NE(refused.err.find("payload.lua:6: payload: arm 'pa10' at 127.0.0.1:" + std::to_string(owned.port()) +
                             ": the device refused the payload (another client owns the arm"),
            std::string::npos)
      << refused.err;
  owned.Stop();
}

// same scenario and seed, fast mode: the same bytes, although the script walks a
// string-keyed table with pairs() and pauses for math.random() seconds
TEST(TaskCli, TwoRunsGiveByteIdenticalLogs) {
  TempDir a, b;
  ASSERT_EQ(RunVlab("run tests/data/task/determinism.yaml --out '" + a.path() + "'").exit_code, 0);
  ASSERT_EQ(RunVlab("run tests/data/task/determinism.yaml --out '" + b.path() + "'").exit_code, 0);
  const std::string la = ReadFile(a / "log.csv");
  EXPECT_GT(Lines(la).size(), 1000u);
  EXPECT_EQ(la, ReadFile(b / "log.csv"));
  // another seed pauses differently: the log changes (the test can tell runs apart)
  TempDir c;
  ASSERT_EQ(RunVlab("run tests/data/task/determinism.yaml --seed 12 --out '" + c.path() + "'").exit_code, 0);
  EXPECT_NE(la, ReadFile(c / "log.csv"));
}

// the scenario's checks say it: the tip ends within 2 mm of the table's surface
TEST(TaskCli, GuardedMoveStopsAtTheTable) {
  TempDir out;
  const ProcessResult r = RunVlab("run tests/data/task/guarded.yaml --out '" + out.path() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("contact\tstopped"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("pass  stopped_at_the_table"), std::string::npos) << r.out;
}

// docs/tasks.md's tutorial, steps 1-6, with the gripper (scenes/pa10_gripper.xml): the
// scenario's checks say the cube ends within 2 mm of the place frame, turned by 90 degrees
TEST(TaskCli, TutorialWithTheGripperPicksAndPlacesTheCube) {
  TempDir out;
  const ProcessResult r = RunVlab("run tests/data/task/tutorial_gripper.yaml --out '" + out.path() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("touched at"), std::string::npos) << r.out;  // step 4 felt the table
  for (const char* check : {"placed_x", "placed_y", "placed_z", "turned_90_deg"}) {
    EXPECT_NE(r.out.find(std::string("pass  ") + check), std::string::npos) << r.out;
  }
}

// docs/tasks.md's tutorial, steps 1-4, as written there
TEST(TaskCli, TutorialStepsRun) {
  TempDir out;
  const ProcessResult r = RunVlab("run tests/data/task/tutorial.yaml --out '" + out.path() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("touched at\tvec3(0.6"), std::string::npos) << r.out;
}

TEST(TaskCli, SyntaxErrorIsExit2BeforeAnythingRuns) {
  TempDir out;
  const ProcessResult r = RunVlab("run tests/data/task/syntax_error.yaml --out '" + out.path() + "/run'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("tests/data/task/syntax_error.lua:4: ')' expected"), std::string::npos) << r.err;
  EXPECT_EQ(r.out.find("never runs"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(out / "run"));  // nothing written
}

// vlab task compiles the script before it contacts a device (none listens on port 9 here)
TEST(TaskCli, VlabTaskSyntaxErrorIsExit2BeforeConnecting) {
  const ProcessResult r =
      RunVlab("task tests/data/task/syntax_error.lua --arm 127.0.0.1:9 --scene scenes/pa10.xml --tip tool", 30);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("tests/data/task/syntax_error.lua:4: ')' expected"), std::string::npos) << r.err;
}

TEST(TaskCli, RuntimeErrorIsExit1WithTracebackAndTheLogKept) {
  TempDir out;
  const ProcessResult r = RunVlab("run tests/data/task/runtime_error.yaml --out '" + out.path() + "'");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("runtime_error.lua:5: frame *: argument 2 must be a frame, got nil"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("runtime_error.lua:7: in main chunk"), std::string::npos) << r.err;
  // the log up to the failing period: 0.5 s of 2 ms periods, and row 0
  EXPECT_EQ(Lines(ReadFile(out / "log.csv")).size(), 1u + 251u);
}

// where print() output and a script error go: task.log, -q, --log, --hold, program_ended
#define EXPECT_HAS(text, part) EXPECT_NE((text).find(part), std::string::npos) << (text)

TEST(TaskCli, PrintLinesAreKeptInTaskLogAndQuietSilencesThem) {
  TempDir out, quiet;
  const ProcessResult r = RunVlab("run scenes/pa10_task_hello --out '" + out.path() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_HAS(r.out, "[pa10 t=0.000] start\tframe(");
  const std::string log = ReadFile(out / "task.log");
  EXPECT_EQ(log.rfind("[pa10 t=0.000] start\tframe(", 0), 0u) << log;
  EXPECT_HAS(log, "] back\tframe(");
  const ProcessResult q = RunVlab("run scenes/pa10_task_hello -q --out '" + quiet.path() + "'");
  ASSERT_EQ(q.exit_code, 0) << q.out << q.err;
  EXPECT_EQ(q.out.find("[pa10 t="), std::string::npos) << q.out;
  EXPECT_EQ(ReadFile(quiet / "task.log"), log);  // the same lines, kept with the run
}

TEST(TaskCli, AProgramThatDiesInItsFirstPeriodFailsTheRunAndProgramEnded) {
  TempDir out;
  const ProcessResult r = RunVlab("run tests/task/died_at_start.yaml --out '" + out.path() + "'");
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_HAS(r.out, "FAIL  program_ended");
  EXPECT_HAS(r.err, "died_at_start.lua:4: movej: option 'w' is not supported");
  const std::string log = ReadFile(out / "task.log");
  EXPECT_HAS(log, "[pa10 t=0.000] starting\n");
  EXPECT_HAS(log, "[error t=0.000] ");
  EXPECT_HAS(log, "died_at_start.lua:4: movej: option 'w' is not supported");
}

TEST(TaskCli, AScriptErrorEndsVlabTaskAtOnceEvenWithHold) {
  KinsimProcess kinsim({"--scene", "scenes/pa10.xml"});
  ASSERT_TRUE(kinsim.ok()) << kinsim.start_line();
  TempDir out;
  const ProcessResult r =
      RunVlab("task tests/task/died_at_start.lua --hold -q --log '" + out.path() +
                  "/task.log' --arm 127.0.0.1:" + std::to_string(kinsim.port()) + " --scene scenes/pa10.xml --tip tool",
              30);
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_HAS(r.err, "died_at_start.lua:4: movej: option 'w' is not supported");
  EXPECT_EQ(r.out.find("starting"), std::string::npos) << r.out;  // -q
  const std::string log = ReadFile(out / "task.log");
  EXPECT_EQ(log.rfind("[pa10 t=0.000] starting\n", 0), 0u) << log;
  EXPECT_HAS(log, "[error t=0.000] tests/task/died_at_start.lua:4: movej: option 'w'");
  kinsim.Stop();
}

}  // namespace
}  // namespace vlab::testing
