// vlab excite (src/cli/cli_excite.cc) end to end: the real executable writes the task, the
// scenario and the record; the same seed writes the same bytes; the scenario runs in the lab
// and the arm's logged joint speeds and positions stay within their limits; bad input is
// refused with exit 2 and nothing written.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "kinsim/kinsim_process.h"
#include "test_util.h"

namespace vlab::cli {
namespace {

using testing::ProcessResult;
using testing::ReadFile;
using testing::RunVlab;
using testing::TempDir;

#define EXPECT_HAS(text, part) EXPECT_NE((text).find(part), std::string::npos) << (text)

constexpr double kPi = 3.14159265358979323846;
// short: a 4 s period, one cycle, 200 evaluations (a few seconds)
const std::string kShort = "excite scenes/pa10_task_hello.yaml --period 4 --cycles 1 --evaluations 200 ";

TEST(CliExciteTest, WritesTheTaskScenarioAndRecordAndPrintsTheConditionNumber) {
  TempDir tmp;
  const ProcessResult r = RunVlab(kShort + "--out " + (tmp / "a"));
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_HAS(r.out, "regressor: 91 parameters, 62 base parameters");
  double before = 0, after = 0;
  const std::size_t at = r.out.find("condition number: ");
  ASSERT_NE(at, std::string::npos) << r.out;
  ASSERT_EQ(
      std::sscanf(r.out.c_str() + at, "condition number: %lf (initial guess) -> %lf (optimised)", &before, &after), 2)
      << r.out;
  EXPECT_LT(after, before);
  const nlohmann::json j = nlohmann::json::parse(ReadFile(tmp / "a/excite.json"));
  EXPECT_NEAR(j["condition_number"]["optimised"].get<double>(), after, 1e-3 * after);
  EXPECT_EQ(j["joints"].size(), 7u);
  EXPECT_EQ(j["a_rad_per_s"].size(), 7u);
  EXPECT_EQ(j["a_rad_per_s"][0].size(), 5u);
  // every peak within its limit (the record's own numbers)
  const auto& l = j["limits"];
  const auto& p = j["peaks"];
  for (int i = 0; i < 7; ++i) {
    EXPECT_LE(p["speed_rad_per_s"][i].get<double>(), l["speed_rad_per_s"][i].get<double>()) << i;
    EXPECT_LE(p["acceleration_rad_per_s2"][i].get<double>(), l["acceleration_rad_per_s2"][i].get<double>()) << i;
    EXPECT_LE(p["q_max_rad"][i].get<double>(), l["upper_rad"][i].get<double>()) << i;
    EXPECT_GE(p["q_min_rad"][i].get<double>(), l["lower_rad"][i].get<double>()) << i;
  }
  EXPECT_HAS(ReadFile(tmp / "a/excite.lua"), "servoj(q)");
  EXPECT_HAS(ReadFile(tmp / "a/excite.yaml"), "script: excite.lua");
}

TEST(CliExciteTest, SameSeedSameBytes) {
  TempDir tmp;
  for (const char* dir : {"a", "b"}) ASSERT_EQ(RunVlab(kShort + "--seed 3 --out " + (tmp / dir)).exit_code, 0);
  ASSERT_EQ(RunVlab(kShort + "--seed 4 --out " + (tmp / "c")).exit_code, 0);
  for (const char* file : {"excite.lua", "excite.yaml", "excite.json"}) {
    EXPECT_EQ(ReadFile(tmp / "a/" + file), ReadFile(tmp / "b/" + file)) << file;
  }
  EXPECT_NE(ReadFile(tmp / "a/excite.lua"), ReadFile(tmp / "c/excite.lua"));
}

TEST(CliExciteTest, TheScenarioRunsInTheLabWithinTheLimits) {
  TempDir tmp;
  ASSERT_EQ(RunVlab(kShort + "--out " + (tmp / "e")).exit_code, 0);
  const ProcessResult run = RunVlab("run " + (tmp / "e/excite.yaml") + " --out " + (tmp / "run"));
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_HAS(run.out, "pass  program_ended");
  EXPECT_HAS(run.out, "pass  speed_W1");
  // the log, read here: every joint speed within 180 deg/s, and the arm moved
  const std::vector<std::string> lines = testing::Lines(ReadFile(tmp / "run/log.csv"));
  ASSERT_GT(lines.size(), 2000u);
  const std::vector<std::string> header = testing::SplitCsv(lines[0]);
  std::vector<int> speed;
  for (std::size_t c = 0; c < header.size(); ++c) {
    if (header[c].rfind("pa10.qd.", 0) == 0) speed.push_back(static_cast<int>(c));
  }
  ASSERT_EQ(speed.size(), 7u);
  double fastest = 0;
  for (std::size_t k = 1; k < lines.size(); ++k) {
    const std::vector<std::string> row = testing::SplitCsv(lines[k]);
    for (int c : speed) fastest = std::max(fastest, std::abs(std::stod(row[c])));
  }
  EXPECT_LT(fastest, kPi);
  EXPECT_GT(fastest, 0.2);
}

TEST(CliExciteTest, TheTaskRunsUnchangedAgainstAnArmOverTheWire) {
  // vlab-kinsim stands in for the real arm (realtime, 500 Hz), away from the start pose: the
  // task moves there, streams its period and ends (vlab task exit 0: no reference refused)
  TempDir tmp;
  ASSERT_EQ(RunVlab("excite scenes/pa10_task_hello.yaml --period 2 --cycles 1 --evaluations 100 --out " + (tmp / "e"))
                .exit_code,
            0);
  testing::KinsimProcess kinsim({"--initial", "0", "0", "0", "0.5", "0", "1.0", "0"});
  ASSERT_TRUE(kinsim.ok());
  const ProcessResult r =
      RunVlab("task " + (tmp / "e/excite.lua") + " --arm 127.0.0.1:" + std::to_string(kinsim.port()) +
              " --scene scenes/pa10.xml --tip tool");
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_HAS(r.out, "excitation: 1 periods of 2 s");
  EXPECT_HAS(r.out, "excitation: done");
}

TEST(CliExciteTest, RefusesBadInputAndWritesNothing) {
  TempDir tmp;
  const auto refused = [&](const std::string& args, const std::string& message) {
    const ProcessResult r = RunVlab(args + " --out " + (tmp / "x"));
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.out << r.err;
    EXPECT_HAS(r.err, message);
    EXPECT_FALSE(std::filesystem::exists(tmp / "x")) << args;
    for (const std::string& entry : testing::Entries(tmp.path())) EXPECT_NE(entry.rfind(".vlab-", 0), 0u) << entry;
  };
  refused("excite scenes/pa10_task_hello.yaml --arm nope",
          "--arm nope: scenario 'scenes/pa10_task_hello.yaml' has no arm device named 'nope' (arms: pa10)");
  refused("excite scenes/pa10_task_hello.yaml --harmonics 1", "--harmonics must be 2 ... 50");
  refused("excite scenes/pa10_task_hello.yaml --period 0.003", "--period 0.003 s is not a whole number");
  refused("excite scenes/pa10_task_hello.yaml --cycles 0", "--cycles must be 1 ... 1000");
  refused("excite scenes/pa10_task_hello.yaml --seed -1", "--seed must be >= 0");
  refused("excite scenes/pa10_task_hello.yaml --tip nosite", "the task's chain (--base world, --tip nosite)");
  refused("excite scenes/pa10_nomad_reach.yaml",
          "the chain from body 'world' to site 'tool' is not the joints of arm 'pa10' in order: give --base and --tip");
  testing::WriteFile(tmp / "noarm.yaml", "scene: " VLAB_SOURCE_DIR "/scenes/pa10.xml\nduration: 1\n");
  refused("excite " + (tmp / "noarm.yaml"), "has no arm device (kind: arm)");
  // a start pose within the margin of a joint's limit (S2 at 92 of 94 deg)
  testing::WriteFile(tmp / "edge.yaml", "scene: " VLAB_SOURCE_DIR
                                        "/scenes/pa10.xml\nduration: 1\ndevices:\n"
                                        "  - {name: pa10, kind: arm, joints: [S1, S2, S3, E1, E2, W1, W2],\n"
                                        "     initial: [0, 1.6057, 0, 1.047198, 0, 1.570796, 0]}\n");
  refused("excite " + (tmp / "edge.yaml"),
          "arm 'pa10': excitation: joint S2 starts at 91.9998 deg, not inside its range -94 .. 94 deg less the margin "
          "5 deg");
  // a folder vlab did not write is never replaced
  std::filesystem::create_directories(tmp / "mine");
  testing::WriteFile(tmp / "mine/notes.txt", "keep");
  const ProcessResult r = RunVlab(kShort + "--out " + (tmp / "mine"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_HAS(r.err, "is not an output folder of vlab's");
  EXPECT_EQ(ReadFile(tmp / "mine/notes.txt"), "keep");
}

}  // namespace
}  // namespace vlab::cli
