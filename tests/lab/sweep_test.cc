// lab_sweep.h and lab_collect.h, and vlab sweep / vlab collect on the real binary:
// a grid expands in order with stable ids, every override is checked before any run,
// runs already complete are skipped, and the collected table is one row per run.
#include "lab/lab_collect.h"
#include "lab/lab_sweep.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "core/core_errors.h"
#include "test_util.h"

namespace vlab::lab {
namespace {

namespace fs = std::filesystem;
using vlab::testing::Lines;
using vlab::testing::ReadFile;
using vlab::testing::RunVlab;
using vlab::testing::SplitCsv;
using vlab::testing::TempDir;
using vlab::testing::WriteFile;

const std::string kScenario = std::string(VLAB_SOURCE_DIR) + "/scenes/pa10_reach.yaml";

std::string SweepError(const std::string& text) {
  TempDir dir;
  WriteFile(dir / "s.yaml", text);
  try {
    LoadSweep(dir / "s.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(SweepTest, GridExpandsLastKeyFastestSeedsInnermost) {
  TempDir dir;
  WriteFile(dir / "s.yaml", "scenario: " + kScenario +
                                "\nseeds: {from: 4, count: 2}\nset: [devices.jr3.filter=2]\n"
                                "grid:\n  controller.gains.position: [10, 20]\n  controller.start: [0.25, 0.5, 1]\n");
  const Sweep s = LoadSweep(dir / "s.yaml");
  EXPECT_EQ(s.name, "s");
  ASSERT_EQ(s.runs.size(), 2u * 3u * 2u);
  EXPECT_EQ(s.runs[0].id, "p00_s4");
  EXPECT_EQ(s.runs[1].id, "p00_s5");
  EXPECT_EQ(s.runs[2].id, "p01_s4");
  EXPECT_EQ(s.runs[11].id, "p05_s5");
  EXPECT_EQ(s.runs[2].sets, (std::vector<std::string>{"devices.jr3.filter=2", "controller.gains.position=10",
                                                      "controller.start=0.5"}));
  EXPECT_EQ(RunArguments(s, s.runs[3], "/o"),
            (std::vector<std::string>{"run", kScenario, "--seed", "5", "--set", "devices.jr3.filter=2", "--set",
                                      "controller.gains.position=10", "--set", "controller.start=0.5", "--out",
                                      "/o/p01_s5", "-q"}));
}

TEST(SweepTest, ListEntriesAndNoSeedsUseTheScenariosSeed) {
  TempDir dir;
  WriteFile(dir / "s.yaml", "name: l\nscenario: " + kScenario + "\nduration: 2\n"
                                "list:\n  - {controller.gains.position: 5, devices.jr3.filter: 3}\n"
                                "  - {'devices.pa10.initial': [0, 0.5, 0, 1, 0, 1.5, 0]}\n");
  const Sweep s = LoadSweep(dir / "s.yaml");
  ASSERT_EQ(s.runs.size(), 2u);
  EXPECT_EQ(s.runs[0].id, "p00");
  EXPECT_EQ(s.runs[0].seed, -1);
  EXPECT_EQ(s.runs[1].sets, (std::vector<std::string>{"devices.pa10.initial=[0, 0.5, 0, 1, 0, 1.5, 0]"}));
  const std::vector<std::string> args = RunArguments(s, s.runs[0], "o");
  EXPECT_EQ(std::count(args.begin(), args.end(), "--seed"), 0);
  EXPECT_EQ(args[3], "2");  // --duration 2
}

TEST(SweepTest, BadSweepsNameFileKeyAndOverrideSetBeforeAnyRun) {
  const std::string head = "scenario: " + kScenario + "\n";
  EXPECT_NE(SweepError(head + "seed: [1]\n").find("s.yaml:2: seed: unknown key"), std::string::npos);
  EXPECT_NE(SweepError(head + "seeds: [1, -2]\n").find("seeds[1]: must be a non-negative integer"), std::string::npos);
  EXPECT_NE(SweepError(head + "grid: {a: []}\n").find("grid.a: expected a non-empty list"), std::string::npos);
  EXPECT_NE(SweepError(head + "grid: {a: [1]}\nlist: [{a: 1}]\n").find("either grid or list"), std::string::npos);
  EXPECT_NE(SweepError("scenario: nope.yaml\n").find("scenario: no such file"), std::string::npos);
  // a value the scenario refuses: named with its override set, nothing run
  const std::string e = SweepError(head + "grid: {devices.jr3.filter: [2, abc]}\n");
  EXPECT_NE(e.find("override set 1: "), std::string::npos) << e;
  EXPECT_NE(e.find("devices[1].filter: expected an integer, got 'abc' (from --set devices.jr3.filter=abc)"),
            std::string::npos) << e;
}

TEST(SweepTest, ShellQuoteLeavesPlainWordsAndQuotesTheRest) {
  EXPECT_EQ(ShellQuote("controller.gains.position=10"), "controller.gains.position=10");
  EXPECT_EQ(ShellQuote("a=[1, 2]"), "'a=[1, 2]'");
  EXPECT_EQ(ShellQuote("it's"), "'it'\\''s'");
  EXPECT_EQ(ShellQuote(""), "''");
}

TEST(CollectTest, OneRowPerRunFolderColumnsFromSummaries) {
  TempDir dir;
  fs::create_directories(dir / "b");
  fs::create_directories(dir / "a");
  fs::create_directories(dir / "logs");  // not a run: no summary.json
  WriteFile(dir / "b/summary.json",
            R"({"scenario":"x","seed":2,"result":"fail","exit_code":1,"overrides":{"k":"20"},
                "checks":[{"name":"c","value":0.5,"pass":false}],"timings":{"sim_time_s":1,"loop_wall_s":0.25}})");
  WriteFile(dir / "a/summary.json",
            R"({"scenario":"x","seed":1,"result":"pass","exit_code":0,"overrides":{"k":"10","m":"[1, 2]"},
                "checks":[{"name":"c","value":0.1,"pass":true},{"name":"d","value":null,"pass":true,"skipped":"s"}]})");
  const CollectedTable t = CollectRuns(dir.path(), false);
  EXPECT_EQ(t.columns, (std::vector<std::string>{"id", "scenario", "seed", "result", "exit_code", "set:k", "set:m", "c",
                                                 "c.verdict", "d", "d.verdict"}));
  EXPECT_EQ(CollectedCsv(t), "id,scenario,seed,result,exit_code,set:k,set:m,c,c.verdict,d,d.verdict\n"
                             "a,x,1,pass,0,10,\"[1, 2]\",0.1,pass,nan,skip\n"
                             "b,x,2,fail,1,20,,0.5,fail,,\n");
  EXPECT_EQ(t.pass, 1);
  EXPECT_EQ(t.failed, 1);
  EXPECT_EQ(CollectRuns(dir.path(), true).Column("loop_wall_s"), 12);
  fs::create_directories(dir / "c");
  WriteFile(dir / "c/summary.json", "{oops");
  EXPECT_THROW(CollectRuns(dir.path(), false), InputError);
  TempDir empty;
  EXPECT_THROW(CollectRuns(empty.path(), false), InputError);
}

// the real binary: 2 seeds x 2 gains, run 2 at a time, resumed, collected, plotted
// (3 s: the first corner, 2.5 s, is reached, so the scenario's final-error check holds)
TEST(SweepCliTest, RunsResumesCollectsAndPlots) {
  TempDir dir;
  WriteFile(dir / "s.yaml", "name: g\nscenario: " + kScenario +
                                "\nduration: 3\nseeds: [1, 2]\ngrid: {controller.gains.position: [10, 40]}\n");
  const auto list = RunVlab("sweep " + (dir / "s.yaml") + " --list --out " + (dir / "out") + " --vlab vlab");
  ASSERT_EQ(list.exit_code, 0) << list.err;
  const std::vector<std::string> lines = Lines(list.out);
  ASSERT_EQ(lines.size(), 4u) << list.out;
  EXPECT_EQ(lines[3], "vlab run " + kScenario + " --seed 2 --duration 3 --set controller.gains.position=40 --out " +
                          (dir / "out/p01_s2") + " -q");

  const auto run = RunVlab("sweep " + (dir / "s.yaml") + " -j 2 --out " + (dir / "out"));
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_NE(run.out.find("sweep g: 4 pass, 0 failed, 0 skipped"), std::string::npos) << run.out;
  for (const char* id : {"p00_s1", "p00_s2", "p01_s1", "p01_s2"}) {
    EXPECT_TRUE(fs::is_regular_file(dir / ("out/" + std::string(id) + "/summary.json"))) << id;
  }
  // resume: a missing run and an interrupted one are run again, the complete ones skipped
  fs::remove_all(dir / "out/p00_s2");
  std::string summary = ReadFile(dir / "out/p01_s1/summary.json");
  summary.replace(summary.find("\"result\": \"pass\""), 16, "\"result\": \"interrupted\"");
  WriteFile(dir / "out/p01_s1/summary.json", summary);
  const auto resumed = RunVlab("sweep " + (dir / "s.yaml") + " -j 2 --out " + (dir / "out"));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.out << resumed.err;
  EXPECT_NE(resumed.out.find("4 runs, 2 complete already (skipped), 2 to run"), std::string::npos) << resumed.out;
  EXPECT_NE(resumed.out.find("p00_s2"), std::string::npos);
  EXPECT_NE(resumed.out.find("p01_s1"), std::string::npos);
  EXPECT_EQ(resumed.out.find("p00_s1 "), std::string::npos) << "a complete run is not run again";

  const auto collect = RunVlab("collect " + (dir / "out") + " --plot " + (dir / "g.png") +
                               " --x controller.gains.position --y position_tracking");
  ASSERT_EQ(collect.exit_code, 0) << collect.err;
  EXPECT_NE(collect.err.find("4 runs: 4 pass, 0 failed, 0 interrupted"), std::string::npos) << collect.err;
  const std::vector<std::string> rows = Lines(collect.out);
  ASSERT_EQ(rows.size(), 5u) << collect.out;
  const std::vector<std::string> header = SplitCsv(rows[0]);
  const auto col = [&](const std::string& name) { return std::find(header.begin(), header.end(), name) - header.begin(); };
  ASSERT_LT(col("position_tracking"), static_cast<long>(header.size()));
  ASSERT_LT(col("loop_wall_s"), static_cast<long>(header.size()));
  // a stiffer task-space gain tracks closer: the table shows it per seed
  const std::vector<std::string> p00 = SplitCsv(rows[1]), p01 = SplitCsv(rows[3]);
  EXPECT_EQ(p00[col("set:controller.gains.position")], "10");
  EXPECT_EQ(p01[col("set:controller.gains.position")], "40");
  EXPECT_LT(std::stod(p01[col("position_tracking")]), std::stod(p00[col("position_tracking")]));
  EXPECT_GT(fs::file_size(dir / "g.png"), 1000u);
  EXPECT_EQ(vlab::testing::Entries(dir.path()).count("g.png.data-" ), 0u);
  const auto bad = RunVlab("collect " + (dir / "out") + " --plot " + (dir / "h.png") + " --x nope --y position_tracking");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--x nope: no run overrides it"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace vlab::lab
