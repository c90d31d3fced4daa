// Ports a run takes for itself (src/lab/run/lab_command.cc, `port: auto`, `vlab serve --ports
// auto`, `vlab devices`), through the real vlab binary: two serves of one scenario with `port:
// auto` side by side each bind their own free ports and report them (start line and
// summary.json); an external controller's {port:NAME} is a free port, released before the
// program starts (the program binds it), the same in every place and in VLAB_PORT_NAME, and
// recorded in summary.json; `vlab devices --json` describes the ports a server would take,
// not the ones it bound to describe.
#include <regex>
#include <set>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "test_process.h"
#include "test_util.h"

namespace vlab::testing::ports_test {
namespace {

using nlohmann::json;

// the PA10 and its JR3, each on a port of `ports` ("auto" or a number), and `rest`
std::string Scenario(const std::string& arm_port, const std::string& wrench_port, const std::string& rest) {
  return R"(
name: ports
scene: )" VLAB_SOURCE_DIR R"(/scenes/pa10.xml
duration: 0.1
control_period: 0.002
seed: 1
clock: lockstep
lockstep: {timeout: 1.0, start_timeout: 120.0}
devices:
  - name: pa10
    kind: arm
    port: )" +
         arm_port + R"(
    joints: [S1, S2, S3, E1, E2, W1, W2]
  - {name: jr3, kind: wrench, port: )" +
         wrench_port + R"(, force_sensor: jr3_force, torque_sensor: jr3_torque}
  - {name: sim, kind: sim}
)" + rest;
}

// "NAME (KIND) ADDRESS:PORT;" of a `vlab serve` start line: NAME -> PORT
std::map<std::string, int> ServedPorts(const std::string& line) {
  std::map<std::string, int> ports;
  static const std::regex served(R"(([a-z0-9_]+) \([a-z]+\) 127\.0\.0\.1:([0-9]+);)");
  for (std::sregex_iterator it(line.begin(), line.end(), served), end; it != end; ++it) {
    ports[(*it)[1]] = std::stoi((*it)[2]);
  }
  return ports;
}

std::map<std::string, int> SummaryPorts(const std::string& summary_path) {
  std::map<std::string, int> ports;
  const json summary = json::parse(ReadFile(summary_path));
  for (const json& d : summary["bridge"]["devices"]) ports[d["name"]] = d["port"];
  return ports;
}

TEST(Ports, TwoServesOfOneScenarioWithPortAutoTakeTheirOwn) {
  TempDir dir;
  WriteFile(dir / "s.yaml", Scenario("auto", "auto", ""));
  // A binds its ports and waits (lockstep, 120 s) for a controller that never comes
  TestProcess a({VLAB_BINARY_DIR "/vlab", "serve", dir / "s.yaml", "--out", dir / "a", "-q"});
  const std::map<std::string, int> a_ports = ServedPorts(a.start_line());
  ASSERT_EQ(a_ports.size(), 2u) << a.start_line();
  // B, the same scenario while A holds its ports: fast, nothing waited for
  const ProcessResult b = RunVlab("serve " + (dir / "s.yaml") + " --clock fast -q --out " + (dir / "b"), 60);
  ASSERT_EQ(b.exit_code, 0) << b.err << b.out;
  const std::map<std::string, int> b_ports = ServedPorts(b.out);
  ASSERT_EQ(b_ports.size(), 2u) << b.out;
  std::set<int> every;
  for (const auto* ports : {&a_ports, &b_ports}) {
    for (const auto& [name, port] : *ports) {
      EXPECT_GT(port, 0) << name;
      every.insert(port);
    }
  }
  EXPECT_EQ(every.size(), 4u) << "four sockets, four ports";
  // summary.json gives the ports taken, as the start line did
  EXPECT_EQ(SummaryPorts(dir / "b/summary.json"), b_ports);
  a.Stop(30);  // SIGINT: A writes what ran (interrupted)
  EXPECT_EQ(SummaryPorts(dir / "a/summary.json"), a_ports);
}

TEST(Ports, ServePortsAutoMovesFixedPortsAside) {
  TempDir dir;
  WriteFile(dir / "s.yaml", Scenario("50010", "50011", ""));
  const ProcessResult r =
      RunVlab("serve " + (dir / "s.yaml") + " --ports auto --clock fast -q --out " + (dir / "o"), 60);
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  const std::map<std::string, int> ports = ServedPorts(r.out);
  ASSERT_EQ(ports.size(), 2u) << r.out;
  for (const auto& [name, port] : ports) {
    EXPECT_GT(port, 0) << name;
    EXPECT_NE(port, name == "pa10" ? 50010 : 50011) << name << ": a free port, not the scenario's";
  }
  EXPECT_EQ(SummaryPorts(dir / "o/summary.json"), ports);
}

// the program binds {port:helper} (python3 exits 1 when it cannot: the run would fail) and
// writes what it was given: every placeholder and variable
TEST(Ports, PlaceholderAndEnvironmentGiveTheProgramAFreePort) {
  TempDir dir;
  WriteFile(dir / "helper.py", R"(import os, socket, sys
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
s.bind(("127.0.0.1", int(sys.argv[1])))
with open(sys.argv[-1], "w") as f:
    f.write(" ".join(sys.argv[1:-1] + [os.environ["VLAB_PORT_HELPER"], os.environ["VLAB_PORT_PA10"],
                                       os.environ["VLAB_DEVICE_JR3"]]))
)");
  const std::string command = R"(controller:
  type: external
  command: ["python3", ")" + (dir / "helper.py") +
                              R"(", "{port:helper}", "{port:helper}", "{port:pa10}", "{jr3}",
            "{out}/given.txt"]
)";
  WriteFile(dir / "s.yaml", Scenario("50010", "auto", command));
  const ProcessResult r = RunVlab("run " + (dir / "s.yaml") + " -q --out " + (dir / "o"), 60);
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  const json summary = json::parse(ReadFile(dir / "o/summary.json"));
  ASSERT_TRUE(summary["controller"]["ports"].contains("helper")) << summary["controller"].dump();
  const int helper = summary["controller"]["ports"]["helper"];
  const std::map<std::string, int> devices = SummaryPorts(dir / "o/summary.json");
  ASSERT_EQ(devices.size(), 2u);
  EXPECT_GT(helper, 0);
  EXPECT_NE(helper, devices.at("pa10"));
  EXPECT_NE(helper, devices.at("jr3"));
  const std::string h = std::to_string(helper), pa10 = std::to_string(devices.at("pa10"));
  const std::string jr3 = "127.0.0.1:" + std::to_string(devices.at("jr3"));
  EXPECT_EQ(ReadFile(dir / "o/given.txt"), h + " " + h + " " + pa10 + " " + jr3 + " " + h + " " + pa10 + " " + jr3);
}

TEST(Ports, BadPortNamesAndValuesAreBadInput) {
  TempDir dir;
  WriteFile(dir / "name.yaml", Scenario("auto", "auto", "controller: {type: external, command: [sh, '{port:a-b}']}\n"));
  const ProcessResult name = RunVlab("run " + (dir / "name.yaml") + " -q --out " + (dir / "o1"), 60);
  EXPECT_EQ(name.exit_code, 2) << name.err;
  EXPECT_NE(name.err.find("name.yaml:"), std::string::npos) << name.err;
  EXPECT_NE(name.err.find("{port:a-b}: a port's name is letters, digits and '_'"), std::string::npos) << name.err;
  WriteFile(dir / "value.yaml", Scenario("automatic", "auto", ""));
  const ProcessResult value = RunVlab("serve " + (dir / "value.yaml") + " -q --out " + (dir / "o2"), 60);
  EXPECT_EQ(value.exit_code, 2) << value.err;
  EXPECT_NE(value.err.find("devices[0].port"), std::string::npos) << value.err;
  const ProcessResult option = RunVlab("devices " + (dir / "name.yaml") + " --port pa10=auto1", 60);
  EXPECT_EQ(option.exit_code, 2) << option.err;
  EXPECT_NE(option.err.find("--port 'pa10=auto1'"), std::string::npos) << option.err;
}

// vlab devices binds free ports to describe (a server may hold the real ones), and prints
// the ports a server would take: the scenario's, or auto (null in the describe reply)
TEST(Ports, DevicesDescribesThePortsAServerWouldTake) {
  TempDir dir;
  WriteFile(dir / "s.yaml", Scenario("50010", "auto", ""));
  const ProcessResult r = RunVlab("devices " + (dir / "s.yaml") + " --json", 60);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("udp 127.0.0.1:50010\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("udp 127.0.0.1:auto (a free port, chosen when served)\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("sim      sim    not served (no port)"), std::string::npos) << r.out;
  std::map<std::string, json> endpoints;
  for (const std::string& line : Lines(r.out)) {
    const std::size_t at = line.find("describe: ");
    if (at == std::string::npos) continue;
    const json d = json::parse(line.substr(at + 10));
    endpoints[d["name"]] = d["endpoint"];
  }
  ASSERT_EQ(endpoints.size(), 2u) << r.out;
  EXPECT_EQ(endpoints["pa10"], json::parse(R"({"address": "127.0.0.1", "port": 50010})"));
  EXPECT_EQ(endpoints["jr3"], json::parse(R"({"address": "127.0.0.1", "port": null})"));
  // --port DEVICE=PORT and --ports auto as vlab serve takes them
  const ProcessResult o = RunVlab("devices " + (dir / "s.yaml") + " --port jr3=50123", 60);
  EXPECT_NE(o.out.find("udp 127.0.0.1:50123\n"), std::string::npos) << o.out;
  const ProcessResult all = RunVlab("devices " + (dir / "s.yaml") + " --ports auto", 60);
  EXPECT_EQ(all.out.find("udp 127.0.0.1:50010"), std::string::npos) << all.out;
}

}  // namespace
}  // namespace vlab::testing::ports_test
