// The vlab executable end to end: the default scenario passes and writes a
// complete, deterministic output folder; bad input exits 2 with one line naming
// the cause and writes nothing; divergence and failed checks exit 1.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lab/outputs/lab_log.h"
#include "test_run_output.h"
#include "test_util.h"

namespace vlab::lab::cli_test {
namespace {

namespace fs = std::filesystem;
using vlab::testing::Entries;
using vlab::testing::ExpectInterruptedOutput;
using vlab::testing::Lines;
using vlab::testing::ReadFile;
using vlab::testing::RunVlab;
using vlab::testing::SplitCsv;
using vlab::testing::TempDir;
using vlab::testing::WriteFile;

bool Has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// The default scenario with the scene given by absolute path, `duration` and the
// checks replaced by `checks` (YAML list items), written to dir/name.yaml.
std::string DefaultScenarioWith(const TempDir& dir, const std::string& name, const std::string& checks,
                                const std::string& device_joints = "[S1, S2, S3, E1, E2, W1, W2]") {
  std::string text = ReadFile(VLAB_SOURCE_DIR "/scenes/pa10_reach.yaml");
  auto replace = [&text](const std::string& from, const std::string& to) {
    const auto at = text.find(from);
    if (at == std::string::npos) throw std::runtime_error("pa10_reach.yaml has no '" + from + "'");
    text.replace(at, from.size(), to);
  };
  replace("name: pa10_reach", "name: " + name);
  replace("scene: pa10.xml", "scene: " VLAB_SOURCE_DIR "/scenes/pa10.xml");
  replace("duration: 13.0", "duration: 1.0");
  replace("joints: [S1, S2, S3, E1, E2, W1, W2]", "joints: " + device_joints);
  text = text.substr(0, text.find("\nchecks:")) + "\nchecks:\n" + checks;
  const std::string path = dir / (name + ".yaml");
  WriteFile(path, text);
  return path;
}

TEST(CliTest, DefaultScenarioPassesAndWritesOutputs) {
  TempDir tmp;
  const auto r = RunVlab("run scenes/pa10_reach -q --out '" + (tmp / "out") + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  EXPECT_EQ(r.err, "");
  EXPECT_EQ(Entries(tmp.path()), std::set<std::string>{"out"});  // no staging folder left
  EXPECT_EQ(Entries(tmp / "out"), (std::set<std::string>{"log.csv", "summary.json", ".vlab-output"}));

  const nlohmann::json s = nlohmann::json::parse(ReadFile(tmp / "out/summary.json"));
  EXPECT_EQ(s.at("result"), "pass");
  EXPECT_EQ(s.at("exit_code"), 0);
  EXPECT_EQ(s.at("seed"), 7);
  EXPECT_EQ(s.at("versions").at("mujoco"), "2.2.2");
  ASSERT_EQ(s.at("checks").size(), 6u);
  for (const auto& c : s.at("checks")) {
    EXPECT_TRUE(c.at("value").is_number()) << c.dump();
    EXPECT_TRUE(c.at("bound").contains("max")) << c.dump();
    EXPECT_LE(c.at("value").get<double>(), c.at("bound").at("max").get<double>()) << c.dump();
    EXPECT_EQ(c.at("pass"), true) << c.dump();
  }
  EXPECT_EQ(s.at("checks")[0].at("name"), "position_tracking");
  const auto& t = s.at("timings");
  EXPECT_EQ(t.at("steps"), 13000);  // 13 s at the scene's 1 ms timestep
  EXPECT_EQ(t.at("control_periods"), 6500);
  EXPECT_DOUBLE_EQ(t.at("sim_time_s").get<double>(), 13.0);
  EXPECT_GT(t.at("loop_wall_s").get<double>(), 0.0);

  const std::vector<std::string> lines = Lines(ReadFile(tmp / "out/log.csv"));
  ASSERT_EQ(lines.size(), 1u + 13.0 / 0.002 + 1);  // header, initial row, one row per period
  const std::vector<std::string> header = SplitCsv(lines[0]);
  EXPECT_EQ(header[0], "time");
  for (std::size_t k = 1; k < lines.size(); ++k) {
    const std::vector<std::string> row = SplitCsv(lines[k]);
    ASSERT_EQ(row.size(), header.size()) << "row " << k - 1;
    ASSERT_EQ(row[0], FormatDouble((k - 1) * 0.002)) << "row " << k - 1;
  }
  EXPECT_EQ(SplitCsv(lines[4])[0], "0.006");
  EXPECT_EQ(SplitCsv(lines.back())[0], "13");
}

TEST(CliTest, RunsAreDeterministicAndSeedOnlyMovesTheSensor) {
  TempDir tmp;
  // the default scenario, whole, twice
  for (const char* run : {"a", "b"}) {
    const auto r = RunVlab("run scenes/pa10_reach -q --out '" + (tmp / run) + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  ASSERT_EQ(RunVlab("run scenes/pa10_reach -q --duration 3 --seed 8 --out '" + (tmp / "c") + "'").exit_code, 0);
  std::string a = ReadFile(tmp / "a/log.csv");
  const std::string b = ReadFile(tmp / "b/log.csv"), c = ReadFile(tmp / "c/log.csv");
  ASSERT_EQ(Lines(a).size(), 1u + 6500 + 1);
  ASSERT_EQ(Lines(c).size(), 1u + 1500 + 1);
  EXPECT_TRUE(a == b) << "same scenario, same seed: logs differ";
  // a shorter run with another seed: compare the rows both have
  const std::size_t row_t3 = a.find("\n3,");  // the row at t = 3 s ends the shorter log
  ASSERT_NE(row_t3, std::string::npos);
  a = a.substr(0, a.find('\n', row_t3 + 1) + 1);
  EXPECT_FALSE(a == c) << "a different seed must change the JR3 noise";
  // the JR3 acts on nothing: time, arm and controller columns are the same for any seed
  const auto la = Lines(a), lc = Lines(c);
  ASSERT_EQ(la.size(), lc.size());
  const std::vector<std::string> header = SplitCsv(la[0]);
  int arm_columns = 0, jr3_columns_differing = 0;
  std::set<std::size_t> differing;
  for (std::size_t k = 1; k < la.size(); ++k) {
    const auto ra = SplitCsv(la[k]), rc = SplitCsv(lc[k]);
    for (std::size_t i = 0; i < header.size(); ++i) {
      if (ra[i] != rc[i]) differing.insert(i);
    }
  }
  for (std::size_t i = 0; i < header.size(); ++i) {
    const std::string& h = header[i];
    if (h == "time" || h.rfind("pa10.", 0) == 0 || h.rfind("controller.", 0) == 0) {
      ++arm_columns;
      EXPECT_EQ(differing.count(i), 0u) << h << " depends on the seed";
    } else if (h.rfind("jr3.F", 0) == 0 || h.rfind("jr3.M", 0) == 0) {
      jr3_columns_differing += static_cast<int>(differing.count(i));
    }
  }
  EXPECT_EQ(arm_columns, 1 + 3 * 7 + 1 + 8);
  EXPECT_EQ(jr3_columns_differing, 6);
}

struct BadInput {
  std::string what;
  std::string args;                 // "run ..." (the test adds -q and --out)
  std::vector<std::string> expect;  // substrings of the one stderr line
};

// Runs each case with --out DIR/OUT_LEAF in a fresh DIR: exit 2, exactly one line on
// stderr naming the cause, and DIR left empty (no output, staging or parent folder).
void ExpectRejected(const std::vector<BadInput>& cases, const std::string& out_leaf = "out") {
  for (const BadInput& c : cases) {
    TempDir tmp;
    const auto r = RunVlab(c.args + " -q --out '" + (tmp / out_leaf) + "'");
    EXPECT_EQ(r.exit_code, 2) << c.what << ": " << r.err;
    EXPECT_FALSE(r.err.empty()) << c.what;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << c.what << ": not exactly one line:\n" << r.err;
    for (const auto& part : c.expect) EXPECT_TRUE(Has(r.err, part)) << c.what << ": no '" << part << "' in " << r.err;
    const auto left = Entries(tmp.path());
    EXPECT_TRUE(left.empty()) << c.what << ": left " << *left.begin() << " in the output's parent";
  }
}

// Scenarios that load but do not bind: an unknown check signal, an unknown joint,
// a control period that is not a whole number of timesteps.
struct BindingCases {
  TempDir dir;
  std::vector<BadInput> cases;
  BindingCases() {
    const std::string bad_signal = DefaultScenarioWith(
        dir, "bad_signal", "  - {name: tracking, signal: controller.postion_error, reduce: max, max: 1}\n");
    const std::string bad_joint = DefaultScenarioWith(dir, "bad_joint", "  - {name: t, signal: time, max: 100}\n",
                                                      "[S1, S2, S3, E1, E7, W1, W2]");
    const std::string text = ReadFile(bad_signal);
    const auto line = 1 + std::count(text.begin(), text.begin() + text.find("{name: tracking"), '\n');
    std::string period = ReadFile(DefaultScenarioWith(dir, "period", "  - {name: t, signal: time, max: 100}\n"));
    period.replace(period.find("control_period: 0.002"), 21, "control_period: 0.0015");
    WriteFile(dir / "period.yaml", period);
    cases = {
        {"unknown signal",
         "run '" + bad_signal + "'",
         {"bad_signal.yaml:" + std::to_string(line) + ": ", "check 'tracking'",
          "unknown signal 'controller.postion_error'"}},
        {"unknown joint", "run '" + bad_joint + "'", {"bad_joint.yaml:", "device 'pa10'", "no joint 'E7'"}},
        {"control period",
         "run '" + (dir / "period.yaml") + "'",
         {"period.yaml", "control_period 0.0015", "not a whole multiple", "0.001"}},
    };
  }
};

TEST(CliTest, BadFilesExit2WithOneLineAndWriteNothing) {
  const bool had_mujoco_log = fs::exists(VLAB_SOURCE_DIR "/MUJOCO_LOG.TXT");
  ExpectRejected({
      {"missing file", "run tests/data/no_such_scenario", {"no_such_scenario", "cannot open"}},
      {"malformed YAML", "run tests/data/malformed", {"malformed.yaml:3", "malformed YAML"}},
      {"unknown key", "run tests/data/unknown_key", {"unknown_key.yaml:8", "dampingratio", "unknown key"}},
      {"wrong type", "run tests/data/wrong_type", {"wrong_type.yaml:2", "duration", "ten seconds"}},
      {"broken scene", "run tests/data/broken_scene", {"broken_scene.xml", "undefined_attribute"}},
  });
  ExpectRejected(BindingCases().cases);
  // MuJoCo's default handlers would write MUJOCO_LOG.TXT into the working folder
  if (!had_mujoco_log) {
    EXPECT_FALSE(fs::exists(VLAB_SOURCE_DIR "/MUJOCO_LOG.TXT"));
  }
}

TEST(CliTest, BadBindingCreatesNoOutputParent) {
  // --out runs/out: on bad input not even the parent "runs" may appear
  ExpectRejected(BindingCases().cases, "runs/out");
}

TEST(CliTest, BadOptionsExit2WithOneLine) {
  ExpectRejected({
      {"no scenario", "run", {"scenario"}},
      {"negative duration", "run scenes/pa10_reach --duration -1", {"--duration"}},
      {"infinite duration", "run scenes/pa10_reach --duration inf", {"--duration", "at most 1e6 s"}},
      {"huge duration", "run scenes/pa10_reach --duration 1e300", {"--duration", "at most 1e6 s"}},
      {"shorter than half a period",
       "run scenes/pa10_reach --duration 0.0009",
       {"pa10_reach.yaml", "is shorter than half a control period (0.002 s): nothing would be simulated"}},
      {"huge duration served", "serve scenes/pa10_serve --duration 1e300", {"--duration", "at most 1e6 s"}},
      {"unknown option", "run scenes/pa10_reach --durration 1", {"--durration"}},
  });
}

TEST(CliTest, DurationsThatCannotRunAreBadInput) {
  TempDir dir;
  std::vector<BadInput> cases;
  // too long, or not a number the YAML reader takes (non-finite)
  const std::vector<std::pair<std::string, std::string>> durations = {
      {"1e300", "duration: must be > 0 s and at most 1e6 s"},
      {"2e6", "duration: must be > 0 s and at most 1e6 s"},
      {".inf", "duration: expected a finite number"},
      {".nan", "duration: expected a finite number"}};
  for (const auto& [duration, why] : durations) {
    std::string text = ReadFile(DefaultScenarioWith(dir, "d", "  - {name: t, signal: time, max: 100}\n"));
    text.replace(text.find("duration: 1.0"), 13, "duration: " + duration);
    const std::string path = dir / ("duration_" + std::to_string(cases.size()) + ".yaml");
    WriteFile(path, text);
    cases.push_back({"duration " + duration, "run '" + path + "'", {path + ":", why}});
  }
  ExpectRejected(cases);
}

// --out never removes or replaces a folder vlab did not write
TEST(CliTest, OutOnAForeignFolderExits2AndLeavesItAlone) {
  TempDir tmp;
  fs::create_directory(tmp / "mine");
  WriteFile(tmp / "mine/notes.txt", "my notes");
  const auto r = RunVlab("run scenes/pa10_reach --duration 0.1 -q --out '" + (tmp / "mine") + "'");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_TRUE(Has(r.err, "output folder '" + (tmp / "mine") + "'")) << r.err;
  EXPECT_TRUE(Has(r.err, "not an output folder of vlab's")) << r.err;
  EXPECT_EQ(ReadFile(tmp / "mine/notes.txt"), "my notes");
  EXPECT_EQ(Entries(tmp.path()), std::set<std::string>{"mine"});
  EXPECT_EQ(Entries(tmp / "mine"), std::set<std::string>{"notes.txt"});
  // a folder vlab wrote is replaced, run after run
  ASSERT_EQ(RunVlab("run scenes/pa10_reach --duration 0.1 -q --out '" + (tmp / "run") + "'").exit_code, 0);
  ASSERT_EQ(RunVlab("run scenes/pa10_reach --duration 0.1 -q --out '" + (tmp / "run") + "'").exit_code, 0);
  EXPECT_EQ(Entries(tmp / "run"), (std::set<std::string>{"log.csv", "summary.json", ".vlab-output"}));
}

TEST(CliTest, DivergingModelExits1NamingTheCause) {
  TempDir tmp;
  const auto r = RunVlab("run tests/data/diverge -q --out '" + (tmp / "out") + "'", 60);
  ASSERT_EQ(r.exit_code, 1) << r.err;  // 124 would be the timeout: a hang
  EXPECT_TRUE(Has(r.err, "diverged")) << r.err;
  EXPECT_TRUE(Has(r.err, "QACC")) << r.err;
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;
  const nlohmann::json s = nlohmann::json::parse(ReadFile(tmp / "out/summary.json"));
  EXPECT_EQ(s.at("result"), "fail");
  EXPECT_TRUE(Has(s.at("failure").get<std::string>(), "diverged"));
  EXPECT_LT(s.at("timings").at("sim_time_s").get<double>(), 2.0);  // stopped early
}

// a MuJoCo engine error mid-run: one line, exit 1, the staging folder removed,
// and MuJoCo's own handler (which waits on stdin, writes MUJOCO_LOG.TXT) never runs
TEST(CliTest, MujocoErrorExits1AndLeavesNothing) {
  TempDir tmp;
  const auto r = RunVlab("run tests/data/stack_overflow -q --out '" + (tmp / "runs/out") + "'", 60);
  ASSERT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(r.err, "vlab: MuJoCo error: Stack overflow\n");
  EXPECT_TRUE(Entries(tmp / "runs").empty()) << "no output folder, no staging folder";
  EXPECT_FALSE(fs::exists(VLAB_SOURCE_DIR "/MUJOCO_LOG.TXT"));
}

// Ctrl-C (SIGINT) stops a long run at a period boundary: exit 1, one line naming the
// signal and the time, and the output folder written whole for the periods that ran
TEST(CliTest, InterruptKeepsEveryPeriodThatRan) {
  TempDir tmp;
  // 2000 s of simulation take tens of seconds: the signal comes after 1 s
  const auto r = RunVlab("run scenes/pa10_reach -q --duration 2000 --out '" + (tmp / "runs/out") + "'", 1, "INT");
  ASSERT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(Has(r.err, "vlab: interrupted by SIGINT at t = ")) << r.err;
  EXPECT_EQ(Lines(r.err).size(), 1u) << r.err;
  EXPECT_TRUE(Has(r.out, "pa10_reach: INTERRUPTED")) << r.out;
  EXPECT_EQ(Entries(tmp / "runs"), std::set<std::string>{"out"}) << "no staging folder left";
  EXPECT_EQ(Entries(tmp / "runs/out"), (std::set<std::string>{"log.csv", "summary.json", ".vlab-output"}));
  EXPECT_GT(ExpectInterruptedOutput(tmp / "runs/out", "SIGINT", 0.002), 0);
  // the checks are evaluated over what ran, and the verdict stays "interrupted"
  const nlohmann::json s = nlohmann::json::parse(ReadFile(tmp / "runs/out/summary.json"));
  EXPECT_FALSE(s.at("checks").empty());
}

// a MuJoCo warning fails the run and is reported, unless the scenario allows it
TEST(CliTest, WarningsFailUnlessAllowed) {
  TempDir tmp;
  const auto r = RunVlab("run tests/data/contact_overflow -q --out '" + (tmp / "a") + "'", 60);
  ASSERT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(Has(r.err, "MuJoCo warning 'contactfull'")) << r.err;
  const nlohmann::json a = nlohmann::json::parse(ReadFile(tmp / "a/summary.json"));
  EXPECT_EQ(a.at("result"), "fail");
  ASSERT_EQ(a.at("warnings").size(), 1u);
  EXPECT_EQ(a.at("warnings")[0].at("name"), "contactfull");
  EXPECT_GT(a.at("warnings")[0].at("count").get<int>(), 0);
  EXPECT_FALSE(a.at("warnings")[0].at("allowed").get<bool>());
  EXPECT_TRUE(Has(a.at("warnings")[0].at("message").get<std::string>(), "nconmax"));

  const auto allowed = RunVlab("run tests/data/contact_overflow_allowed -q --out '" + (tmp / "b") + "'", 60);
  ASSERT_EQ(allowed.exit_code, 0) << allowed.err;
  const nlohmann::json b = nlohmann::json::parse(ReadFile(tmp / "b/summary.json"));
  EXPECT_EQ(b.at("result"), "pass");
  ASSERT_EQ(b.at("warnings").size(), 1u);
  EXPECT_TRUE(b.at("warnings")[0].at("allowed").get<bool>());
}

TEST(CliTest, FailedCheckExits1AndWritesCompleteOutput) {
  TempDir tmp;
  const std::string scenario =
      DefaultScenarioWith(tmp, "strict",
                          "  - {name: loose, signal: controller.position_error, reduce: max, max: 1.0}\n"
                          "  - {name: impossible, signal: controller.position_error, reduce: max, max: 1e-12}\n");
  const auto r = RunVlab("run '" + scenario + "' -q --out '" + (tmp / "out") + "'");
  ASSERT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(Has(r.err, "check 'impossible' failed")) << r.err;
  EXPECT_EQ(Entries(tmp.path()), (std::set<std::string>{"out", "strict.yaml"}));
  EXPECT_EQ(Entries(tmp / "out"), (std::set<std::string>{"log.csv", "summary.json", ".vlab-output"}));
  const nlohmann::json s = nlohmann::json::parse(ReadFile(tmp / "out/summary.json"));
  EXPECT_EQ(s.at("result"), "fail");
  ASSERT_EQ(s.at("checks").size(), 2u);
  EXPECT_EQ(s.at("checks")[0].at("pass"), true);
  EXPECT_EQ(s.at("checks")[1].at("name"), "impossible");
  EXPECT_EQ(s.at("checks")[1].at("pass"), false);
  EXPECT_GT(s.at("checks")[1].at("value").get<double>(), 1e-12);
  EXPECT_EQ(Lines(ReadFile(tmp / "out/log.csv")).size(), 1u + 500 + 1);  // the whole 1 s run
}

TEST(CliTest, ListSignalsPrintsColumnsAndWritesNothing) {
  TempDir tmp;
  const auto r = RunVlab("run scenes/pa10_reach --list-signals --out '" + (tmp / "out") + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<std::string> lines = Lines(r.out);
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(lines[0], "time");
  const std::set<std::string> names(lines.begin(), lines.end());
  for (const char* c : {"pa10.q.S1", "pa10.tau.W2", "pa10.limit_violation", "jr3.Fz", "jr3.Mx",
                        "controller.position_error", "controller.orientation_error"}) {
    EXPECT_EQ(names.count(c), 1u) << c;
  }
  EXPECT_EQ(names.size(), lines.size());  // no duplicates
  EXPECT_TRUE(Entries(tmp.path()).empty());
}

TEST(CliTest, HelpNamesSubcommands) {
  const auto r = RunVlab("--help");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(Has(r.out, "run")) << r.out;
  EXPECT_TRUE(Has(r.out, "bench")) << r.out;
  EXPECT_TRUE(Has(r.out, "Exit codes")) << r.out;
  EXPECT_NE(RunVlab("").exit_code, 0);  // a subcommand is required
}

TEST(CliTest, WrongThingsGivenSayWhatTheyAre) {
  // an unknown subcommand, and none: the known ones are named
  for (const std::string args : {"foo", ""}) {
    const auto r = RunVlab(args);
    EXPECT_EQ(r.exit_code, 2) << args;
    EXPECT_TRUE(Has(r.err, args.empty() ? "a subcommand is required" : "unknown subcommand 'foo'")) << r.err;
    EXPECT_TRUE(Has(r.err, "known: run, serve, devices, bench, render, camera, vision, cubes")) << r.err;
  }
  // a scene where a scenario is expected
  const auto scene = RunVlab("run scenes/pa10.xml -q");
  EXPECT_EQ(scene.exit_code, 2);
  EXPECT_TRUE(Has(scene.err, "scenes/pa10.xml: this is an MJCF scene, not a scenario")) << scene.err;
  // a scenario whose scene is missing: its file, line and key, and the scene's path
  TempDir dir;
  WriteFile(dir / "s.yaml", "name: s\nduration: 1\nscene: nope.xml\n");
  const auto missing = RunVlab("run '" + (dir / "s.yaml") + "' -q --out '" + (dir / "out") + "'");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_TRUE(Has(missing.err, dir / "s.yaml" + ":3: scene: scene '" + (dir / "nope.xml") + "'")) << missing.err;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

}  // namespace
}  // namespace vlab::lab::cli_test
