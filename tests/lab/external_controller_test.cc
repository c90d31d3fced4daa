// Scenario controllers of type `external` (src/lab/run/lab_external.cc), through
// the real vlab binary: `vlab run` serves the devices on free loopback ports,
// starts the program with its placeholders expanded, runs lockstep and keeps
// the program's output in controller.log; the same scenario twice gives the same log bit for
// bit; a controller that fails ends the run at once with its exit status and
// last line (the output folder says why); one that ends the run (ends_run) ends it at the first
// period it left unanswered; SIGTERM on vlab run keeps every period that ran and
// stops the controller; the program inherits none of the lab's descriptors; a program that cannot
// run and an unknown placeholder are bad input (exit 2, nothing written). Placeholder expansion
// itself is checked directly.
#include <sched.h>
#include <signal.h>
#include <sys/stat.h>

#include <cerrno>
#include <filesystem>
#include <map>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/core_errors.h"
#include "lab/run/lab_external.h"
#include "test_run_output.h"
#include "test_util.h"

namespace vlab::testing::external_controller_test {
namespace {

// the PA10 served on port 50010 (vlab run binds a free port instead), a JR3
// served and never named, and a controller command
std::string Scenario(const std::string& command, double duration = 6.5) {
  return R"(
name: external
scene: )" VLAB_SOURCE_DIR R"(/scenes/pa10.xml
duration: )" +
         std::to_string(duration) + R"(
control_period: 0.002
seed: 5
clock: fast
lockstep: {timeout: 1.0, start_timeout: 600.0}
devices:
  - name: pa10
    kind: arm
    port: 50010
    joints: [S1, S2, S3, E1, E2, W1, W2]
    initial: [0, 0.523599, 0, 1.047198, 0, 1.570796, 0]
  - {name: jr3, kind: wrench, port: 50011, force_sensor: jr3_force, torque_sensor: jr3_torque}
controller:
  type: external
  command: )" +
         command + R"(
checks:
  - {name: joint_limits, signal: pa10.limit_violation, reduce: max, max: 0.0}
)";
}

TEST(ExternalController, RunStartsItAndTheLogIsTheSameTwice) {
  TempDir dir;
  // the controller ends at t = 6 s by itself (its output flushed), the arm holds for the rest
  WriteFile(dir / "s.yaml", Scenario(R"(["{bin}/examples/joint_control", "--arm", "{pa10}", "--duration", "6"])"));
  const ProcessResult a = RunVlab("run " + (dir / "s.yaml") + " -q --out " + (dir / "a"));
  ASSERT_EQ(a.exit_code, 0) << a.err << a.out;
  const ProcessResult b = RunVlab("run " + (dir / "s.yaml") + " -q --out " + (dir / "b"));
  ASSERT_EQ(b.exit_code, 0) << b.err << b.out;
  EXPECT_EQ(ReadFile(dir / "a/log.csv"), ReadFile(dir / "b/log.csv"));
  EXPECT_EQ(Lines(ReadFile(dir / "a/log.csv")).size(), 1u + 1u + 3250u);  // header, t = 0, 3250 periods

  const auto summary = nlohmann::json::parse(ReadFile(dir / "a/summary.json"));
  EXPECT_EQ(summary["clock"], "lockstep");  // fast becomes lockstep with an external controller
  EXPECT_EQ(summary["controller"]["type"], "external");
  EXPECT_NE(summary["controller"]["program"].get<std::string>().find("examples/joint_control"), std::string::npos);
  EXPECT_EQ(summary["controller"]["outcome"], "exit status 0");  // it ended by itself, before the run
  // every period until it ended was answered: the arm accepted one command per period
  long accepted = -1;
  for (const auto& d : summary["bridge"]["devices"]) {
    if (d["name"] == "pa10") accepted = d["accepted"];
    EXPECT_EQ(d["address"], "127.0.0.1");
    EXPECT_NE(d["port"], 50010);  // a free port, not the scenario's
  }
  EXPECT_GE(accepted, 3000);  // t = 0 .. 6 s at 500 Hz
  EXPECT_EQ(summary["clock_stats"]["timeouts"], 0);
  // the controller's own output is kept (joint_control prints its tracking error)
  EXPECT_NE(ReadFile(dir / "a/controller.log").find("max tracking error"), std::string::npos);
}

// lockstep: the lab waits for the answer to the state that closes the run before it stops
// the controller, so a controller that logs each state before it answers logs the final one
// on every run. This one takes 20 ms per state (Python dies on SIGTERM at once): stopped
// without that wait, its last row was the period before, or missing, whichever SIGTERM hit.
TEST(ExternalController, TheFinalStateIsAnsweredBeforeTheControllerIsStopped) {
  TempDir dir;
  WriteFile(dir / "slow.py", R"(import sys, time
sys.path.insert(0, ")" VLAB_SOURCE_DIR R"(/bridge/python")
import vlab_client
host, port = sys.argv[1].rsplit(":", 1)
with vlab_client.Arm(host, int(port), timeout=5.0) as arm, open(sys.argv[2], "w") as rows:
    while True:
        state = arm.read(5.0)
        time.sleep(0.02)
        rows.write("%.3f\n" % state.time)
        rows.flush()
        arm.write(vlab_client.HOLD, [], state.seq)
)");
  WriteFile(dir / "s.yaml",
            Scenario(R"(["python3", ")" + (dir / "slow.py") + R"(", "{pa10}", "{out}/rows.txt"])", 0.1));
  for (const char* run : {"a", "b"}) {
    const ProcessResult r = RunVlab("run " + (dir / "s.yaml") + " -q --out " + (dir / run));
    ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
    const std::vector<std::string> rows = Lines(ReadFile(dir / (std::string(run) + "/rows.txt")));
    ASSERT_EQ(rows.size(), 51u) << "t = 0 .. 0.1 s at 500 Hz: 51 states, each logged";
    EXPECT_EQ(rows.back(), "0.100");
  }
}

TEST(ExternalController, AFailingControllerEndsTheRunWithItsStatus) {
  TempDir dir;
  WriteFile(dir / "s.yaml", Scenario(R"(["sh", "-c", "echo cannot reach {pa10} >&2; exit 3"])"));
  // the start timeout is 600 s and RunVlab gives up after 60 s (exit 124): only
  // a lab that sees the program exit ends the run with exit 1
  const ProcessResult r = RunVlab("run " + (dir / "s.yaml") + " -q --out " + (dir / "out"), 60);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("controller 'sh' ended with exit status 3"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("cannot reach 127.0.0.1:"), std::string::npos) << r.err;
  // a failed run is written whole, with the controller's output and the reason
  EXPECT_NE(ReadFile(dir / "out/controller.log").find("cannot reach 127.0.0.1:"), std::string::npos);
  const auto summary = nlohmann::json::parse(ReadFile(dir / "out/summary.json"));
  EXPECT_EQ(summary["result"], "fail");
  EXPECT_EQ(summary["controller"]["outcome"], "exit status 3");
}

// controller.ends_run: the run ends at the first period the program left unanswered once it
// exited with status 0, the same period every run, however late the exit comes after it gave
// its devices up; the image output's `last` frame is of that state. Without it the devices
// hold to the run's duration; a non-zero exit still fails the run.
TEST(ExternalController, EndsRunEndsAtTheFirstPeriodItLeftUnanswered) {
  TempDir dir;
  // answers the states up to t = 0.05 s (seq 0..25), unsubscribes (the with block), then exits
  // after `linger` seconds with status `status`
  WriteFile(dir / "done.py", R"(import sys, time
sys.path.insert(0, ")" VLAB_SOURCE_DIR R"(/bridge/python")
import vlab_client
host, port = sys.argv[1].rsplit(":", 1)
with vlab_client.Arm(host, int(port), timeout=5.0) as arm:
    while True:
        state = arm.read(5.0)
        arm.write(vlab_client.HOLD, [], state.seq)
        if state.seq >= 25:
            break
time.sleep(float(sys.argv[2]))
sys.exit(int(sys.argv[3]))
)");
  const auto scenario = [&](const char* linger, const char* status, bool ends_run) {
    return Scenario(R"(["python3", ")" + (dir / "done.py") + R"(", "{pa10}", ")" + linger + R"(", ")" + status +
                        R"("])" + (ends_run ? "\n  ends_run: true" : ""),
                    0.1) +
           "outputs:\n  images:\n    - {camera: overview, every: 1.0, last: true, width: 64, height: 48}\n";
  };
  WriteFile(dir / "prompt.yaml", scenario("0", "0", true));
  WriteFile(dir / "late.yaml", scenario("0.5", "0", true));  // (a slow peer: the lab must wait for its exit)
  for (const std::string run : {"prompt", "late"}) {
    const std::string out = dir / run;
    const ProcessResult r = RunVlab("run " + out + ".yaml -q --out " + out);
    ASSERT_EQ(r.exit_code, 0) << run << ": " << r.err << r.out;
    // periods 0..25 answered and run; period 26 is the first it left unanswered
    const std::vector<std::string> rows = Lines(ReadFile(out + "/log.csv"));
    ASSERT_EQ(rows.size(), 1u + 1u + 26u) << run << ": header, t = 0, 26 periods";
    const double t_end = 26 * 0.002;  // (the lab's times are k T)
    EXPECT_EQ(std::stod(rows.back().substr(0, rows.back().find(','))), t_end) << run;
    const nlohmann::json summary = nlohmann::json::parse(ReadFile(out + "/summary.json"));
    EXPECT_EQ(summary["result"], "pass") << run;
    EXPECT_EQ(summary["controller"]["ended_run"], true) << run;
    EXPECT_EQ(summary["controller"]["outcome"], "exit status 0") << run;
    EXPECT_EQ(summary["timings"]["sim_time_s"].get<double>(), t_end) << run;
    const std::vector<std::string> frames = Lines(ReadFile(out + "/overview/frames.csv"));
    ASSERT_EQ(frames.size(), 3u) << run;
    EXPECT_EQ(frames[1], "0,0") << run;
    EXPECT_EQ(std::stod(frames[2].substr(2)), t_end) << run << ": " << frames[2];
  }
  EXPECT_EQ(ReadFile(dir / "prompt/log.csv"), ReadFile(dir / "late/log.csv"));

  // without ends_run the arm holds to the duration (0.1 s: 50 periods); `last` adds no frame
  // where the last state had one (every: 1 s falls on no period end but t = 0 here)
  WriteFile(dir / "holds.yaml", scenario("0", "0", false));
  const ProcessResult holds = RunVlab("run " + (dir / "holds.yaml") + " -q --out " + (dir / "holds"));
  ASSERT_EQ(holds.exit_code, 0) << holds.err << holds.out;
  EXPECT_EQ(Lines(ReadFile(dir / "holds/log.csv")).size(), 1u + 1u + 50u);
  const auto held = nlohmann::json::parse(ReadFile(dir / "holds/summary.json"));
  EXPECT_EQ(held["controller"]["ended_run"], false);
  EXPECT_EQ(ReadFile(dir / "holds/overview/frames.csv"), "frame,time\n0,0\n1,0.1\n");

  // a program that fails ends the run as a failure, ends_run or not
  WriteFile(dir / "fails.yaml", scenario("0", "3", true));
  const ProcessResult fails = RunVlab("run " + (dir / "fails.yaml") + " -q --out " + (dir / "fails"));
  EXPECT_EQ(fails.exit_code, 1) << fails.err;
  EXPECT_NE(fails.err.find("ended with exit status 3"), std::string::npos) << fails.err;
  const auto failed = nlohmann::json::parse(ReadFile(dir / "fails/summary.json"));
  EXPECT_EQ(failed["controller"]["ended_run"], false);
}

// {out}: what the program writes there moves into the output folder with the log
TEST(ExternalController, FilesWrittenIntoOutArriveWithTheLog) {
  TempDir dir;
  WriteFile(dir / "s.yaml", Scenario(R"(["sh", "-c", "echo from the controller > {out}/note.txt"])", 0.1));
  const ProcessResult r = RunVlab("run " + (dir / "s.yaml") + " -q --out " + (dir / "out"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(ReadFile(dir / "out/note.txt"), "from the controller\n");
  EXPECT_EQ(Entries(dir.path()), (std::set<std::string>{"s.yaml", "out"}));  // nothing left beside it
}

// a plot of a CSV the controller writes into {out}: drawn under vlab run; a controller that
// did not write it fails the run, with everything else written; under vlab serve (which
// starts no controller) the plot is skipped and said so
TEST(ExternalController, PlotsOfItsCsv) {
  TempDir dir;
  const std::string plot = "\noutputs:\n  plots:\n    - {file: c.png, csv: c.csv, x: t, y: [v]}\n";
  WriteFile(dir / "writes.yaml", Scenario(R"(["sh", "-c", "printf 't,v\\n0,1\\n1,2\\n' > {out}/c.csv"])", 0.1) + plot);
  ProcessResult r = RunVlab("run " + (dir / "writes.yaml") + " -q --out " + (dir / "a"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("plot: " + (dir / "a/c.png")), std::string::npos) << r.out;
  EXPECT_TRUE(std::filesystem::exists(dir / "a/c.png"));

  WriteFile(dir / "silent.yaml", Scenario(R"(["sh", "-c", "true"])", 0.1) + plot);
  r = RunVlab("run " + (dir / "silent.yaml") + " -q --out " + (dir / "b"));
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("c.csv"), std::string::npos) << r.err;
  const auto summary = nlohmann::json::parse(ReadFile(dir / "b/summary.json"));
  EXPECT_EQ(summary["result"], "fail");
  EXPECT_NE(summary["failure"].get<std::string>().find("c.png"), std::string::npos) << summary["failure"];
  EXPECT_TRUE(std::filesystem::exists(dir / "b/log.csv"));
  EXPECT_FALSE(std::filesystem::exists(dir / "b/c.png"));

  r = RunVlab("serve " + (dir / "silent.yaml") + " --ports auto --clock fast --out " + (dir / "c"));  // free ports
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("plot skipped: c.png: no c.csv"), std::string::npos) << r.out;
  EXPECT_EQ(nlohmann::json::parse(ReadFile(dir / "c/summary.json"))["plots_skipped"].size(), 1u);
  EXPECT_TRUE(std::filesystem::exists(dir / "c/log.csv"));
}

// a program that gets the end-of-run SIGTERM and exits with status 1 (its own
// verdict) fails the run; one the signal ends does not
TEST(ExternalController, ItsVerdictAfterTheEndOfTheRunCounts) {
  TempDir dir;
  // joint_control answers every period; the shell around it traps SIGTERM and says no
  WriteFile(
      dir / "fails.yaml",
      Scenario(
          R"(["sh", "-c", "trap 'echo my check failed; exit 1' TERM; {bin}/examples/joint_control --arm {pa10} --duration 100 & wait"])",
          0.1));
  ProcessResult r = RunVlab("run " + (dir / "fails.yaml") + " -q --out " + (dir / "a"));
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("ended with exit status 1"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("my check failed"), std::string::npos) << r.err;
  WriteFile(dir / "ends.yaml",
            Scenario(R"(["{bin}/examples/joint_control", "--arm", "{pa10}", "--duration", "100"])", 0.1));
  r = RunVlab("run " + (dir / "ends.yaml") + " -q --out " + (dir / "b"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

// examples/with_helper.sh (a second program beside the controller, as in the yo-yo stages 2
// and 3): the helper is ended with the controller; a helper that fails on its own fails the
// run once the controller is done; a controller the end-of-run SIGTERM ends does not
TEST(ExternalController, WithHelperEndsItsHelperAndReportsItsFailure) {
  TempDir dir;
  const std::string with = R"([")" VLAB_SOURCE_DIR R"(/examples/with_helper.sh", )";
  // the helper notes its end in {out}; the controller answers every period until SIGTERM. The
  // controller starts once the helper has set its trap (it opens a FIFO the helper writes after
  // the trap), so the end-of-run SIGTERM cannot reach the helper before its trap is set.
  const std::string ready = dir / "helper_ready";
  ASSERT_EQ(::mkfifo(ready.c_str(), 0600), 0) << ready;
  WriteFile(dir / "ends.yaml",
            Scenario(with + R"("sh", "-c", "trap 'echo helper ended > {out}/helper.txt; exit 0' TERM; echo > )" +
                         ready + R"(; sleep 100 & wait", "--", "sh", "-c", "read x < )" + ready +
                         R"(; exec {bin}/examples/joint_control --arm {pa10} --duration 100"])",
                     0.1));
  ProcessResult r = RunVlab("run " + (dir / "ends.yaml") + " -q --out " + (dir / "a"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(ReadFile(dir / "a/helper.txt"), "helper ended\n");
  // the helper fails at once; the controller is done (status 0) at the end of the run
  WriteFile(dir / "fails.yaml", Scenario(with + R"("sh", "-c", "exit 4", "--", "sh", "-c",
                     "trap 'exit 0' TERM; {bin}/examples/joint_control --arm {pa10} --duration 100 & wait"])",
                                         0.1));
  r = RunVlab("run " + (dir / "fails.yaml") + " -q --out " + (dir / "b"));
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("ended with exit status 4"), std::string::npos) << r.err;
  EXPECT_NE(ReadFile(dir / "b/controller.log").find("with_helper.sh: sh exited with status 4"), std::string::npos);
  // no `--`: the script's usage, exit 2, and the run fails with it
  WriteFile(dir / "usage.yaml", Scenario(with + R"("{bin}/examples/joint_control", "--arm", "{pa10}"])", 0.1));
  r = RunVlab("run " + (dir / "usage.yaml") + " -q --out " + (dir / "c"), 60);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("ended with exit status 2"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("usage: with_helper.sh"), std::string::npos) << r.err;
}

// SIGTERM on vlab run: the run stops at a period boundary and writes every period that ran,
// and the plots of what there is; the controller it started is stopped as at the end of a run,
// and reaped
TEST(ExternalController, SigtermKeepsTheRunAndStopsTheController) {
  TempDir dir;
  const std::string plots =
      "\noutputs:\n  plots:\n    - {file: q.png, y: [pa10.q.S1]}\n"
      "    - {file: c.png, csv: c.csv, x: t, y: [v]}\n";
  WriteFile(
      dir / "s.yaml",
      Scenario(
          R"(["sh", "-c", "echo $$ > {out}/controller.pid; exec {bin}/examples/joint_control --arm {pa10} --duration 100000 --quiet"])",
          100000) +
          plots);
  const ProcessResult r = RunVlab("run " + (dir / "s.yaml") + " -q --out " + (dir / "out"), 2, "TERM");
  ASSERT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("vlab: interrupted by SIGTERM at t = "), std::string::npos) << r.err;
  EXPECT_EQ(Entries(dir.path()), (std::set<std::string>{"s.yaml", "out"})) << "no staging folder";
  EXPECT_GT(ExpectInterruptedOutput(dir / "out", "SIGTERM", 0.002), 0);
  const auto summary = nlohmann::json::parse(ReadFile(dir / "out/summary.json"));
  EXPECT_EQ(summary["clock"], "lockstep");
  EXPECT_EQ(summary["controller"]["outcome"], "killed by signal 15");  // the lab's SIGTERM, not the test's
  // the log's plot is drawn; the plot of a CSV the controller never wrote is skipped, not a failure
  EXPECT_TRUE(std::filesystem::exists(dir / "out/q.png"));
  EXPECT_FALSE(std::filesystem::exists(dir / "out/c.png"));
  ASSERT_EQ(summary["plots_skipped"].size(), 1u) << summary["plots_skipped"];
  const std::string skipped = summary["plots_skipped"][0];
  EXPECT_EQ(skipped.rfind("c.png: ", 0), 0u) << skipped;
  EXPECT_NE(skipped.find("interrupted"), std::string::npos) << skipped;
  EXPECT_TRUE(std::filesystem::exists(dir / "out/controller.log"));
  const pid_t pid = std::stoi(ReadFile(dir / "out/controller.pid"));
  errno = 0;
  EXPECT_EQ(::kill(pid, 0), -1) << "the controller is gone";
  EXPECT_EQ(errno, ESRCH);
}

// the program gets /dev/null, its log and its end of the exit pipe: no socket of the served
// devices, no file of the output folder (log.csv, the images' video), nothing the lab inherited
TEST(ExternalController, GetsOnlyItsOwnDescriptors) {
  TempDir dir;
  // the shell's own descriptors and their targets, into controller.log (find runs beside it)
  const std::string images =
      "\noutputs:\n  images:\n    - {camera: overview, every: 0.05, width: 64, height: 48, "
      "profile: fast, video: o.mp4}\n";
  WriteFile(dir / "s.yaml",
            Scenario(R"(["sh", "-c", "find /proc/$$/fd -mindepth 1 -printf '%f %l\\n'; true"])", 0.1) + images);
  const ProcessResult r = RunVlab("run " + (dir / "s.yaml") + " -q --out " + (dir / "out"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string listing = ReadFile(dir / "out/controller.log");
  std::map<int, std::string> targets;
  for (const std::string& line : Lines(listing)) {
    const std::size_t space = line.find(' ');
    ASSERT_NE(space, std::string::npos) << listing;
    targets[std::stoi(line.substr(0, space))] = line.substr(space + 1);
  }
  ASSERT_EQ(targets.size(), 4u) << listing;
  EXPECT_EQ(targets[0], "/dev/null") << listing;
  const std::string log = targets[1];
  EXPECT_EQ(log.substr(log.size() - std::min<std::size_t>(log.size(), 15)), "/controller.log") << listing;
  EXPECT_EQ(targets[2], log) << listing;
  EXPECT_EQ(targets[3].rfind("pipe:", 0), 0u) << listing;
  EXPECT_EQ(listing.find("socket:"), std::string::npos) << listing;
  EXPECT_EQ(listing.find("log.csv"), std::string::npos) << listing;
  EXPECT_EQ(listing.find(".mp4"), std::string::npos) << listing;
}

// what the kernel allows this process, asked without the code under test
bool FifoPermitted() {
  bool permitted = false;
  std::thread probe([&] {
    sched_param p{};
    p.sched_priority = 1;
    permitted = ::sched_setscheduler(0, SCHED_FIFO, &p) == 0;  // this thread only
  });
  probe.join();
  return permitted;
}

TEST(ExternalController, RunsAtItsRealtimePriorityWhenPermittedAndTheRunRecordsIt) {
  TempDir dir;
  // the program prints its own rt_priority and policy (fields 40 and 41 of /proc/PID/stat)
  std::string text = Scenario(R"(["sh", "-c", "read -r s < /proc/$$/stat; set -- $s; shift 39; echo \"$1 $2\""])", 0.1);
  text.replace(text.find("  type: external\n"), 17, "  type: external\n  realtime_priority: 7\n");
  WriteFile(dir / "s.yaml", text + "realtime: {priority: 9}\n");
  const ProcessResult r = RunVlab("run " + (dir / "s.yaml") + " --out " + (dir / "out"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const bool permitted = FifoPermitted();
  // SCHED_FIFO is policy 1
  EXPECT_EQ(Lines(ReadFile(dir / "out/controller.log")).at(0), permitted ? "7 1" : "0 0");
  const nlohmann::json rt = nlohmann::json::parse(ReadFile(dir / "out/summary.json"))["realtime_priority"];
  EXPECT_EQ(rt["controller"]["requested"], 7);
  EXPECT_EQ(rt["controller"]["granted"], permitted) << rt.dump();
  EXPECT_EQ(rt["lab"]["requested"], 9);
  EXPECT_EQ(rt["lab"]["granted"], permitted) << rt.dump();
  // printed once each, on stderr
  const std::string lab_line =
      permitted ? "vlab: realtime priority 9 granted (SCHED_FIFO" : "vlab: realtime priority 9 not granted: ";
  EXPECT_NE(r.err.find(lab_line), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(permitted ? "vlab: controller: realtime priority 7 granted"
                                 : "vlab: controller: realtime priority 7 not granted"),
            std::string::npos)
      << r.err;
  if (!permitted) {
    EXPECT_NE(rt["lab"]["reason"].get<std::string>().find("rtprio"), std::string::npos) << rt.dump();
  }

  // --rt-priority 0 overrides the scenario: the lab runs at normal priority, the controller still asks
  const ProcessResult off = RunVlab("run " + (dir / "s.yaml") + " -q --rt-priority 0 --out " + (dir / "off"));
  ASSERT_EQ(off.exit_code, 0) << off.err;
  const nlohmann::json rt_off = nlohmann::json::parse(ReadFile(dir / "off/summary.json"))["realtime_priority"];
  EXPECT_EQ(rt_off["lab"]["requested"], 0);
  EXPECT_EQ(rt_off["lab"]["granted"], false);
  EXPECT_EQ(off.err.find("realtime priority"), std::string::npos) << "-q prints nothing: " << off.err;
}

TEST(ExternalController, BadCommandsAreBadInput) {
  TempDir dir;
  WriteFile(dir / "missing.yaml", Scenario(R"(["{bin}/examples/no_such_controller", "--arm", "{pa10}"])"));
  ProcessResult r = RunVlab("run " + (dir / "missing.yaml") + " -q --out " + (dir / "out"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("cannot run '"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("no_such_controller': No such file or directory"), std::string::npos) << r.err;

  WriteFile(dir / "unknown.yaml", Scenario(R"(["{bin}/examples/joint_control", "--arm", "{nomad}"])"));
  r = RunVlab("run " + (dir / "unknown.yaml") + " -q --out " + (dir / "out"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("controller.command: unknown placeholder {nomad}"), std::string::npos) << r.err;

  WriteFile(dir / "empty.yaml", Scenario("[]"));
  r = RunVlab("run " + (dir / "empty.yaml") + " -q --out " + (dir / "out"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("controller.command"), std::string::npos) << r.err;

  // ends_run and an image output's last take true or false only
  const std::string command = R"(["{bin}/examples/joint_control", "--arm", "{pa10}"])";
  WriteFile(dir / "ends.yaml", Scenario(command + "\n  ends_run: maybe"));
  r = RunVlab("run " + (dir / "ends.yaml") + " -q --out " + (dir / "out"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("controller.ends_run: expected true or false, got 'maybe'"), std::string::npos) << r.err;
  WriteFile(dir / "last.yaml",
            Scenario(command) + "outputs:\n  images:\n    - {camera: overview, every: 1.0, last: 2}\n");
  r = RunVlab("run " + (dir / "last.yaml") + " -q --out " + (dir / "out"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("outputs.images[0].last: expected true or false, got '2'"), std::string::npos) << r.err;
  EXPECT_EQ(Entries(dir.path()),
            (std::set<std::string>{"missing.yaml", "unknown.yaml", "empty.yaml", "ends.yaml", "last.yaml"}));
}

TEST(ExpandCommand, PlaceholdersAnywhereInAnArgument) {
  const std::map<std::string, std::string> values = {{"pa10", "127.0.0.1:4000"}, {"bin", "/opt/vlab"}};
  EXPECT_EQ(lab::ExpandCommand({"{bin}/x", "--arm={pa10}", "{pa10}{pa10}", "plain"}, values, "s.yaml:3"),
            (std::vector<std::string>{"/opt/vlab/x", "--arm=127.0.0.1:4000", "127.0.0.1:4000127.0.0.1:4000", "plain"}));
  try {
    lab::ExpandCommand({"{bin"}, values, "s.yaml:3");
    FAIL() << "an unclosed brace must be refused";
  } catch (const vlab::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("s.yaml:3: controller.command: '{bin': a '{' without its '}'"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace vlab::testing::external_controller_test
