// vlab compare and vlab golden on the real binary: the shipped PA10 golden catches a
// planted 0.1 % change of one joint's damping and passes an unchanged run; --update
// writes a golden only when asked and says what changed.
#include <mujoco/mujoco.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <regex>

#include "test_util.h"

namespace vlab::golden_test {
namespace {

namespace fs = std::filesystem;
using testing::ReadFile;
using testing::RunVlab;
using testing::TempDir;
using testing::WriteFile;

const std::string kSource = VLAB_SOURCE_DIR;

// The servo's damping of PA10 joint S2 at the ready pose, as the arm device computes
// it (device_arm.h): kd = 2 zeta H_ii w, zeta 1, w = 2 pi 10 Hz (scenes/pa10_reach.yaml).
double ServoDampingS2(const std::string& scene) {
  char error[1000] = "";
  mjModel* m = mj_loadXML(scene.c_str(), nullptr, error, sizeof error);
  EXPECT_NE(m, nullptr) << error;
  if (!m) return 0;
  mjData* d = mj_makeData(m);
  const char* joints[] = {"S1", "S2", "S3", "E1", "E2", "W1", "W2"};
  const double ready[] = {0, 0.523599, 0, 1.047198, 0, 1.570796, 0};
  for (int i = 0; i < 7; ++i) d->qpos[m->jnt_qposadr[mj_name2id(m, mjOBJ_JOINT, joints[i])]] = ready[i];
  mj_forward(m, d);
  const int dof = m->jnt_dofadr[mj_name2id(m, mjOBJ_JOINT, "S2")];
  const double H = d->qM[m->dof_Madr[dof]];
  mj_deleteData(d);
  mj_deleteModel(m);
  return 2.0 * 1.0 * H * 2.0 * M_PI * 10.0;
}

TEST(GoldenTest, PlantedDampingChangeOfOneJointIsCaughtUnchangedRunPasses) {
  TempDir dir;
  // a copy of the scene with its relative layout: scenes/ and mjcf/pa10/
  fs::create_directories(dir / "scenes");
  fs::create_directories(dir / "mjcf");
  fs::copy(kSource + "/mjcf/pa10", dir / "mjcf/pa10", fs::copy_options::recursive);
  fs::copy(kSource + "/scenes/pa10.xml", dir / "scenes/pa10.xml");
  fs::copy(kSource + "/scenes/pa10_reach.yaml", dir / "scenes/pa10_reach.yaml");
  const double kd = ServoDampingS2(kSource + "/scenes/pa10.xml");
  ASSERT_GT(kd, 100.0);  // S2 carries the arm: H_22 of several kg m^2
  // passive damping 0.1 % of the servo's: the joint's total damping grows by 0.1 %
  const std::string arm_file = dir / "mjcf/pa10/pa10.xml";
  std::string arm = ReadFile(arm_file);
  const std::string joint = "<joint name=\"S2\" axis=\"0 1 0\" range=\"-94 94\" armature=\"0.75\"";
  ASSERT_NE(arm.find(joint), std::string::npos) << "the S2 joint line changed: update this test";
  char damping[64];
  std::snprintf(damping, sizeof damping, " damping=\"%.9g\"", 0.001 * kd);
  arm.replace(arm.find(joint), joint.size(), joint + damping);
  WriteFile(arm_file, arm);

  const auto planted = RunVlab("run " + (dir / "scenes/pa10_reach") + " -q --out " + (dir / "planted"));
  ASSERT_EQ(planted.exit_code, 0) << planted.err;  // its own checks cannot see 0.1 %
  const auto caught = RunVlab("compare " + (dir / "planted") + " tests/goldens/pa10_reach");
  EXPECT_EQ(caught.exit_code, 1) << caught.out << caught.err;
  EXPECT_NE(caught.out.find("FAIL pa10.q.S2 (abs 1e-09)"), std::string::npos) << caught.out;
  EXPECT_NE(caught.out.find("FAIL pa10.tau.S2"), std::string::npos) << caught.out;
  EXPECT_NE(caught.out.find("result: FAIL"), std::string::npos) << caught.out;
  // the worst divergence of S2 is far outside the tolerance (measured 1.2e-6 rad: 1000x)
  const std::regex worst(R"(FAIL pa10\.q\.S2[^\n]*\n[^\n]*\n +worst [^\n]*, ([0-9.e+]+)x the tolerance)");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(caught.out, m, worst)) << caught.out;
  EXPECT_GT(std::stod(m[1]), 100.0) << caught.out;

  const auto unchanged = RunVlab("run scenes/pa10_reach -q --out " + (dir / "unchanged"));
  ASSERT_EQ(unchanged.exit_code, 0) << unchanged.err;
  const auto passes = RunVlab("compare " + (dir / "unchanged") + " tests/goldens/pa10_reach");
  EXPECT_EQ(passes.exit_code, 0) << passes.out << passes.err;
  EXPECT_NE(passes.out.find("result: pass (37 columns within tolerance)"), std::string::npos) << passes.out;
}

TEST(GoldenTest, CompareOptionsAndBadInput) {
  TempDir dir;
  ASSERT_EQ(RunVlab("run scenes/pa10_reach -q --duration 1 --out " + (dir / "a")).exit_code, 0);
  ASSERT_EQ(
      RunVlab("run scenes/pa10_reach -q --duration 1 --out " + (dir / "b") + " --set controller.gains.position=19")
          .exit_code,
      0);
  // different gains: positions differ; --ignore and a loose --tol make it pass
  EXPECT_EQ(RunVlab("compare " + (dir / "b") + " " + (dir / "a")).exit_code, 1);
  EXPECT_EQ(RunVlab("compare " + (dir / "b") + " " + (dir / "a") + " --tol '*=1e6'").exit_code, 0);
  // a window before the controller moves (it holds until 0.5 s): identical
  EXPECT_EQ(RunVlab("compare " + (dir / "b") + " " + (dir / "a") + " --to 0.5").exit_code, 0);
  // the golden longer than the run: fails, saying so
  ASSERT_EQ(RunVlab("run scenes/pa10_reach -q --duration 2 --out " + (dir / "long")).exit_code, 0);
  const auto short_run = RunVlab("compare " + (dir / "a") + " " + (dir / "long"));
  EXPECT_EQ(short_run.exit_code, 1);
  EXPECT_NE(short_run.out.find("the run's log covers t = 0 .. 1 s, the golden's window is 0 .. 2 s"), std::string::npos)
      << short_run.out;
  const auto bad = RunVlab("compare " + (dir / "a") + " " + (dir / "a") + " --tol 'q.*=abc'");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--tol q.*=abc: ABS: expected a number >= 0, got 'abc'"), std::string::npos) << bad.err;
  EXPECT_EQ(RunVlab("compare " + (dir / "a") + " " + (dir / "none")).exit_code, 2);
}

TEST(GoldenTest, UpdateWritesOnlyWhenAskedAndSaysWhatChanged) {
  TempDir dir;
  const std::string golden = dir / "g";
  fs::create_directories(golden);
  WriteFile(golden + "/golden.yaml", "scenario: " + kSource +
                                         "/scenes/pa10_reach.yaml\nduration: 1\nevery: 50\n"
                                         "tolerances: [{columns: 'jr3.*', ignore: true}]\n");
  // no golden log yet: checking says how to write one, and writes nothing
  const auto none = RunVlab("golden " + golden);
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.err.find("no golden log yet (write it: vlab golden --update"), std::string::npos) << none.err;
  EXPECT_FALSE(fs::exists(golden + "/log.csv"));

  const auto created = RunVlab("golden --update " + golden);
  ASSERT_EQ(created.exit_code, 0) << created.out << created.err;
  EXPECT_NE(created.out.find("new golden"), std::string::npos) << created.out;
  const std::string log = ReadFile(golden + "/log.csv");
  EXPECT_EQ(testing::Lines(log).size(), 1u + 11u) << "header and rows 0, 50, ..., 500 of a 1 s run at 2 ms";
  EXPECT_EQ(RunVlab("golden " + golden).exit_code, 0);

  // a golden that no longer matches: checking fails; --update prints the change and rewrites it
  std::string changed = log;
  const std::size_t row = changed.find("\n0.1,");
  ASSERT_NE(row, std::string::npos) << log.substr(0, 300);
  const std::size_t comma = changed.find(',', row + 5);
  changed.insert(comma, "1");  // pa10.q.S1 at t = 0.1 s: another value
  WriteFile(golden + "/log.csv", changed);
  const auto check = RunVlab("golden " + golden);
  EXPECT_EQ(check.exit_code, 1) << check.out;
  EXPECT_NE(check.out.find("FAIL pa10.q.S1"), std::string::npos) << check.out;
  EXPECT_EQ(ReadFile(golden + "/log.csv"), changed) << "checking never writes";
  const auto update = RunVlab("golden --update " + golden);
  EXPECT_EQ(update.exit_code, 0) << update.out << update.err;
  EXPECT_NE(update.out.find("NOT within the golden's tolerances"), std::string::npos) << update.out;
  EXPECT_NE(update.out.find("FAIL pa10.q.S1 (exact): 1 of 11 rows out"), std::string::npos) << update.out;
  EXPECT_EQ(ReadFile(golden + "/log.csv"), log);
}

// a scenario's golden check: the run's log against a golden, the report beside it
TEST(GoldenTest, ScenarioGoldenCheckPassesFailsAndSkipsLikeAnyCheck) {
  TempDir dir;
  std::string scenario = ReadFile(kSource + "/scenes/pa10_reach.yaml");
  scenario.replace(scenario.find("scene: pa10.xml"), 15, "scene: " + kSource + "/scenes/pa10.xml");
  scenario.replace(scenario.find("\nchecks:\n"), 9,
                   "\nchecks:\n  - {name: matches, golden: " + kSource + "/tests/goldens/pa10_reach, from: 0.5}\n");
  WriteFile(dir / "s.yaml", scenario);
  const auto same = RunVlab("run " + (dir / "s.yaml") + " --out " + (dir / "same"));
  EXPECT_EQ(same.exit_code, 0) << same.out << same.err;
  EXPECT_NE(same.out.find("pass  matches"), std::string::npos) << same.out;
  EXPECT_NE(ReadFile(dir / "same/golden_matches.txt").find("result: pass (37 columns"), std::string::npos);
  // other gains: the scenario's own checks still pass, the golden check does not
  const auto other =
      RunVlab("run " + (dir / "s.yaml") + " --out " + (dir / "other") + " --set controller.gains.position=19");
  EXPECT_EQ(other.exit_code, 1) << other.out << other.err;
  EXPECT_NE(other.out.find("FAIL  matches"), std::string::npos) << other.out;
  EXPECT_NE(other.out.find("pass  position_tracking"), std::string::npos) << other.out;
  EXPECT_NE(other.err.find("check 'matches' failed: log.csv diverges from the golden"), std::string::npos) << other.err;
  EXPECT_NE(ReadFile(dir / "other/golden_matches.txt").find("FAIL pa10.q.S1"), std::string::npos);
  // a shortened run is compared over what it reached; one that ends before `from` skips it
  EXPECT_EQ(RunVlab("run " + (dir / "s.yaml") + " -q --duration 3 --out " + (dir / "short")).exit_code, 0);
  const auto early = RunVlab("run " + (dir / "s.yaml") + " --duration 0.2 --out " + (dir / "early"));
  EXPECT_NE(early.out.find("skip  matches"), std::string::npos) << early.out;
  // bad input: a golden that is not there, a golden check without a log
  const std::string missing = dir / "missing.yaml";
  std::string bad = scenario;
  bad.replace(bad.find("tests/goldens/pa10_reach"), 24, "tests/goldens/nope");
  WriteFile(missing, bad);
  const auto no_golden = RunVlab("run " + missing + " --out " + (dir / "x"));
  EXPECT_EQ(no_golden.exit_code, 2);
  EXPECT_NE(no_golden.err.find("checks[0].golden: no such golden folder or log"), std::string::npos) << no_golden.err;
  const auto no_log = RunVlab("run " + (dir / "s.yaml") + " --set outputs.log=false --out " + (dir / "y"));
  EXPECT_EQ(no_log.exit_code, 2);
  EXPECT_NE(no_log.err.find("a golden check compares log.csv: it needs outputs.log: true"), std::string::npos)
      << no_log.err;
}

}  // namespace
}  // namespace vlab::golden_test
