// lab_sweep.h and lab_collect.h, and vlab sweep / vlab collect on the real binary:
// a grid expands in order with stable ids, every override is checked before any run,
// runs already complete with the same record are skipped (the others run again, said why),
// and the collected table is one row per run.
#include "lab/sweep/lab_collect.h"
#include "lab/sweep/lab_sweep.h"

#include <gtest/gtest.h>

#include <filesystem>

#include <nlohmann/json.hpp>

#include "core/core_errors.h"
#include "test_util.h"

namespace vlab::lab::sweep_test {
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
  EXPECT_EQ(s.runs[2].sets,
            (std::vector<std::string>{"devices.jr3.filter=2", "controller.gains.position=10", "controller.start=0.5"}));
  // one record per override set; a run's record is its set's with its seed
  ASSERT_EQ(s.records.size(), 6u);
  EXPECT_EQ(RecordOfRun(s, s.runs[3]).seed, 5u);
  EXPECT_EQ(RecordOfRun(s, s.runs[3]).scenario_yaml, s.records[1].scenario_yaml);
  EXPECT_NE(s.records[1].scenario_yaml, s.records[2].scenario_yaml);
  EXPECT_EQ(RunArguments(s, s.runs[3], "/o"),
            (std::vector<std::string>{"run", kScenario, "--seed", "5", "--set", "devices.jr3.filter=2", "--set",
                                      "controller.gains.position=10", "--set", "controller.start=0.5", "--out",
                                      "/o/p01_s5", "-q"}));
}

TEST(SweepTest, ListEntriesAndNoSeedsUseTheScenariosSeed) {
  TempDir dir;
  WriteFile(dir / "s.yaml", "name: l\nscenario: " + kScenario +
                                "\nduration: 2\n"
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
            std::string::npos)
      << e;
}

TEST(SweepTest, ValuesWithControlCharactersGoInDoubleQuotesOnOneLine) {
  TempDir dir;
  WriteFile(dir / "s.yaml", "scenario: " + kScenario +
                                "\nset: [\"description=a\\tb\"]\n"
                                "grid:\n  description: [\"a\\nb\", \"$(c) `d` 'e'\"]\n");
  const Sweep s = LoadSweep(dir / "s.yaml");
  ASSERT_EQ(s.runs.size(), 2u);
  EXPECT_EQ(s.runs[0].sets, (std::vector<std::string>{"description=\"a\\x09b\"", "description=\"a\\x0ab\""}));
  EXPECT_EQ(s.runs[1].sets[1], "description=$(c) `d` 'e'");
  EXPECT_EQ(s.runs[0].label, "description=\"a\\x0ab\"");
}

TEST(SweepTest, ControlCharactersInKeysNamesAndPathsAreRefusedAtTheirLine) {
  const std::string head = "scenario: " + kScenario + "\n";
  std::string e = SweepError(head + "grid:\n  \"description\\n\": [a]\n");
  EXPECT_NE(e.find("s.yaml:3: grid: 'description\\x0a' holds a control character"), std::string::npos) << e;
  e = SweepError(head + "list:\n  - {\"a\\x1bb\": 1}\n");
  EXPECT_NE(e.find("s.yaml:3: list[0].a\\x1bb: 'a\\x1bb' holds a control character"), std::string::npos) << e;
  e = SweepError(head + "set: [\"a\\rb=1\"]\n");
  EXPECT_NE(e.find("s.yaml:2: set[0]: 'a\\x0db' holds a control character"), std::string::npos) << e;
  e = SweepError(head + "name: \"x\\ty\"\n");
  EXPECT_NE(e.find("s.yaml:2: name: 'x\\x09y' holds a control character"), std::string::npos) << e;
  e = SweepError("scenario: \"a\\nb.yaml\"\n");
  EXPECT_NE(e.find("s.yaml:1: scenario: 'a\\x0ab.yaml' holds a control character"), std::string::npos) << e;
}

TEST(CollectTest, OneRowPerRunFolderColumnsFromSummaries) {
  TempDir dir;
  fs::create_directories(dir / "b");
  fs::create_directories(dir / "a");
  fs::create_directories(dir / "logs");  // not a run: no summary.json
  WriteFile(dir / "b/summary.json",
            R"({"scenario":"x","seed":2,"result":"fail","exit_code":1,"overrides":{"k":"20"},
                "checks":[{"name":"c","value":0.5,"pass":false}],"timings":{"sim_time_s":1,"loop_wall_s":0.25}})");
  WriteFile(
      dir / "a/summary.json",
      R"({"scenario":"x","seed":1,"duration_s":2.5,"result":"pass","exit_code":0,"overrides":{"k":"10","m":"[1, 2]"},
                "checks":[{"name":"c","value":0.1,"pass":true},{"name":"d","value":null,"pass":true,"skipped":"s"}]})");
  const CollectedTable t = CollectRuns(dir.path(), false);
  EXPECT_EQ(t.columns, (std::vector<std::string>{"id", "scenario", "seed", "duration_s", "result", "exit_code", "set:k",
                                                 "set:m", "c", "c.verdict", "d", "d.verdict"}));
  EXPECT_EQ(CollectedCsv(t),
            "id,scenario,seed,duration_s,result,exit_code,set:k,set:m,c,c.verdict,d,d.verdict\n"
            "a,x,1,2.5,pass,0,10,\"[1, 2]\",0.1,pass,nan,skip\n"
            "b,x,2,nan,fail,1,20,,0.5,fail,,\n");
  EXPECT_EQ(t.pass, 1);
  EXPECT_EQ(t.failed, 1);
  EXPECT_EQ(CollectRuns(dir.path(), true).Column("loop_wall_s"), 13);
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
  // resume: a missing run, an interrupted one and one without a record (an older
  // vlab's) are run again, the complete ones skipped
  fs::remove_all(dir / "out/p00_s2");
  std::string summary = ReadFile(dir / "out/p01_s1/summary.json");
  summary.replace(summary.find("\"result\": \"pass\""), 16, "\"result\": \"interrupted\"");
  WriteFile(dir / "out/p01_s1/summary.json", summary);
  nlohmann::json older = nlohmann::json::parse(ReadFile(dir / "out/p01_s2/summary.json"));
  older.erase("record");
  WriteFile(dir / "out/p01_s2/summary.json", older.dump(2));
  const auto resumed = RunVlab("sweep " + (dir / "s.yaml") + " -j 2 --out " + (dir / "out"));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.out << resumed.err;
  EXPECT_NE(resumed.out.find("4 runs, 1 complete already (skipped), 3 to run"), std::string::npos) << resumed.out;
  EXPECT_NE(resumed.out.find("p00_s2"), std::string::npos);
  EXPECT_NE(resumed.out.find("p01_s1"), std::string::npos);
  EXPECT_NE(resumed.out.find("  p01_s2 (controller.gains.position=40): runs again: it has no record of what it ran "
                             "(written by an older vlab)\n"),
            std::string::npos)
      << resumed.out;
  EXPECT_EQ(resumed.out.find("p00_s1 "), std::string::npos) << "a complete run is not run again";

  const auto collect = RunVlab("collect " + (dir / "out") + " --plot " + (dir / "g.png") +
                               " --x controller.gains.position --y position_tracking");
  ASSERT_EQ(collect.exit_code, 0) << collect.err;
  EXPECT_NE(collect.err.find("4 runs: 4 pass, 0 failed, 0 interrupted"), std::string::npos) << collect.err;
  const std::vector<std::string> rows = Lines(collect.out);
  ASSERT_EQ(rows.size(), 5u) << collect.out;
  const std::vector<std::string> header = SplitCsv(rows[0]);
  const auto col = [&](const std::string& name) {
    return std::find(header.begin(), header.end(), name) - header.begin();
  };
  ASSERT_LT(col("position_tracking"), static_cast<long>(header.size()));
  ASSERT_LT(col("loop_wall_s"), static_cast<long>(header.size()));
  // a stiffer task-space gain tracks closer: the table shows it per seed
  const std::vector<std::string> p00 = SplitCsv(rows[1]), p01 = SplitCsv(rows[3]);
  EXPECT_EQ(p00[col("set:controller.gains.position")], "10");
  EXPECT_EQ(p01[col("set:controller.gains.position")], "40");
  EXPECT_LT(std::stod(p01[col("position_tracking")]), std::stod(p00[col("position_tracking")]));
  EXPECT_GT(fs::file_size(dir / "g.png"), 1000u);
  EXPECT_EQ(vlab::testing::Entries(dir.path()).count("g.png.data-"), 0u);
  const auto bad =
      RunVlab("collect " + (dir / "out") + " --plot " + (dir / "h.png") + " --x nope --y position_tracking");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--x nope: no run overrides it"), std::string::npos) << bad.err;
}

// A scenario of a falling ball, 0.2 s: a sweep of six runs takes a few seconds.
void WriteTinyScenario(const TempDir& dir) {
  WriteFile(dir / "ball.xml",
            "<mujoco><worldbody><body pos='0 0 1'><freejoint/><geom size='0.1'/></body>"
            "</worldbody></mujoco>\n");
  WriteFile(dir / "tiny.yaml",
            "scene: ball.xml\nduration: 0.5\ncontrol_period: 0.01\n"
            "checks:\n  - {name: ran, signal: time, reduce: final, min: 0}\n");
}

std::string TinySweep(const std::string& duration, const std::string& mins) {
  return "name: t\nscenario: tiny.yaml\nduration: " + duration + "\nseeds: [1, 2]\ngrid: {checks.ran.min: " + mins +
         "}\n";
}

bool Has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// an edited sweep: a changed value, then a changed duration; only what changed
// runs again, says why, and the table shows the values the runs ran with
TEST(SweepCliTest, AnEditedSweepRunsAgainWhatChangedAndSaysWhy) {
  TempDir dir;
  WriteTinyScenario(dir);
  const std::string sweep = dir / "t.yaml";
  const std::string out = dir / "out";
  WriteFile(sweep, TinySweep("0.2", "[0, 0.05, 0.1]"));
  const auto first = RunVlab("sweep " + sweep + " -j 2 --out " + out);
  ASSERT_EQ(first.exit_code, 0) << first.out << first.err;
  EXPECT_TRUE(Has(first.out, "sweep t: 6 pass, 0 failed, 0 skipped")) << first.out;
  const nlohmann::json summary = nlohmann::json::parse(ReadFile(out + "/p02_s2/summary.json"));
  ASSERT_TRUE(summary.contains("record")) << summary.dump();
  EXPECT_EQ(summary["record"]["seed"], 2);
  EXPECT_EQ(summary["record"]["duration_s"], 0.2);
  EXPECT_TRUE(Has(summary["record"]["scenario"].get<std::string>(), "min: 0.1")) << summary["record"].dump();
  EXPECT_EQ(summary["record"]["hash"].get<std::string>().rfind("fnv1a64:", 0), 0u);

  // one value changed: its two runs are listed and run again, the other four kept
  WriteFile(sweep, TinySweep("0.2", "[0, 0.05, 0.15]"));
  const auto pending = RunVlab("sweep " + sweep + " --list --pending --out " + out);
  ASSERT_EQ(pending.exit_code, 0) << pending.err;
  const std::vector<std::string> jobs = Lines(pending.out);
  ASSERT_EQ(jobs.size(), 2u) << pending.out;
  EXPECT_TRUE(Has(jobs[0], "--set checks.ran.min=0.15 --out " + out + "/p02_s1 ")) << jobs[0];
  EXPECT_TRUE(Has(pending.err, "6 runs, 4 complete already (not listed), 2 listed")) << pending.err;
  const std::string seeds = ReadFile(out + "/p00_s1/summary.json");
  const auto resumed = RunVlab("sweep " + sweep + " -j 2 --out " + out);
  ASSERT_EQ(resumed.exit_code, 0) << resumed.out << resumed.err;
  EXPECT_TRUE(Has(resumed.out, "6 runs, 4 complete already (skipped), 2 to run")) << resumed.out;
  EXPECT_TRUE(Has(resumed.out, "p02_s1 (checks.ran.min=0.15): runs again: the scenario changed since it ran\n"))
      << resumed.out;
  EXPECT_TRUE(Has(resumed.out, "p02_s2 (checks.ran.min=0.15): runs again"));
  EXPECT_FALSE(Has(resumed.out, "p00_s1")) << "an unchanged run is not run again";
  EXPECT_EQ(ReadFile(out + "/p00_s1/summary.json"), seeds) << "an unchanged run's folder is kept";

  // the duration changed and the grid shrank: every run again, the old p02 named
  WriteFile(sweep, TinySweep("0.1", "[0, 0.08]"));
  const auto shorter = RunVlab("sweep " + sweep + " -j 2 --out " + out);
  ASSERT_EQ(shorter.exit_code, 0) << shorter.out << shorter.err;
  EXPECT_TRUE(Has(shorter.out, "4 runs, 0 complete already (skipped), 4 to run")) << shorter.out;
  EXPECT_TRUE(
      Has(shorter.out, "p00_s1 (checks.ran.min=0): runs again: the duration changed since it ran (0.2 s -> 0.1 s)\n"))
      << shorter.out;
  EXPECT_TRUE(Has(shorter.out,
                  "p01_s1 (checks.ran.min=0.08): runs again: the scenario changed since it ran; the "
                  "duration changed since it ran (0.2 s -> 0.1 s)"))
      << shorter.out;
  EXPECT_TRUE(Has(shorter.out, "p02_s1: not a run of this sweep (left as it is; vlab collect lists it)"))
      << shorter.out;

  fs::remove_all(out + "/p02_s1");
  fs::remove_all(out + "/p02_s2");
  const auto table = RunVlab("collect " + out + " --no-timings");
  ASSERT_EQ(table.exit_code, 0) << table.err;
  const std::vector<std::string> rows = Lines(table.out);
  ASSERT_EQ(rows.size(), 5u) << table.out;
  const std::vector<std::string> header = SplitCsv(rows[0]);
  const auto col = [&](const std::string& name) {
    return std::find(header.begin(), header.end(), name) - header.begin();
  };
  for (int i = 1; i <= 4; ++i) {
    const std::vector<std::string> row = SplitCsv(rows[i]);
    EXPECT_EQ(row[col("duration_s")], "0.1") << rows[i];
    EXPECT_EQ(row[col("set:checks.ran.min")], i <= 2 ? "0" : "0.08") << rows[i];
    EXPECT_EQ(row[col("ran")], "0.1") << rows[i];  // the final time: the runs ran 0.1 s
  }
}

}  // namespace
}  // namespace vlab::lab::sweep_test
