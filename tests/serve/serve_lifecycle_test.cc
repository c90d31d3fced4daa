// How a `vlab serve` run starts and ends, with real processes and signals:
// SIGINT during a lockstep run with examples/joint_control ends it with every
// period that ran written (more signals while it writes change nothing); a
// signal ends the wait for a controller and a paused run at once; a lockstep run
// in which no command ever arrived fails and says why, after saying on stderr
// whom it waits for.
#include <gtest/gtest.h>

#include <signal.h>

#include <chrono>
#include <string>

#include <nlohmann/json.hpp>

#include "bridge/bridge_client.h"
#include "serve/serve_process.h"
#include "test_process.h"
#include "test_run_output.h"
#include "test_util.h"
#include "wait_until.h"

namespace vlab::testing {
namespace {

std::string Port(int port) { return std::to_string(port); }

// the PA10 and the sim device in lockstep, with the given start timeout and duration
std::string LockstepScenario(double start_timeout_s, double duration_s) {
  return std::string("name: lifecycle\nscene: ") + VLAB_SOURCE_DIR + "/scenes/pa10.xml\n" +
         "duration: " + std::to_string(duration_s) + "\ncontrol_period: 0.002\nclock: lockstep\n" +
         "lockstep: {timeout: 1.0, start_timeout: " + std::to_string(start_timeout_s) +
         ", on_timeout: hold}\n"
         "devices:\n"
         "  - {name: pa10, kind: arm, port: 1, joints: [S1, S2, S3, E1, E2, W1, W2],\n"
         "     initial: [0, 0.523599, 0, 1.047198, 0, 1.570796, 0]}\n"
         "  - {name: sim, kind: sim, port: 1}\n"
         "checks:\n"
         "  - {name: joint_limits, signal: pa10.limit_violation, reduce: max, max: 0.0}\n";
}

TEST(ServeLifecycle, SigintKeepsEveryPeriodThatRan) {
  TempDir tmp;
  const int arm = FreeUdpPort(), jr3 = FreeUdpPort(), sim = FreeUdpPort();
  // a shipped lockstep scenario, far longer than the test
  ServeProcess serve("scenes/pa10_serve --duration 100000 --port pa10=" + Port(arm) + " --port jr3=" + Port(jr3) +
                         " --port sim=" + Port(sim) + " --out '" + (tmp / "out") + "'",
                     tmp.path());
  ASSERT_TRUE(serve.WaitStarted()) << serve.Output() << serve.Errors();
  TestProcess controller(
      {VLAB_BINARY_DIR "/examples/joint_control", "--arm", "127.0.0.1:" + Port(arm), "--duration", "100000", "--quiet"},
      0);
  // lockstep periods go by: 250 of them (0.5 s), read from the sim device by a bystander that
  // sends no op (lockstep does not wait for it)
  bridge::Sim watch = bridge::Sim::Connect("127.0.0.1", sim, 10.0);
  bridge::Sim::State state = watch.Read(10.0);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (state.periods < 250 && std::chrono::steady_clock::now() < deadline) state = watch.Read(10.0);
  ASSERT_GE(state.periods, 250) << serve.Output() << serve.Errors();
  serve.Signal(SIGINT);
  // and SIGINT again every 10 ms until it has exited: the files are still written whole. (Not
  // SIGTERM: sent microseconds after the first SIGINT, on a busy machine another thread of the
  // process may take it before the thread the kernel woke for SIGINT runs, and either is then
  // "the first": seen once in 948 tests run beside a build.)
  ASSERT_EQ(serve.Wait(60, SIGINT), 1) << serve.Output() << serve.Errors();
  EXPECT_NE(serve.Errors().find("vlab: interrupted by SIGINT at t = "), std::string::npos) << serve.Errors();
  EXPECT_NE(serve.Output().find("pa10_serve: INTERRUPTED"), std::string::npos) << serve.Output();
  EXPECT_EQ(Entries(tmp.path()), (std::set<std::string>{"out", "serve.out", "serve.err"})) << "no staging folder";
  const long periods = ExpectInterruptedOutput(tmp / "out", "SIGINT", 0.002);
  EXPECT_GT(periods, 0);
  // the controller answered every period that ran
  const nlohmann::json summary = nlohmann::json::parse(ReadFile(tmp / "out/summary.json"));
  EXPECT_EQ(summary.at("bridge").at("devices").at(0).at("name"), "pa10");
  EXPECT_GE(summary.at("bridge").at("devices").at(0).at("accepted").get<long>(), periods);
}

// the wait for a controller (start timeout 600 s) ends at the signal
TEST(ServeLifecycle, SignalEndsTheWaitForAController) {
  TempDir tmp;
  WriteFile(tmp / "s.yaml", LockstepScenario(600, 10));
  const int arm = FreeUdpPort(), sim = FreeUdpPort();
  ServeProcess serve("'" + (tmp / "s.yaml") + "' --port pa10=" + Port(arm) + " --port sim=" + Port(sim) + " --out '" +
                         (tmp / "out") + "'",
                     tmp.path());
  ASSERT_TRUE(serve.WaitStarted()) << serve.Output() << serve.Errors();
  // it waits for a controller once it says so
  ASSERT_TRUE(WaitUntil([&] {
    return serve.Errors().find("vlab serve: waiting for a controller") != std::string::npos;
  })) << serve.Errors();
  serve.Signal(SIGINT);
  ASSERT_EQ(serve.Wait(30), 1) << serve.Output() << serve.Errors();  // -1: still waiting after 30 s
  EXPECT_NE(serve.Errors().find("vlab serve: waiting for a controller on pa10 127.0.0.1:" + Port(arm) +
                                " (lockstep, start timeout 600 s)"),
            std::string::npos)
      << serve.Errors();
  EXPECT_NE(serve.Errors().find("vlab: interrupted by SIGINT at t = 0 s"), std::string::npos) << serve.Errors();
  EXPECT_EQ(ExpectInterruptedOutput(tmp / "out", "SIGINT", 0.002), 0);  // the initial row only
}

// a run paused through the sim device ends at the signal
TEST(ServeLifecycle, SigtermEndsAPausedRun) {
  TempDir tmp;
  // period 0 goes ahead without a controller after 2 s: time enough for the pause to arrive
  WriteFile(tmp / "s.yaml", LockstepScenario(2, 10000));
  const int arm = FreeUdpPort(), sim_port = FreeUdpPort();
  ServeProcess serve("'" + (tmp / "s.yaml") + "' --port pa10=" + Port(arm) + " --port sim=" + Port(sim_port) +
                         " --out '" + (tmp / "out") + "'",
                     tmp.path());
  ASSERT_TRUE(serve.WaitStarted()) << serve.Output() << serve.Errors();
  bridge::Sim sim = bridge::Sim::Connect("127.0.0.1", sim_port, 10.0);
  bridge::Sim::State state = sim.Read(10.0);
  ASSERT_TRUE(sim.Write(bridge::SimOp::kPause, 0, state.seq));
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (state.mode != 1 && std::chrono::steady_clock::now() < deadline) state = sim.Read(10.0);
  ASSERT_EQ(state.mode, 1) << "paused";
  serve.Signal(SIGTERM);
  ASSERT_EQ(serve.Wait(30), 1) << serve.Output() << serve.Errors();  // -1: still paused after 30 s
  EXPECT_EQ(ExpectInterruptedOutput(tmp / "out", "SIGTERM", 0.002), static_cast<long>(state.periods));
}

// lockstep with nobody to answer: the run goes on after the start timeout, and fails
// because no command arrived; other clocks are not judged by it
TEST(ServeLifecycle, NoControllerIsNotAPass) {
  TempDir tmp;
  WriteFile(tmp / "s.yaml", LockstepScenario(0.3, 0.2));
  const int arm = FreeUdpPort(), sim = FreeUdpPort();
  const std::string ports = " --port pa10=" + Port(arm) + " --port sim=" + Port(sim);
  ProcessResult r = RunVlab("serve '" + (tmp / "s.yaml") + "'" + ports + " --out '" + (tmp / "a") + "'", 60);
  ASSERT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_NE(r.err.find("vlab serve: waiting for a controller on pa10 127.0.0.1:" + Port(arm) +
                       " (lockstep, start timeout 0.3 s)\n"),
            std::string::npos)
      << r.err;
  const std::string why = "no controller connected: no command arrived in the run";
  EXPECT_NE(r.err.find("vlab: " + why + " (lockstep; commanded devices: pa10 127.0.0.1:" + Port(arm) + ")"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.out.find("lifecycle: FAIL"), std::string::npos) << r.out;
  const nlohmann::json a = nlohmann::json::parse(ReadFile(tmp / "a/summary.json"));
  EXPECT_EQ(a.at("result"), "fail");
  EXPECT_EQ(a.at("failure").get<std::string>().rfind(why, 0), 0u) << a.at("failure");
  EXPECT_EQ(Lines(ReadFile(tmp / "a/log.csv")).size(), 2u + 100u);  // the run itself went to its end

  // --quiet: no waiting line; the verdict is the same
  r = RunVlab("serve '" + (tmp / "s.yaml") + "'" + ports + " -q --out '" + (tmp / "b") + "'", 60);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(r.err.find("waiting"), std::string::npos) << r.err;
  // realtime and fast runs are not judged by it
  r = RunVlab("serve '" + (tmp / "s.yaml") + "'" + ports + " --clock realtime --out '" + (tmp / "c") + "'", 60);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  r = RunVlab("serve '" + (tmp / "s.yaml") + "'" + ports + " --clock fast --out '" + (tmp / "d") + "'", 60);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
}

}  // namespace
}  // namespace vlab::testing
