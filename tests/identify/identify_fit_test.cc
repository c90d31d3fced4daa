// vlab identify's fit: planted parameters recovered from logs the lab makes in-test.
#include <charconv>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "identify/identify_fit.h"
#include "identify/identify_output.h"
#include "identify/identify_problem.h"
#include "identify/identify_spec.h"
#include "identify_test_plant.h"
#include "scene/scene_csv.h"
#include "test_util.h"

namespace vlab::identify {
namespace {

using testing::RunLab;
using vlab::testing::TempDir;
using vlab::testing::WriteFile;

// a spec over pa10_joint_pd on `scene`, fitting `columns` with `parameters` (YAML list items)
std::string SpecText(const std::string& scene, const std::string& log, const std::string& columns,
                     const std::string& parameters, double window = 0.2) {
  return "scenario: " + testing::kScenario + "\nset: [\"scene=" + scene + "\", \"checks=[]\"]\nlogs: [" + log +
         "]\nwindow: " + std::to_string(window) + "\ncolumns:\n" + columns + "parameters:\n" + parameters;
}

// The replay's conventions (a row's torque acts over the period that ends at it; the window
// starts from its first row's state) reproduce the lab's own run: the nominal model's
// residuals on its own log are at rounding level.
TEST(IdentifyFit, ReplayOfTheTrueModelReproducesTheLog) {
  TempDir tmp;
  const std::string log = RunLab(testing::kScene, tmp / "run", 3.0);
  WriteFile(tmp / "id.yaml", SpecText(testing::kScene, log, "  - {name: \"pa10.q*\"}\n",
                                      "  - {name: m2, target: body pa10_link2 mass, lower: 1, upper: 20}\n") +
                                 "start_smoothing: 0\n");
  const std::unique_ptr<Problem> problem = Problem::Create(LoadSpec(tmp / "id.yaml"));
  ASSERT_EQ(problem->columns().size(), 14u);  // pa10.q.* and pa10.qd.*
  Workspace ws = problem->MakeWorkspace();
  double worst = 0;
  for (int w = 0; w < problem->window_count(); ++w) {
    std::vector<double> r(problem->window_residuals(w));
    ASSERT_TRUE(problem->Rollout(w, {problem->parameters()[0].nominal}, ws, r.data(), nullptr));
    for (double x : r) worst = std::max(worst, std::abs(x));
  }
  EXPECT_EQ(problem->window_count(), 15);  // 1500 periods in 0.2 s windows of 100
  EXPECT_LT(worst, 1e-9);
  // a planted change shows: 10 % more mass moves the joints by far more than that
  std::vector<double> r(problem->window_residuals(5));
  ASSERT_TRUE(problem->Rollout(5, {problem->parameters()[0].nominal * 1.1}, ws, r.data(), nullptr));
  double moved = 0;
  for (double x : r) moved = std::max(moved, std::abs(x));
  EXPECT_GT(moved, 1e-5);
}

// the planted parameters: nominal model (the shipped PA10 with damping on S2 and friction
// loss on E1, which the data sheet leaves at 0) and the "real" arm's changes to it
struct Planted {
  const char* name;
  const char* target;
  double nominal, truth, lower, upper;
};
const std::vector<Planted> kPlanted = {
    {"m3", "body pa10_link3 mass", 3.52, 3.52 * 1.10, 1, 8},  {"m4", "body pa10_link4 mass", 4.31, 4.31 * 0.93, 1, 8},
    {"d_s2", "joint S2 damping", 3.0, 3.0 * 1.5, 0, 20},      {"a_s1", "joint S1 armature", 0.75, 0.75 * 1.15, 0, 5},
    {"f_e1", "joint E1 frictionloss", 1.0, 1.0 * 1.2, 0, 10},
};

void EditNominal(mjModel* m) {
  m->dof_damping[testing::Dof(m, "S2")] = 3.0;
  m->dof_frictionloss[testing::Dof(m, "E1")] = 1.0;
}

void EditTruth(mjModel* m) {
  EditNominal(m);
  ScaleBodyMass(m, "pa10_link3", 1.10);
  ScaleBodyMass(m, "pa10_link4", 0.93);
  m->dof_damping[testing::Dof(m, "S2")] *= 1.5;
  m->dof_armature[testing::Dof(m, "S1")] *= 1.15;
  m->dof_frictionloss[testing::Dof(m, "E1")] *= 1.2;
}

// Planted link masses (+10 %, -7 %), damping x1.5, armature +15 % and friction loss +20 %,
// fitted from the nominal model to 10 s of the lab's log with encoder noise (sd 1e-5 rad):
// each within 2 % and within 3 sd of the truth; the base's mass, which no joint moves,
// reported as not excited and left at its nominal value.
TEST(IdentifyFit, RecoversPlantedParameters) {
  TempDir tmp;
  WriteEditedScene(testing::kScene, EditNominal, tmp / "nominal.xml");
  WriteEditedScene(testing::kScene, EditTruth, tmp / "truth.xml");
  const std::string clean = RunLab(tmp / "truth.xml", tmp / "real", 10.0);
  constexpr double kSigma = 1e-5;  // rad, about the PA10's encoder count (7.67e-6 rad)
  WriteNoisyLog(clean, tmp / "noisy.csv", ".q.", kSigma, 7);
  std::string params;
  for (const Planted& p : kPlanted) {
    params += std::string("  - {name: ") + p.name + ", target: " + p.target + ", lower: " + std::to_string(p.lower) +
              ", upper: " + std::to_string(p.upper) + "}\n";
  }
  params += "  - {name: m_base, target: body pa10_base mass, lower: 1, upper: 10}\n";
  WriteFile(tmp / "id.yaml",
            SpecText(tmp / "nominal.xml", tmp / "noisy.csv", "  - {name: pa10.q.*, weight: 1.0e5}\n", params));
  const std::unique_ptr<Problem> problem = Problem::Create(LoadSpec(tmp / "id.yaml"));
  FitOptions options;
  options.threads = 2;
  const auto start = std::chrono::steady_clock::now();
  const FitResult fit = Fit(*problem, options);
  std::printf("fit: %d iterations, %d rollouts, %.2f s, cost %.4g -> %.4g, residual sd %.3f\n", fit.iterations,
              fit.rollouts, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
              fit.cost_nominal, fit.cost_fitted, fit.residual_sd);
  for (std::size_t i = 0; i < kPlanted.size(); ++i) {
    const Estimate& e = fit.estimates[i];
    const double truth = kPlanted[i].truth;
    std::printf("%-6s nominal %.6g truth %.6g fitted %.6g sd %.3g (%.2f sd off; sd_iid %.3g) %s\n", e.name.c_str(),
                e.nominal, truth, e.value, e.sd, std::abs(e.value - truth) / e.sd, e.sd_iid, e.note.c_str());
    EXPECT_EQ(e.nominal, kPlanted[i].nominal) << e.name;
    EXPECT_TRUE(e.identifiable) << e.name << ": " << e.note;
    EXPECT_LT(std::abs(e.value - truth), 0.02 * truth) << e.name;
    EXPECT_LT(std::abs(e.value - truth), 3 * e.sd) << e.name;
  }
  const Estimate& base = fit.estimates.back();
  EXPECT_FALSE(base.excited);
  EXPECT_FALSE(base.identifiable);
  EXPECT_EQ(base.value, base.nominal);
  EXPECT_FALSE(std::isfinite(base.sd));
  // the weights are 1/sigma: the fitted residuals are the noise, sd about 1
  EXPECT_NEAR(fit.residual_sd, 1.0, 0.1);

  // held out: another path through other poses, run by the lab on the truth, the fitted and
  // the nominal model; the fitted one's joints follow the truth's within the noise level
  const std::unique_ptr<Problem> all = Problem::Create(LoadSpec(tmp / "id.yaml"));
  WriteEditedScene(
      tmp / "nominal.xml", [&](mjModel* m) { SetModelParameters(*all, fit.fitted_values, m); }, tmp / "fitted.xml");
  const std::vector<std::string> path = {"controller.waypoints.0.q=[0.3, 0.5, -0.2, 1.2, 0.3, 1.4, 0.5]",
                                         "controller.waypoints.1.q=[-0.3, 0.6, 0.4, 0.8, -0.5, 1.3, -0.6]"};
  auto joints = [&](const std::string& scene, const std::string& name) {
    return scene::ReadCsvTable(RunLab(scene, tmp / name, 10.0, path));
  };
  const scene::CsvTable truth = joints(tmp / "truth.xml", "h_truth"), fitted = joints(tmp / "fitted.xml", "h_fitted"),
                        nominal = joints(tmp / "nominal.xml", "h_nominal");
  double worst_fitted = 0, worst_nominal = 0;
  for (const char* j : {"S1", "S2", "S3", "E1", "E2", "W1", "W2"}) {
    const int c = truth.Column(std::string("pa10.q.") + j);
    for (std::size_t r = 0; r < truth.rows.size(); ++r) {
      worst_fitted = std::max(worst_fitted, std::abs(fitted.rows[r][c] - truth.rows[r][c]));
      worst_nominal = std::max(worst_nominal, std::abs(nominal.rows[r][c] - truth.rows[r][c]));
    }
  }
  std::printf("held out: largest joint difference to the truth: fitted %.3g rad, nominal %.3g rad\n", worst_fitted,
              worst_nominal);
  EXPECT_LT(worst_fitted, 2 * kSigma);
  EXPECT_GT(worst_nominal, 10 * kSigma);
}

// A sensor's bias, gain and delay: the log's S2 angle reads 2 mrad high, its E1 angle 2 %
// large, its S1 angle one period (2 ms) late; all are recovered with a planted mass, the
// start states corrected by them.
TEST(IdentifyFit, RecoversASensorsBiasGainAndDelay) {
  TempDir tmp;
  WriteEditedScene(
      testing::kScene, [](mjModel* m) { ScaleBodyMass(m, "pa10_link4", 0.93); }, tmp / "truth.xml");
  WriteNoisyLog(RunLab(tmp / "truth.xml", tmp / "real", 4.0), tmp / "noisy.csv", ".q.", 1e-5, 13);
  scene::CsvTable table = scene::ReadCsvTable(tmp / "noisy.csv");
  const int s2 = table.Column("pa10.q.S2"), e1 = table.Column("pa10.q.E1");
  std::string text;
  for (std::size_t c = 0; c < table.columns.size(); ++c) text += (c ? "," : "") + table.columns[c];
  text += "\n";
  const int s1 = table.Column("pa10.q.S1");
  char buffer[32];
  for (std::size_t r = table.rows.size(); r-- > 0;) {
    // S1 read one period (2 ms) late; the first row as it is
    if (r > 0) table.rows[r][s1] = table.rows[r - 1][s1];
  }
  for (std::vector<double>& row : table.rows) {
    row[s2] += 2e-3;
    row[e1] *= 1.02;
    for (std::size_t c = 0; c < row.size(); ++c) {
      text += (c ? "," : "") + std::string(buffer, std::to_chars(buffer, buffer + sizeof buffer, row[c]).ptr);
    }
    text += "\n";
  }
  WriteFile(tmp / "biased.csv", text);
  WriteFile(tmp / "id.yaml", SpecText(testing::kScene, tmp / "biased.csv", "  - {name: pa10.q.*, weight: 1.0e5}\n",
                                      "  - {name: m4, target: body pa10_link4 mass, lower: 1, upper: 8}\n"
                                      "  - {name: bias, target: column pa10.q.S2 bias, lower: -0.01, upper: 0.01}\n"
                                      "  - {name: gain, target: column pa10.q.E1 gain, lower: 0.9, upper: 1.1}\n"
                                      "  - {name: delay, target: column pa10.q.S1 delay, lower: 0, upper: 0.01}\n"));
  const std::unique_ptr<Problem> problem = Problem::Create(LoadSpec(tmp / "id.yaml"));
  FitOptions options;
  options.threads = 2;
  const FitResult fit = Fit(*problem, options);
  const double truth[] = {4.31 * 0.93, 2e-3, 1.02, 0.002};
  for (int i = 0; i < 4; ++i) {
    const Estimate& e = fit.estimates[i];
    std::printf("%-5s truth %.6g fitted %.6g sd %.3g %s\n", e.name.c_str(), truth[i], e.value, e.sd, e.note.c_str());
    EXPECT_TRUE(e.identifiable) << e.name << ": " << e.note;
    EXPECT_LT(std::abs(e.value - truth[i]), 0.02 * truth[i]) << e.name;
    EXPECT_LT(std::abs(e.value - truth[i]), 3 * e.sd) << e.name;
  }
}

// Every rollout is computed alone and summed in a fixed order: one thread and three give the
// same estimates, bit for bit.
TEST(IdentifyFit, SameResultForAnyThreadCount) {
  TempDir tmp;
  WriteEditedScene(testing::kScene, EditTruth, tmp / "truth.xml");
  WriteNoisyLog(RunLab(tmp / "truth.xml", tmp / "real", 3.0), tmp / "noisy.csv", ".q.", 1e-5, 11);
  WriteFile(tmp / "id.yaml", SpecText(testing::kScene, tmp / "noisy.csv", "  - {name: pa10.q.*, weight: 1.0e5}\n",
                                      "  - {name: m4, target: body pa10_link4 mass, lower: 1, upper: 8}\n"
                                      "  - {name: a_s1, target: joint S1 armature, lower: 0, upper: 5}\n"));
  const std::unique_ptr<Problem> problem = Problem::Create(LoadSpec(tmp / "id.yaml"));
  FitOptions one, three;
  one.threads = 1;
  three.threads = 3;
  const FitResult a = Fit(*problem, one), b = Fit(*problem, three);
  ASSERT_EQ(a.estimates.size(), b.estimates.size());
  EXPECT_GT(std::abs(a.estimates[0].value - a.estimates[0].nominal), 0.01);  // it moved
  for (std::size_t i = 0; i < a.estimates.size(); ++i) {
    EXPECT_EQ(vlab::testing::Bits(a.estimates[i].value), vlab::testing::Bits(b.estimates[i].value));
    EXPECT_EQ(vlab::testing::Bits(a.estimates[i].sd), vlab::testing::Bits(b.estimates[i].sd));
  }
  EXPECT_EQ(vlab::testing::Bits(a.cost_fitted), vlab::testing::Bits(b.cost_fitted));
  EXPECT_EQ(a.iterations, b.iterations);
}

}  // namespace
}  // namespace vlab::identify
