// vlab identify from the command line: its output folder (estimates, the patched scene and
// the overrides that run it, fit.csv, plots, report) and its exit codes.
#include <string>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <nlohmann/json.hpp>

#include "core/core_mujoco.h"
#include "identify/identify_output.h"
#include "identify/identify_problem.h"
#include "identify_test_plant.h"
#include "test_util.h"

namespace vlab::identify::cli_test {
namespace {

using vlab::testing::ReadFile;
using vlab::testing::RunVlab;
using vlab::testing::TempDir;
using vlab::testing::WriteFile;

// link 4 planted 7 % light, fitted from 3 s of pa10_joint_pd; the base's mass cannot be told
TEST(IdentifyCli, WritesEstimatesAPatchedSceneAndOverridesThatRunIt) {
  TempDir tmp;
  WriteEditedScene(
      testing::kScene, [](mjModel* m) { ScaleBodyMass(m, "pa10_link4", 0.93); }, tmp / "truth.xml");
  WriteNoisyLog(testing::RunLab(tmp / "truth.xml", tmp / "real", 3.0), tmp / "noisy.csv", ".q.", 1e-5, 5);
  WriteFile(tmp / "id.yaml", "scenario: " + testing::kScenario + "\nset: [\"checks=[]\"]\nlogs: [noisy.csv]\n" +
                                 "columns: [{name: pa10.q.*, weight: 1.0e5}]\nparameters:\n"
                                 "  - {name: m4, target: body pa10_link4 mass, lower: 1, upper: 8}\n"
                                 "  - {name: m0, target: body pa10_base mass, lower: 1, upper: 8}\n");
  const auto r = RunVlab("identify '" + (tmp / "id.yaml") + "' --out '" + (tmp / "fit") + "' --threads 2 -q");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("m4 "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("NOT identifiable: not excited"), std::string::npos) << r.out;
  const nlohmann::json j = nlohmann::json::parse(ReadFile(tmp / "fit/estimates.json"));
  const double truth = 4.31 * 0.93;
  const nlohmann::json& m4 = j["parameters"][0];
  EXPECT_EQ(m4["name"], "m4");
  EXPECT_EQ(m4["target"], "body pa10_link4 mass");
  EXPECT_NEAR(m4["value"].get<double>(), truth, 0.002 * truth);
  EXPECT_TRUE(m4["identifiable"].get<bool>());
  // the fit started from the linear estimate, which found link 4's mass (not the base's: no
  // joint moves it, its torque column is zero)
  EXPECT_EQ(j["first_estimate"], "linear");
  EXPECT_NEAR(m4["linear"].get<double>(), truth, 0.01 * truth);
  EXPECT_TRUE(j["parameters"][1]["linear"].is_null());
  EXPECT_NE(r.out.find("first estimate linear"), std::string::npos) << r.out;
  EXPECT_TRUE(j["parameters"][1]["sd"].is_null());
  EXPECT_FALSE(j["parameters"][1]["excited"].get<bool>());
  EXPECT_EQ(j["correlation"]["names"].size(), 2u);
  // the patched scene holds the fitted mass, its inertia scaled with it (MuJoCo 2.2.2 writes
  // 6 significant digits)
  const ModelPtr fitted = LoadModel(tmp / "fit/model.xml");
  const ModelPtr nominal = LoadModel(testing::kScene);
  const int b = testing::Body(fitted.get(), "pa10_link4");
  EXPECT_NEAR(fitted->body_mass[b], m4["value"].get<double>(), 1e-5 * truth);
  EXPECT_NEAR(fitted->body_inertia[3 * b] / nominal->body_inertia[3 * b], fitted->body_mass[b] / 4.31, 1e-5);
  EXPECT_EQ(fitted->nv, nominal->nv);
  // the overrides run the scenario on it
  const std::string overrides = ReadFile(tmp / "fit/overrides.txt");
  EXPECT_NE(overrides.find("scene=" + (tmp / "fit/model.xml")), std::string::npos) << overrides;
  const auto run = RunVlab("run scenes/pa10_joint_pd --duration 0.1 -q --overrides '" + (tmp / "fit/overrides.txt") +
                           "' --out '" + (tmp / "rerun") + "'");
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  const nlohmann::json summary = nlohmann::json::parse(ReadFile(tmp / "rerun/summary.json"));
  EXPECT_EQ(summary["overrides"]["scene"], tmp / "fit/model.xml");
  // the fit's columns, plotted and reported
  const std::string csv = ReadFile(tmp / "fit/fit.csv");
  EXPECT_EQ(csv.rfind("time,log,pa10.q.S1.measured,pa10.q.S1.nominal,pa10.q.S1.fitted,", 0), 0u);
  for (const char* file : {"fit_pa10.q.S1.png", "fit_pa10.q.W2.png", "report.md"}) {
    EXPECT_TRUE(std::filesystem::exists(tmp / ("fit/" + std::string(file)))) << file;
  }
  EXPECT_NE(ReadFile(tmp / "fit/report.md").find("| m4 | body pa10_link4 mass |"), std::string::npos);
}

// a payload on the tool fitted with the JR3's columns: model.xml holds it in the tool's body,
// overrides.txt says what it is and how the arm's scenario declares it
TEST(IdentifyCli, WritesAPayloadAndTheJr3Columns) {
  TempDir tmp;
  const double own[3] = {0, 0, 0.05};
  WriteEditedScene(
      testing::kScene,
      [&](mjModel* m) {
        const int b = testing::Body(m, "tool_body");
        AddPointMass(0.3, own, &m->body_mass[b], m->body_ipos + 3 * b, m->body_inertia + 3 * b, m->body_iquat + 4 * b);
      },
      tmp / "truth.xml");
  testing::RunLab(tmp / "truth.xml", tmp / "real", 2.0, {"devices.jr3.filter=3", "devices.jr3.noise=false"});
  WriteFile(tmp / "id.yaml", "scenario: " + testing::kScenario +
                                 "\nset: [\"checks=[]\", \"devices.jr3.filter=3\"]\nlogs: [real]\n" +
                                 "columns: [{name: pa10.q.*, weight: 1.0e5}, {name: jr3.F*, weight: 50}]\n"
                                 "parameters:\n"
                                 "  - {name: pm, target: payload tool_body mass, nominal: 0.1, lower: 0, upper: 2}\n"
                                 "  - {name: pz, target: payload tool_body com_z, lower: -0.2, upper: 0.2}\n"
                                 "  - {name: bz, target: column jr3.Fz bias, lower: -1, upper: 1}\n");
  const auto r = RunVlab("identify '" + (tmp / "id.yaml") + "' --out '" + (tmp / "fit") + "' --threads 2 -q");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const nlohmann::json j = nlohmann::json::parse(ReadFile(tmp / "fit/estimates.json"));
  EXPECT_EQ(j["parameters"][0]["target"], "payload tool_body mass");
  EXPECT_EQ(j["parameters"][1]["target"], "payload tool_body com_z");
  const double pm = j["parameters"][0]["value"].get<double>(), pz = j["parameters"][1]["value"].get<double>();
  EXPECT_NEAR(pm, 0.3, 0.003);
  EXPECT_NEAR(pz, 0.05, 0.001);
  EXPECT_GT(j["wrench_settle_rows"].get<int>(), 0);
  const ModelPtr fitted = LoadModel(tmp / "fit/model.xml");
  const ModelPtr nominal = LoadModel(testing::kScene);
  const int b = testing::Body(fitted.get(), "tool_body");
  EXPECT_NEAR(fitted->body_mass[b], nominal->body_mass[b] + pm, 1e-5);
  const std::string overrides = ReadFile(tmp / "fit/overrides.txt");
  EXPECT_NE(overrides.find("# payload on body tool_body"), std::string::npos) << overrides;
  // the flange frame (pa10_link7, W2's body) is 25 mm above tool_body's, axes alike
  EXPECT_NE(overrides.find("W2 (the flange frame, body pa10_link7), its scenario's payload: {mass: "),
            std::string::npos)
      << overrides;
  const std::string csv = ReadFile(tmp / "fit/fit.csv");
  EXPECT_NE(csv.find("jr3.Fz.measured"), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(tmp / "fit/fit_jr3.Fz.png"));
}

TEST(IdentifyCli, BadInputIsExitTwoNamingTheField) {
  TempDir tmp;
  WriteFile(tmp / "id.yaml", "scenario: " + testing::kScenario + "\nlogs: [x.csv]\ncolumns: [{name: pa10.q.*}]\n" +
                                 "parameters: [{name: a, target: body pa10_link4 mas, lower: 1, upper: 2}]\n");
  const auto r = RunVlab("identify '" + (tmp / "id.yaml") + "' --out '" + (tmp / "fit") + "'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("id.yaml:4: parameters[0].target: 'body pa10_link4 mas' is none of"), std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(tmp / "fit"));
  // an overrides file's bad line, named by file and line
  WriteFile(tmp / "overrides.txt", "# comment\n\nduration=0.1\nnokey\n");
  const auto run = RunVlab("run scenes/pa10_joint_pd -q --overrides '" + (tmp / "overrides.txt") + "' --out '" +
                           (tmp / "run") + "'");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("overrides.txt:4: --set 'nokey': expected KEY=VALUE"), std::string::npos) << run.err;
  const auto missing = RunVlab("identify '" + (tmp / "none.yaml") + "'");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find("none.yaml"), std::string::npos) << missing.err;
}

}  // namespace
}  // namespace vlab::identify::cli_test
