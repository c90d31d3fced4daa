// vlab record (src/cli/cli_record.cc) end to end: the real vlab executable recording a
// lockstep `vlab serve` (its log against the served run's own log.csv) and a realtime
// vlab-kinsim (every state there), and refusing bad arguments and a silent port.
#include <signal.h>
#include <stdio.h>
#include <sys/wait.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bridge/bridge_device_server.h"
#include "bridge/bridge_layouts.h"
#include "bridge/bridge_udp.h"
#include "kinsim/kinsim_process.h"
#include "test_process.h"
#include "test_util.h"

namespace vlab::cli::record_test {
namespace {

namespace fs = std::filesystem;
using testing::KinsimProcess;
using testing::RunCapture;
using testing::TempDir;
using testing::TestProcess;

const char* const kVlab = VLAB_BINARY_DIR "/vlab";

// the port of "NAME (KIND) 127.0.0.1:PORT;" in a start line (0 when it is not there)
int PortOf(const std::string& line, const std::string& device) {
  const std::size_t at = line.find(" " + device + " (");
  if (at == std::string::npos) return 0;
  const std::size_t colon = line.find(':', at);
  return colon == std::string::npos ? 0 : std::atoi(line.c_str() + colon + 1);
}

nlohmann::json ReadJson(const std::string& path) {
  std::ifstream file(path);
  return nlohmann::json::parse(file, nullptr, false);
}

long Lines(const std::string& path) {
  std::ifstream file(path);
  std::string line;
  long n = 0;
  while (std::getline(file, line)) ++n;
  return n;
}

// A lockstep vlab serve of the PA10 and its JR3 for 0.5 s into tmp/served, and vlab record of
// both for 0.5 s of stamps into tmp/rec, subscribed (its start line read) before any controller
// starts; Controller() starts joint_control on the arm.
struct ServedAndRecorded {
  void Start(const TempDir& tmp) {
    serve = std::make_unique<TestProcess>(std::vector<std::string>{
        kVlab, "serve", "scenes/pa10_serve", "--ports", "auto", "--duration", "0.5", "--out", tmp / "served", "-q"});
    arm = PortOf(serve->start_line(), "pa10");
    const int jr3 = PortOf(serve->start_line(), "jr3");
    ASSERT_TRUE(arm > 0 && jr3 > 0) << serve->start_line();
    record = std::make_unique<TestProcess>(
        std::vector<std::string>{kVlab, "record", "pa10=127.0.0.1:" + std::to_string(arm),
                                 "jr3=127.0.0.1:" + std::to_string(jr3), "--duration", "0.5", "--out", tmp / "rec"});
    ASSERT_NE(record->start_line().find("vlab record: pa10 (arm)"), std::string::npos) << record->start_line();
  }
  // (it prints nothing until it ends: not waited for; it ends when the served run stops answering)
  TestProcess Controller() const {
    return TestProcess(
        {VLAB_BINARY_DIR "/examples/joint_control", "--arm", "127.0.0.1:" + std::to_string(arm), "--quiet"}, 0);
  }
  std::unique_ptr<TestProcess> serve, record;
  int arm = 0;
};

// A lockstep vlab serve of the PA10 and its JR3 under joint_control, recorded from before the
// controller starts (so the lab's period 0 waits for it, and the recorder, subscribed already,
// gets every state): the record has a row at every stamp of the run's log.csv, and vlab compare
// finds every shared column equal, bit for bit (a column no tolerance names must match exactly).
TEST(Record, ServedRunMatchesTheRunsOwnLog) {
  TempDir tmp;
  ServedAndRecorded run;
  ASSERT_NO_FATAL_FAILURE(run.Start(tmp));
  TestProcess controller = run.Controller();
  EXPECT_EQ(run.serve->Wait(60), 0);
  EXPECT_EQ(run.record->Wait(30), 0) << run.record->output();
  controller.Wait(5);  // it ends when the served run stops answering

  // 0.5 s at 500 Hz: stamps 0 .. 0.5, one row each, as the run's log
  EXPECT_EQ(Lines(tmp / "rec/log.csv"), 1 + 251);
  EXPECT_EQ(Lines(tmp / "rec/log.csv"), Lines(tmp / "served/log.csv"));
  std::string report;
  const int code = RunCapture(std::string(kVlab) + " compare " + tmp / "served" + " " + tmp / "rec" +
                                  " --ignore pa10.status --ignore jr3.filter",
                              &report);
  EXPECT_EQ(code, 0) << report;
  // the arm's 21 joint values and the JR3's 7, at the 251 stamps
  EXPECT_NE(report.find("251 golden rows over t = 0 .. 0.5 s, 28 columns compared"), std::string::npos) << report;

  const nlohmann::json summary = ReadJson(tmp / "rec/summary.json");
  ASSERT_TRUE(summary.is_object());
  EXPECT_EQ(summary["rows"], 251);
  for (const nlohmann::json& d : summary["devices"]) {
    EXPECT_EQ(d["states"], 251) << d["name"];
    EXPECT_EQ(d["lost"], 0) << d["name"];
    EXPECT_EQ(d["refused"], 0) << d["name"];
  }
  EXPECT_TRUE(fs::is_regular_file(tmp / "rec/.vlab-output"));
}

// A recorder the machine does not schedule loses nothing its socket buffer holds: stopped
// (SIGSTOP) from its start line until the whole lockstep run has been served, it then finds
// every state of the run waiting in its sockets. vlab record asks for a 4 MiB buffer per device;
// the kernel's default 208 KiB held 167 of the PA10's 251 states, and the recorder then waited
// for the run's last stamps forever. (Where no process of this user may have 1 MiB,
// net.core.rmem_max and no CAP_NET_ADMIN, the test says so and skips.)
TEST(Record, AStalledRecorderLosesNothingItsBufferHolds) {
  // what this process may have, the recorder may have: the same user on the same machine
  const std::unique_ptr<bridge::UdpSocket> probe = bridge::UdpSocket::Bind("127.0.0.1", 0);
  const int may = bridge::SetSocketBuffer(probe->fd(), SO_RCVBUF, 4 << 20);
  if (may < (1 << 20)) GTEST_SKIP() << "a receive buffer of " << may << " bytes only here (net.core.rmem_max)";
  TempDir tmp;
  ServedAndRecorded run;
  ASSERT_NO_FATAL_FAILURE(run.Start(tmp));
  ASSERT_TRUE(run.record->Signal(SIGSTOP));
  TestProcess controller = run.Controller();
  EXPECT_EQ(run.serve->Wait(60), 0);  // every state is sent, to a recorder that has not run since
  ASSERT_TRUE(run.record->Signal(SIGCONT));
  EXPECT_EQ(run.record->Wait(30), 0) << "(-1: it never saw the run's last stamps) " << run.record->output();
  controller.Wait(5);

  const nlohmann::json summary = ReadJson(tmp / "rec/summary.json");
  ASSERT_TRUE(summary.is_object());
  EXPECT_EQ(summary["rows"], 251);
  for (const nlohmann::json& d : summary["devices"]) {
    EXPECT_GE(d["receive_buffer_bytes"], 1 << 20) << d["name"];
    EXPECT_EQ(d["states"], 251) << d["name"];
    EXPECT_EQ(d["lost"], 0) << d["name"];
  }
  EXPECT_EQ(Lines(tmp / "rec/log.csv"), Lines(tmp / "served/log.csv"));
}

// vlab-kinsim in realtime at 500 Hz, recorded for 1 s of its stamps: every state from the first
// taken to the last is there (consecutive seqs, none lost), one row each.
TEST(Record, KinsimInRealtimeEveryStateAccountedFor) {
  TempDir tmp;
  KinsimProcess kinsim({"--rate", "500"});
  ASSERT_TRUE(kinsim.ok()) << kinsim.start_line();
  TestProcess record(
      {kVlab, "record", "arm=127.0.0.1:" + std::to_string(kinsim.port()), "--duration", "1", "--out", tmp / "rec"});
  ASSERT_NE(record.start_line().find("vlab record: arm (arm)"), std::string::npos) << record.start_line();
  EXPECT_EQ(record.Wait(30), 0) << record.output();

  const nlohmann::json summary = ReadJson(tmp / "rec/summary.json");
  ASSERT_TRUE(summary.is_object());
  const nlohmann::json& d = summary["devices"][0];
  EXPECT_EQ(d["lost"], 0);
  EXPECT_EQ(d["refused"], 0);
  EXPECT_EQ(d["late"], 0);
  EXPECT_EQ(d["malformed"], 0);
  // 1 s at 500 Hz: 501 states, seq first .. first + 500, each in its own row
  const long first = d["first_seq"], last = d["last_seq"];
  EXPECT_EQ(last - first, 500);
  EXPECT_EQ(d["states"], 501);
  EXPECT_EQ(summary["rows"], 501);
  EXPECT_EQ(Lines(tmp / "rec/log.csv"), 1 + 501);
  EXPECT_NEAR(summary["last_stamp"].get<double>() - summary["first_stamp"].get<double>(), 1.0, 1e-9);
  // the lab's column names for an arm, from the describe reply's joints
  std::ifstream log(tmp / "rec/log.csv");
  std::string header;
  std::getline(log, header);
  EXPECT_EQ(header.rfind("time,arm.status,arm.q.S1,", 0), 0u) << header;
  EXPECT_NE(header.find(",arm.tau.W2"), std::string::npos) << header;
  kinsim.Stop();
}

// A scripted device of `kind` served by this test on a free port, output only, with a describe
// reply of the protocol's layout for the kind.
std::unique_ptr<bridge::DeviceServer> ScriptedDevice(const std::string& name, bridge::DeviceKind kind) {
  std::unique_ptr<bridge::DeviceServer> server = bridge::DeviceServer::Bind({});
  nlohmann::json describe = {{"name", name},        {"kind", bridge::KindName(static_cast<int>(kind))},
                             {"protocol", 2},       {"server", "scripted test device"},
                             {"clock", "realtime"}, {"layout", bridge::LayoutJson(kind)}};
  bridge::EndpointConfig e;
  e.name = name;
  e.kind = kind;
  e.describe_json = describe.dump();
  e.status_first = kind == bridge::DeviceKind::kGripper;
  server->Serve(std::move(e));
  return server;
}

// Two scripted devices, one thread serving both: a gripper whose states come with a duplicate,
// a replay and a gap, and a wrench with states at some of the gripper's stamps only. The
// duplicate and the replay are refused and counted, the gap counted as lost; rows are one per
// stamp, the wrench's cells NaN where it sent nothing; the gripper's opening_velocity is the
// lab's column g.velocity.
TEST(Record, CountsDuplicatesReplaysAndGapsAndLeavesMissingCellsNaN) {
  TempDir tmp;
  std::unique_ptr<bridge::DeviceServer> gripper = ScriptedDevice("g", bridge::DeviceKind::kGripper);
  std::unique_ptr<bridge::DeviceServer> wrench = ScriptedDevice("w", bridge::DeviceKind::kWrench);
  std::atomic<bool> go{false}, stop{false};
  std::thread server([&] {
    while (!go) {  // the handshakes, until the recorder says it is subscribed
      gripper->Receive(0, nullptr, 0.005);
      wrench->Receive(0);
    }
    // (seq, stamp) of the gripper: 2 again (duplicate), 1 again (replay), 3 and 4 lost
    const double g[][2] = {{0, 0.0}, {1, 0.01}, {2, 0.02}, {2, 0.02}, {1, 0.01}, {5, 0.05}, {6, 0.06}};
    for (int i = 0; i < 7; ++i) {
      const double values[5] = {0, 0.05 + g[i][1], -0.1, 2.0, 0};  // status, opening, opening_velocity, force, grasped
      gripper->Publish(g[i][0], g[i][1], values, 5);
      // the wrench at the gripper's stamps 0, 0.05 and 0.06 only
      const double wrench_values[8] = {1, 2, 3, 0.1, 0.2, 0.3, 0, 0};
      if (i == 0 || i >= 5) wrench->Publish(i == 0 ? 0 : i - 4, g[i][1], wrench_values, 8);
    }
    while (!stop) gripper->Receive(0, nullptr, 0.005);  // (renewals)
  });
  TestProcess record({kVlab, "record", "g=127.0.0.1:" + std::to_string(gripper->port()),
                      "w=127.0.0.1:" + std::to_string(wrench->port()), "--duration", "0.06", "--out", tmp / "rec"});
  go = true;
  EXPECT_NE(record.start_line().find("vlab record: g (gripper)"), std::string::npos) << record.start_line();
  EXPECT_EQ(record.Wait(30), 0) << record.output();
  stop = true;
  server.join();

  const nlohmann::json summary = ReadJson(tmp / "rec/summary.json");
  ASSERT_TRUE(summary.is_object());
  const nlohmann::json& g = summary["devices"][0];
  const nlohmann::json& w = summary["devices"][1];
  EXPECT_EQ(g["states"], 5);
  EXPECT_EQ(g["refused"], 2);
  EXPECT_EQ(g["lost"], 2);
  EXPECT_EQ(w["states"], 3);
  EXPECT_EQ(w["refused"], 0);
  EXPECT_EQ(w["lost"], 0);
  EXPECT_EQ(summary["rows"], 5);
  std::ifstream log(tmp / "rec/log.csv");
  std::stringstream text;
  text << log.rdbuf();
  EXPECT_EQ(text.str(),
            "time,g.status,g.opening,g.velocity,g.force,g.grasped,w.Fx,w.Fy,w.Fz,w.Mx,w.My,w.Mz,w.filter,w.saturated\n"
            "0,0,0.05,-0.1,2,0,1,2,3,0.1,0.2,0.3,0,0\n"
            "0.01,0,0.060000000000000005,-0.1,2,0,nan,nan,nan,nan,nan,nan,nan,nan\n"
            "0.02,0,0.07,-0.1,2,0,nan,nan,nan,nan,nan,nan,nan,nan\n"
            "0.05,0,0.1,-0.1,2,0,1,2,3,0.1,0.2,0.3,0,0\n"
            "0.06,0,0.11,-0.1,2,0,1,2,3,0.1,0.2,0.3,0,0\n");
}

// Bad arguments and a port where nothing answers: exit 2, one line naming the argument, and no
// output folder (nor a staging folder beside it).
TEST(Record, RefusesBadArgumentsAndASilentPortWritingNothing) {
  TempDir tmp;
  const std::unique_ptr<bridge::UdpSocket> silent = bridge::UdpSocket::Bind("127.0.0.1", 0);  // never answers
  const std::string quiet = "a=127.0.0.1:" + std::to_string(silent->local_port());
  const struct {
    std::string args, message;
  } cases[] = {
      {"pa10", "'pa10': expected NAME=HOST:PORT"},
      {"pa10=127.0.0.1", "'pa10=127.0.0.1': expected NAME=HOST:PORT"},
      {"pa10=127.0.0.1:0", "'pa10=127.0.0.1:0': expected NAME=HOST:PORT"},
      {"p.a=127.0.0.1:5", "'p.a=127.0.0.1:5': NAME may hold only"},
      {"a=127.0.0.1:5 a=127.0.0.1:6", "'a=127.0.0.1:6': the name 'a' is given twice"},
      {quiet + " --timeout 0.3", quiet + ": no device answered within 0.3 s"},
  };
  for (const auto& c : cases) {
    std::string output;
    const int code = RunCapture(std::string(kVlab) + " record " + c.args + " --out " + tmp / "rec", &output);
    EXPECT_EQ(code, 2) << c.args << ": " << output;
    EXPECT_NE(output.find(c.message), std::string::npos) << c.args << ": " << output;
    EXPECT_EQ(std::count(output.begin(), output.end(), '\n'), 1) << output;
  }
  EXPECT_TRUE(fs::is_empty(tmp.path())) << "something was written in " << tmp.path();
}

}  // namespace
}  // namespace vlab::cli::record_test
