// vlab identify's fit: planted parameters recovered from logs the lab makes in-test.
#include <atomic>
#include <charconv>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "core/core_errors.h"
#include "identify/identify_fit.h"
#include "identify/identify_output.h"
#include "identify/identify_problem.h"
#include "identify/identify_spec.h"
#include "identify_test_plant.h"
#include "scene/scene_csv.h"
#include "sensors/sensor_wrench.h"
#include "test_util.h"

namespace vlab::identify::fit_test {
namespace {

using testing::RunLab;
using vlab::testing::TempDir;
using vlab::testing::WriteFile;

// a spec over pa10_joint_pd on `scene`, fitting `columns` with `parameters` (YAML list items)
std::string SpecText(const std::string& scene, const std::string& log, const std::string& columns,
                     const std::string& parameters, double window = 0.2, const std::string& more_sets = "") {
  return "scenario: " + testing::kScenario + "\nset: [\"scene=" + scene + "\", \"checks=[]\"" + more_sets +
         "]\nlogs: [" + log + "]\nwindow: " + std::to_string(window) + "\ncolumns:\n" + columns + "parameters:\n" +
         parameters;
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

// The JR3's columns: the replay feeds the model's force/torque sensors to the device's own
// JR3 model, so with the true model it reproduces the lab's filtered wrench (noise, bias and
// rounding off in that run) once each window's filter has settled from its start on the
// model's load there; the rows before are held out of the residual.
TEST(IdentifyFit, ReplayOfTheTrueModelReproducesTheJr3Columns) {
  TempDir tmp;
  const std::vector<std::string> clean = {"devices.jr3.noise=false", "devices.jr3.bias=false",
                                          "devices.jr3.quantization=false"};
  const std::string log = RunLab(testing::kScene, tmp / "run", 3.0, clean);
  WriteFile(tmp / "id.yaml", SpecText(testing::kScene, log, "  - {name: jr3.F*}\n  - {name: jr3.M*}\n",
                                      "  - {name: m2, target: body pa10_link2 mass, lower: 1, upper: 20}\n", 0.5) +
                                 "start_smoothing: 0\n");
  const std::unique_ptr<Problem> problem = Problem::Create(LoadSpec(tmp / "id.yaml"));
  ASSERT_EQ(problem->columns().size(), 6u);
  EXPECT_EQ(problem->columns()[0], "jr3.Fx");
  EXPECT_EQ(problem->columns()[5], "jr3.Mz");
  const int settle = problem->wrench_settle_rows();
  std::printf("filter 4 settles in %d rows\n", settle);
  EXPECT_GT(settle, 10);
  EXPECT_LT(settle, 200);
  Workspace ws = problem->MakeWorkspace();
  double worst = 0, largest = 0, unsettled = 0;
  for (int w = 0; w < problem->window_count(); ++w) {
    std::vector<double> r(problem->window_residuals(w)), predicted(r.size());
    ASSERT_TRUE(problem->Rollout(w, {problem->parameters()[0].nominal}, ws, r.data(), predicted.data()));
    for (std::size_t i = 0; i < r.size(); ++i) {
      const int k = static_cast<int>(i / 6) + 1;
      const double error = std::abs(predicted[i] - problem->Measured(w, k, static_cast<int>(i % 6)));
      largest = std::max(largest, std::abs(problem->Measured(w, k, static_cast<int>(i % 6))));
      // the first window starts where the lab's JR3 did, settled on the same load: exact
      if (w == 0) {
        EXPECT_EQ(error, 0.0) << "row " << k;
      }
      if (k <= settle) {
        EXPECT_EQ(r[i], 0.0);
        unsettled = std::max(unsettled, error);
      } else {
        worst = std::max(worst, error);
        EXPECT_EQ(r[i], predicted[i] - problem->Measured(w, k, static_cast<int>(i % 6)));
      }
    }
  }
  std::printf("jr3 replay: largest error %.3g (N, N m) after settling, %.3g before; largest value %.3g\n", worst,
              unsettled, largest);
  EXPECT_EQ(problem->residuals_left_out(), problem->window_count() * settle * 6);
  // measured 1.73e-5 N: the start's filter transient decayed to 1e-3 of itself, a five-hundredth
  // of the JR3's noise at filter 4 (0.0093 % of 100 N full scale)
  EXPECT_LT(worst, 3e-5);
  EXPECT_GT(unsettled, 100 * worst);  // the rows left out are the ones that needed it
  EXPECT_GT(largest, 1.0);
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

void EditTruth(mjModel* m) {
  testing::EditNominal(m);
  ScaleBodyMass(m, "pa10_link3", 1.10);
  ScaleBodyMass(m, "pa10_link4", 0.93);
  m->dof_damping[testing::Dof(m, "S2")] *= 1.5;
  m->dof_armature[testing::Dof(m, "S1")] *= 1.15;
  m->dof_frictionloss[testing::Dof(m, "E1")] *= 1.2;
}

// The estimates' statistics are those of the point the fit ended on: each free parameter's sd
// from the residual variance and JᵀJ (sd_iid) equals the one computed here from a Jacobian
// taken again at the fitted values with the fit's own central differences (the fit keeps the
// Jacobian of each point Ceres accepts rather than computing it again).
void ExpectStatisticsOfThePointItEndedOn(const Problem& problem, const FitResult& fit) {
  const std::vector<BoundParameter>& params = problem.parameters();
  const int count = problem.residual_count();
  std::vector<int> free;
  for (std::size_t i = 0; i < fit.estimates.size(); ++i) {
    if (!fit.estimates[i].frozen && fit.estimates[i].excited) free.push_back(static_cast<int>(i));
  }
  Workspace ws = problem.MakeWorkspace();
  auto residuals = [&](const std::vector<double>& values) {
    std::vector<double> r(count);
    for (int w = 0; w < problem.window_count(); ++w) {
      EXPECT_TRUE(problem.Rollout(w, values, ws, r.data() + problem.window_offset(w), nullptr));
    }
    return r;
  };
  const std::vector<double> r = residuals(fit.fitted_values);
  double squares = 0;
  for (double x : r) squares += x * x;
  EXPECT_EQ(0.5 * squares, fit.cost_fitted);
  const int n = static_cast<int>(free.size());
  Eigen::MatrixXd j(count, n);
  for (int a = 0; a < n; ++a) {
    const BoundParameter& p = params[free[a]];
    const double u = fit.fitted_values[free[a]] / p.scale;
    const double h = problem.spec().jacobian_step * std::max(1.0, std::abs(u));
    const double hi = std::min(p.spec.upper / p.scale, u + h), lo = std::max(p.spec.lower / p.scale, u - h);
    std::vector<double> up = fit.fitted_values, down = fit.fitted_values;
    up[free[a]] = hi * p.scale;
    down[free[a]] = lo * p.scale;
    const std::vector<double> r_up = residuals(up), r_down = residuals(down);
    for (int k = 0; k < count; ++k) j(k, a) = (r_up[k] - r_down[k]) / (hi - lo);
  }
  const double dof = count - problem.residuals_left_out() - problem.window_nuisances() - n;
  // the fit's pseudo-inverse and this inverse agree within about 1e-11 of the sd; the Jacobian
  // of the step Ceres tried last, 2e-9 to 6e-9 off (measured)
  const Eigen::MatrixXd cov = (squares / dof) * (j.transpose() * j).inverse();
  for (int a = 0; a < n; ++a) {
    const Estimate& e = fit.estimates[free[a]];
    const double sd = std::sqrt(cov(a, a)) * params[free[a]].scale;
    EXPECT_NEAR(e.sd_iid, sd, 1e-10 * sd) << e.name << ": the sd of another point's Jacobian";
  }
}

// Planted link masses (+10 %, -7 %), damping x1.5, armature +15 % and friction loss +20 %,
// fitted from the nominal model to 10 s of the lab's log with encoder noise (sd 1e-5 rad):
// each within 2 % and within 3 sd of the truth; the base's mass, which no joint moves,
// reported as not excited and left at its nominal value; the statistics those of the fitted
// point (Ceres ends this fit on a step it tried and did not keep, its cost change below the
// tolerance, so the statistics' Jacobian is the one kept from the point it accepted before).
TEST(IdentifyFit, RecoversPlantedParameters) {
  TempDir tmp;
  WriteEditedScene(testing::kScene, testing::EditNominal, tmp / "nominal.xml");
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
  ExpectStatisticsOfThePointItEndedOn(*problem, fit);
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

// The planted recovery: a "real" PA10 (link masses +10 % and -7 %, link 5's centre of
// mass moved 10 mm, S2's damping x1.5, E1's friction loss +20 %, S1's armature +15 %, a payload
// on the tool the fit does not know) run by the lab through pa10_joint_pd with the JR3's noise,
// quantisation and its own seeded bias on; a 2 % gain on the JR3's force columns, S1's encoder
// read 2 ms late and encoder noise planted in the log. Fitted from the nominal model with the
// JR3's columns in the residual.
struct Truth {
  std::string name, target;
  double nominal, truth, lower, upper;
  double resolution;  // the stated resolution: |error| within max(2 % of |truth|, this)
};

TEST(IdentifyFit, RecoversThePlantedArmPayloadAndJr3) {
  TempDir tmp;
  constexpr double kPayloadMass = 0.5, kPayloadCom[3] = {0.02, -0.01, 0.08};  // kg; m in tool_body's frame
  WriteEditedScene(testing::kScene, testing::EditNominal, tmp / "nominal.xml");
  WriteEditedScene(
      testing::kScene,
      [&](mjModel* m) {
        EditTruth(m);
        m->body_ipos[3 * testing::Body(m, "pa10_link5") + 0] += 0.010;
        const int tool = testing::Body(m, "tool_body");
        AddPointMass(kPayloadMass, kPayloadCom, &m->body_mass[tool], m->body_ipos + 3 * tool,
                     m->body_inertia + 3 * tool, m->body_iquat + 4 * tool);
      },
      tmp / "truth.xml");
  // the lab's JR3 with its noise, quantisation and its bias from the seed, read at filter 3
  // (31.25 Hz): it settles in 0.03 s, where filter 4 takes 0.22 s of every window
  const std::vector<std::string> jr3 = {"devices.jr3.filter=3"};
  const std::string clean = RunLab(tmp / "truth.xml", tmp / "real", 8.0, jr3);
  constexpr double kSigma = 1e-5;  // rad, encoder noise
  WriteNoisyLog(clean, tmp / "noisy.csv", ".q.", kSigma, 5);
  // the JR3's force columns read 2 % large; S1's encoder one period (2 ms) late
  scene::CsvTable table = scene::ReadCsvTable(tmp / "noisy.csv");
  const int s1 = table.Column("pa10.q.S1");
  for (std::size_t r = table.rows.size(); r-- > 1;) table.rows[r][s1] = table.rows[r - 1][s1];
  std::string text;
  for (std::size_t c = 0; c < table.columns.size(); ++c) text += (c ? "," : "") + table.columns[c];
  text += "\n";
  char buffer[32];
  for (std::vector<double>& row : table.rows) {
    for (const char* f : {"jr3.Fx", "jr3.Fy", "jr3.Fz"}) row[table.Column(f)] *= 1.02;
    for (std::size_t c = 0; c < row.size(); ++c) {
      text += (c ? "," : "") + std::string(buffer, std::to_chars(buffer, buffer + sizeof buffer, row[c]).ptr);
    }
    text += "\n";
  }
  WriteFile(tmp / "planted.csv", text);
  // the JR3's own bias (drawn from its seed at the start, whatever else is on): the reading at
  // rest with it less the reading without it, noise and rounding off
  auto first_row = [&](const std::string& name, const std::string& with_bias) {
    const scene::CsvTable t =
        scene::ReadCsvTable(RunLab(tmp / "truth.xml", tmp / name, 0.01,
                                   {"devices.jr3.filter=3", "devices.jr3.noise=false", "devices.jr3.quantization=false",
                                    "devices.jr3.bias=" + with_bias}));
    sensors::Wrench w;
    for (int a = 0; a < 6; ++a) w[a] = t.rows[0][t.Column(std::string("jr3.") + "FFFMMM"[a] + "xyzxyz"[a])];
    return w;
  };
  const sensors::Wrench bias = first_row("biased", "true") - first_row("unbiased", "false");
  std::printf("the JR3's bias: %.4g %.4g %.4g N, %.4g %.4g %.4g N m\n", bias[0], bias[1], bias[2], bias[3], bias[4],
              bias[5]);
  ASSERT_GT(bias.norm(), 0.0);

  const double com5 = 0.0;  // link 5's centre of mass, x, in the shipped model
  std::vector<Truth> truths = {
      {"m3", "body pa10_link3 mass", 3.52, 3.52 * 1.10, 1, 8, 0},
      {"m4", "body pa10_link4 mass", 4.31, 4.31 * 0.93, 1, 8, 0},
      {"c5x", "body pa10_link5 com_x", com5, com5 + 0.010, -0.05, 0.05, 0},
      {"d_s2", "joint S2 damping", 3.0, 4.5, 0, 20, 0},
      {"a_s1", "joint S1 armature", 0.75, 0.75 * 1.15, 0, 5, 0},
      {"f_e1", "joint E1 frictionloss", 1.0, 1.2, 0, 10, 0},
      {"pm", "payload tool_body mass", 0.2, kPayloadMass, 0, 3, 0},
      {"px", "payload tool_body com_x", 0, kPayloadCom[0], -0.2, 0.2, 0},
      {"py", "payload tool_body com_y", 0, kPayloadCom[1], -0.2, 0.2, 0},
      {"pz", "payload tool_body com_z", 0, kPayloadCom[2], -0.2, 0.3, 0},
      {"delay_s1", "column pa10.q.S1 delay", 0, 0.002, 0, 0.01, 0},
  };
  const char* axes[] = {"Fx", "Fy", "Fz", "Mx", "My", "Mz"};
  for (int a = 0; a < 6; ++a) {
    // a bias is a few counts (0.05 % of full scale drawn, a count 0.006 %): its stated
    // resolution is the JR3's count, full scale / 16384 (the 67M25A's: 100, 100, 200 N, 5 N m)
    const double fs = a < 2 ? 100 : a == 2 ? 200 : 5;
    truths.push_back({std::string("b_") + axes[a], std::string("column jr3.") + axes[a] + " bias", 0, bias[a],
                      -0.01 * fs, 0.01 * fs, fs / sensors::kWrenchCountsPerFullScale});
  }
  for (int a = 0; a < 3; ++a) {
    truths.push_back(
        {std::string("g_") + axes[a], std::string("column jr3.") + axes[a] + " gain", 1, 1.02, 0.9, 1.1, 0});
  }
  std::string params;
  for (const Truth& t : truths) {
    params += "  - {name: " + t.name + ", target: " + t.target + ", nominal: " + std::to_string(t.nominal) +
              ", lower: " + std::to_string(t.lower) + ", upper: " + std::to_string(t.upper) + "}\n";
  }
  params += "  - {name: m_base, target: body pa10_base mass, lower: 1, upper: 10}\n";
  // weights 1/sigma: the encoder's; the JR3's at filter 3, about 0.0186 % of full scale
  WriteFile(tmp / "id.yaml", SpecText(tmp / "nominal.xml", tmp / "planted.csv",
                                      "  - {name: pa10.q.*, weight: 1.0e5}\n"
                                      "  - {name: jr3.Fx, weight: 54}\n  - {name: jr3.Fy, weight: 54}\n"
                                      "  - {name: jr3.Fz, weight: 27}\n  - {name: jr3.M*, weight: 1075}\n",
                                      params, 0.2, ", \"devices.jr3.filter=3\""));
  const std::unique_ptr<Problem> problem = Problem::Create(LoadSpec(tmp / "id.yaml"));
  FitOptions options;
  options.threads = 2;
  const auto start = std::chrono::steady_clock::now();
  const FitResult fit = Fit(*problem, options);
  std::printf(
      "fit: %d windows (%d in contact), %d residuals (%d settling), %d iterations, %d rollouts, %.1f s, "
      "residual sd %.3f\n",
      fit.windows, problem->windows_in_contact(), fit.residuals, problem->residuals_left_out(), fit.iterations,
      fit.rollouts, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), fit.residual_sd);
  // free centres of mass: the linear estimate does not apply, the fit starts from nominal
  EXPECT_EQ(fit.first_estimate, "nominal");
  EXPECT_NE(fit.first_estimate_note.find("centre of mass"), std::string::npos) << fit.first_estimate_note;
  // within 2 % (or the stated resolution) of `truth`, and the sd bracketing it, over the
  // identifiable parameters
  auto check = [&](double wrong, bool print, int* within, int* bracketed) {
    *within = *bracketed = 0;
    for (std::size_t i = 0; i < truths.size(); ++i) {
      const Estimate& e = fit.estimates[i];
      const double truth = truths[i].truth * wrong + (wrong != 1 ? 0.01 * (truths[i].upper - truths[i].lower) : 0);
      const double error = std::abs(e.value - truth);
      const bool ok = error <= std::max(0.02 * std::abs(truth), truths[i].resolution);
      *within += ok;
      *bracketed += error <= 2 * e.sd;
      if (print) {
        std::printf("%-8s nominal %-10.6g truth %-10.6g fitted %-10.6g sd %-9.3g (%.2f sd off) %s %s\n", e.name.c_str(),
                    e.nominal, truth, e.value, e.sd, error / e.sd, ok ? "" : "OUT", e.note.c_str());
      }
    }
  };
  int within = 0, bracketed = 0;
  check(1.0, true, &within, &bracketed);
  // all are fitted; a pair the data tell apart only poorly is flagged by its correlation (the
  // payload's mass and its height on the tool's axis: above 0.99), the rest are identifiable
  int identifiable = 0;
  for (std::size_t i = 0; i < truths.size(); ++i) {
    const Estimate& e = fit.estimates[i];
    EXPECT_TRUE(e.excited) << e.name;
    identifiable += e.identifiable;
    if (!e.identifiable) {
      EXPECT_NE(e.note.find("correlated with"), std::string::npos) << e.name << ": " << e.note;
    }
  }
  EXPECT_GE(identifiable, static_cast<int>(truths.size()) - 2);
  EXPECT_EQ(within, static_cast<int>(truths.size()));
  EXPECT_GE(bracketed, 0.9 * truths.size());
  // the same checks fail for values other than the ones planted (5 % off and 1 % of the range
  // further)
  int within_wrong = 0, bracketed_wrong = 0;
  check(1.05, false, &within_wrong, &bracketed_wrong);
  std::printf("against truths 5 %% off: %d within, %d bracketed of %zu\n", within_wrong, bracketed_wrong,
              truths.size());
  EXPECT_LT(within_wrong, 0.5 * truths.size());
  EXPECT_LT(bracketed_wrong, 0.5 * truths.size());
  // the base's mass: no joint moves it
  const Estimate& base = fit.estimates.back();
  EXPECT_FALSE(base.excited);
  EXPECT_EQ(base.value, base.nominal);
  EXPECT_FALSE(std::isfinite(base.sd));
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

// ForEachWindow (the windows' nominal replays while a problem is made): every window once, on
// any number of threads; of the errors thrown, the lowest window's, whichever thread ran it.
TEST(IdentifyFit, ForEachWindowVisitsEachWindowOnceAndRethrowsTheLowestWindowsError) {
  TempDir tmp;
  WriteNoisyLog(RunLab(testing::kScene, tmp / "real", 2.0), tmp / "noisy.csv", ".q.", 1e-5, 5);
  WriteFile(tmp / "id.yaml", SpecText(testing::kScene, tmp / "noisy.csv", "  - {name: pa10.q.*, weight: 1.0e5}\n",
                                      "  - {name: m4, target: body pa10_link4 mass, lower: 1, upper: 8}\n"));
  const std::unique_ptr<Problem> problem = Problem::Create(LoadSpec(tmp / "id.yaml"), 3);
  const int n = problem->window_count();
  ASSERT_GE(n, 5);
  for (int threads : {1, 3, 64}) {
    std::vector<std::atomic<int>> visits(n);
    problem->ForEachWindow(threads, [&](int w, Workspace& ws) {
      EXPECT_NE(ws.data, nullptr);
      ++visits[w];
    });
    for (int w = 0; w < n; ++w) EXPECT_EQ(visits[w].load(), 1) << "window " << w << ", " << threads << " threads";
    try {
      problem->ForEachWindow(threads, [&](int w, Workspace&) {
        if (w == 2 || w == n - 1) throw InputError("window " + std::to_string(w));
      });
      ADD_FAILURE() << "no error rethrown";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()), "window 2") << threads << " threads";
    }
  }
}

}  // namespace
}  // namespace vlab::identify::fit_test
