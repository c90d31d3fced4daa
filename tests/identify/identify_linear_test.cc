// vlab identify's linear first estimate: planted masses, damping and armature recovered from
// the logs' torques alone (inverse-dynamics regression), and the fit started from it.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "identify/identify_fit.h"
#include "identify/identify_linear.h"
#include "identify/identify_problem.h"
#include "identify/identify_spec.h"
#include "identify_test_plant.h"
#include "test_util.h"

namespace vlab::identify::linear_test {
namespace {

using testing::RunLab;
using vlab::testing::TempDir;
using vlab::testing::WriteFile;

struct Planted {
  const char* name;
  const char* target;
  double nominal, truth, lower, upper;
};
// the nominal PA10 (S2 damping and E1 friction loss added) and a "real" one with link masses
// +-30 %, damping x1.5, armature +15 % and friction loss +20 %
const std::vector<Planted> kPlanted = {
    {"m3", "body pa10_link3 mass", 3.52, 3.52 * 1.30, 1, 8},
    {"m4", "body pa10_link4 mass", 4.31, 4.31 * 0.70, 1, 8},
    {"m6", "body pa10_link6 mass", 1.46, 1.46 * 1.30, 0.1, 8},
    {"d_s2", "joint S2 damping", 3.0, 3.0 * 1.5, 0, 20},
    {"a_e1", "joint E1 armature", 0.2125, 0.2125 * 1.15, 0, 5},
    {"f_e1", "joint E1 frictionloss", 1.0, 1.0 * 1.2, 0, 10},
};

void EditTruth(mjModel* m) {
  testing::EditNominal(m);
  ScaleBodyMass(m, "pa10_link3", 1.30);
  ScaleBodyMass(m, "pa10_link4", 0.70);
  ScaleBodyMass(m, "pa10_link6", 1.30);
  m->dof_damping[testing::Dof(m, "S2")] *= 1.5;
  m->dof_armature[testing::Dof(m, "E1")] *= 1.15;
  m->dof_frictionloss[testing::Dof(m, "E1")] *= 1.2;
}

std::string SpecText(const std::string& scene, const std::string& log, const std::string& extra = "") {
  std::string text = "scenario: " + testing::kScenario + "\nset: [\"scene=" + scene + "\", \"checks=[]\"]\nlogs: [" +
                     log + "]\ncolumns:\n  - {name: pa10.q.*, weight: 1.0e5}\n" + extra + "parameters:\n";
  for (const Planted& p : kPlanted) {
    text += std::string("  - {name: ") + p.name + ", target: " + p.target + ", lower: " + std::to_string(p.lower) +
            ", upper: " + std::to_string(p.upper) + "}\n";
  }
  return text + "  - {name: bias, target: column pa10.q.S2 bias, lower: -0.01, upper: 0.01}\n";
}

// the planted parameters' estimates off the truth, relative; the bias not covered, at nominal
std::vector<double> RelativeErrors(const Problem& problem, const LinearEstimate& e) {
  EXPECT_TRUE(e.applies) << e.why;
  std::vector<double> errors;
  for (std::size_t i = 0; i < kPlanted.size(); ++i) {
    EXPECT_EQ(e.status[i], LinearStatus::kEstimated) << kPlanted[i].name;
    errors.push_back(std::abs(e.values[i] / kPlanted[i].truth - 1));
    std::printf("%-5s nominal %.6g truth %.6g linear %.8g (%.4f %% off)\n", kPlanted[i].name, kPlanted[i].nominal,
                kPlanted[i].truth, e.values[i], 100 * errors.back());
  }
  const std::size_t bias = kPlanted.size();
  EXPECT_EQ(e.status[bias], LinearStatus::kNotCovered);
  EXPECT_EQ(e.values[bias], problem.parameters()[bias].nominal);
  std::printf("%d rows, %d torques, left out: %d near contact, %d clipped, %d slow\n", e.samples, e.torque_rows,
              e.left_out_contact, e.left_out_clipped, e.left_out_slow);
  return errors;
}

class IdentifyLinear : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    tmp_ = new TempDir();
    WriteEditedScene(testing::kScene, testing::EditNominal, *tmp_ / "nominal.xml");
    WriteEditedScene(testing::kScene, EditTruth, *tmp_ / "truth.xml");
    clean_ = RunLab(*tmp_ / "truth.xml", *tmp_ / "real", 10.0);
  }
  static void TearDownTestSuite() { delete tmp_; }
  static std::unique_ptr<Problem> Make(const std::string& log, const std::string& extra = "") {
    WriteFile(*tmp_ / "id.yaml", SpecText(*tmp_ / "nominal.xml", log, extra));
    return Problem::Create(LoadSpec(*tmp_ / "id.yaml"));
  }
  static TempDir* tmp_;
  static std::string clean_;
};
TempDir* IdentifyLinear::tmp_ = nullptr;
std::string IdentifyLinear::clean_;

// From the noise-free log of a torque-controlled arm the estimate is exact but for the
// differentiation: with a narrow filter (a quadratic over 7 rows) masses within 0.02 %, damping
// and friction loss 0.01 %, armature 0.1 % (measured 0.005 %, 0.0001 %, 0.0002 %, 0.027 %);
// with the default (a cubic over 81 rows) masses within 0.05 %, damping 0.01 %, armature 0.3 %,
// friction loss 0.02 % (measured 0.008 %, 0.0004 %, 0.05 %, 0.003 %). The nominal values are
// 15 to 30 % off.
TEST_F(IdentifyLinear, RecoversPlantedParametersFromANoiseFreeLog) {
  const std::unique_ptr<Problem> problem = Make(clean_);
  LinearOptions narrow;
  narrow.degree = 2;
  narrow.half_window = 3;
  const std::vector<double> errors = RelativeErrors(*problem, EstimateLinear(*problem, narrow));
  const double bound[] = {2e-4, 2e-4, 2e-4, 1e-4, 1e-3, 1e-4};
  for (std::size_t i = 0; i < errors.size(); ++i) EXPECT_LT(errors[i], bound[i]) << kPlanted[i].name;
  const std::vector<double> wide = RelativeErrors(*problem, EstimateLinear(*problem));
  const double wide_bound[] = {5e-4, 5e-4, 5e-4, 1e-4, 3e-3, 2e-4};
  for (std::size_t i = 0; i < wide.size(); ++i) EXPECT_LT(wide[i], wide_bound[i]) << kPlanted[i].name;
}

// With encoder noise (q 1e-5 rad, qd 4e-3 rad/s) the default filter keeps it close: masses
// within 0.2 %, damping 0.3 %, armature 5 %, friction loss 0.2 % (measured 0.026 %, 0.073 %,
// 1.8 %, 0.016 %: q̇'s noise in q̈ draws the armature low); the narrow filter would take the
// noise into q̈ (armature clamped at 0).
TEST_F(IdentifyLinear, StaysCloseWithEncoderNoise) {
  WriteNoisyLog(clean_, *tmp_ / "q_noisy.csv", ".q.", 1e-5, 7);
  WriteNoisyLog(*tmp_ / "q_noisy.csv", *tmp_ / "noisy.csv", ".qd.", 4e-3, 8);
  const std::unique_ptr<Problem> problem = Make(*tmp_ / "noisy.csv");
  const std::vector<double> errors = RelativeErrors(*problem, EstimateLinear(*problem));
  const double bound[] = {2e-3, 2e-3, 2e-3, 3e-3, 0.05, 2e-3};
  for (std::size_t i = 0; i < errors.size(); ++i) EXPECT_LT(errors[i], bound[i]) << kPlanted[i].name;
  LinearOptions narrow;
  narrow.degree = 2;
  narrow.half_window = 3;
  EXPECT_GT(RelativeErrors(*problem, EstimateLinear(*problem, narrow))[4], 0.5);
}

// What the torques cannot tell stays nominal: the base's mass (no joint moves it) and one of
// link 1's mass and S1's armature (link 1 turns about S1's axis only: both act as inertia about
// it, the same column); a frozen parameter is a known term, not estimated.
TEST_F(IdentifyLinear, LeavesWhatTheTorquesCannotTellAtNominal) {
  const std::string extra =
      "  - {name: m0, target: body pa10_base mass, lower: 1, upper: 30}\n"
      "  - {name: m1, target: body pa10_link1 mass, lower: 1, upper: 30}\n"
      "  - {name: a_s1, target: joint S1 armature, lower: 0, upper: 5}\n"
      "  - {name: d_s3, target: joint S3 damping, nominal: 0, lower: 0, upper: 5, frozen: true}\n";
  WriteFile(*tmp_ / "id.yaml", SpecText(*tmp_ / "nominal.xml", clean_) + extra);
  const std::unique_ptr<Problem> problem = Problem::Create(LoadSpec(*tmp_ / "id.yaml"));
  const LinearEstimate e = EstimateLinear(*problem);
  ASSERT_TRUE(e.applies) << e.why;
  const std::size_t m0 = kPlanted.size() + 1, m1 = m0 + 1, a_s1 = m0 + 2, d_s3 = m0 + 3;
  EXPECT_EQ(e.status[m0], LinearStatus::kUndetermined);
  EXPECT_EQ(e.values[m0], problem->parameters()[m0].nominal);
  // exactly one of the pair is estimated
  EXPECT_NE(e.status[m1] == LinearStatus::kEstimated, e.status[a_s1] == LinearStatus::kEstimated);
  EXPECT_EQ(e.status[d_s3], LinearStatus::kNotCovered);
  EXPECT_EQ(e.values[d_s3], 0.0);
  EXPECT_EQ(e.rank, static_cast<int>(kPlanted.size()) + 1);
}

// A joint torque at its motor's limit may be the clipped command rather than what acted: its
// equations are left out (here the nominal model's W1 limited to the median of the log's
// |tau|), and the estimate stays within the noise-free bounds.
TEST_F(IdentifyLinear, LeavesClippedTorquesOut) {
  const int w1 = 5;
  std::vector<double> magnitudes;
  {
    const Eigen::MatrixXd& tau = Make(clean_)->log_tau(0);
    for (Eigen::Index r = 0; r < tau.rows(); ++r) magnitudes.push_back(std::abs(tau(r, w1)));
  }
  std::nth_element(magnitudes.begin(), magnitudes.begin() + magnitudes.size() / 2, magnitudes.end());
  const double limit = magnitudes[magnitudes.size() / 2];
  WriteEditedScene(
      *tmp_ / "nominal.xml",
      [limit](mjModel* m) {
        const int a = mj_name2id(m, mjOBJ_ACTUATOR, "W1");
        m->actuator_ctrlrange[2 * a] = m->actuator_forcerange[2 * a] = -limit;
        m->actuator_ctrlrange[2 * a + 1] = m->actuator_forcerange[2 * a + 1] = limit;
      },
      *tmp_ / "limited.xml");
  WriteFile(*tmp_ / "id.yaml", SpecText(*tmp_ / "limited.xml", clean_));
  const std::unique_ptr<Problem> problem = Problem::Create(LoadSpec(*tmp_ / "id.yaml"));
  const LinearEstimate e = EstimateLinear(*problem);
  std::printf("W1 limited to %.4g N m: %d equations left out as clipped\n", limit, e.left_out_clipped);
  // about half of W1's rows (MJCF's 6 digits may round the limit either way)
  EXPECT_GT(e.left_out_clipped, e.samples / 3);
  EXPECT_LT(e.left_out_clipped, 2 * e.samples / 3);
  const std::vector<double> errors = RelativeErrors(*problem, e);
  const double bound[] = {5e-4, 5e-4, 5e-4, 1e-4, 3e-3, 2e-4};
  for (std::size_t i = 0; i < errors.size(); ++i) EXPECT_LT(errors[i], bound[i]) << kPlanted[i].name;
}

// The fit from the linear estimate converges to the fit from the nominal values (masses
// +-30 % planted: the nominal start far off), in fewer iterations.
TEST_F(IdentifyLinear, FitFromItReachesTheSameOptimumSooner) {
  const std::string log = RunLab(*tmp_ / "truth.xml", *tmp_ / "short", 4.0);
  WriteNoisyLog(log, *tmp_ / "short_noisy.csv", ".q.", 1e-5, 9);
  const std::unique_ptr<Problem> problem = Make(*tmp_ / "short_noisy.csv");
  FitOptions from_nominal, from_linear;
  from_nominal.threads = from_linear.threads = 2;
  from_nominal.first_estimate = FirstEstimate::kNominal;
  from_linear.first_estimate = FirstEstimate::kLinear;
  const FitResult a = Fit(*problem, from_nominal), b = Fit(*problem, from_linear);
  std::printf("from nominal: cost %.4g -> %.4g, %d iterations, %d rollouts, %.1f s\n", a.cost_start, a.cost_fitted,
              a.iterations, a.rollouts, a.wall_s);
  std::printf("from linear:  cost %.4g -> %.4g, %d iterations, %d rollouts, %.1f s\n", b.cost_start, b.cost_fitted,
              b.iterations, b.rollouts, b.wall_s);
  EXPECT_EQ(a.first_estimate, "nominal");
  EXPECT_EQ(b.first_estimate, "linear");
  EXPECT_EQ(b.cost_nominal, a.cost_start);
  EXPECT_LT(b.cost_start, 0.01 * a.cost_start);
  EXPECT_LT(b.iterations, a.iterations);
  EXPECT_NEAR(b.cost_fitted, a.cost_fitted, 1e-4 * a.cost_fitted);
  for (std::size_t i = 0; i < kPlanted.size(); ++i) {
    const Estimate &x = a.estimates[i], &y = b.estimates[i];
    std::printf("%-5s truth %.6g from nominal %.6g from linear %.6g sd %.3g\n", x.name.c_str(), kPlanted[i].truth,
                x.value, y.value, x.sd);
    EXPECT_LT(std::abs(x.value - y.value), 0.1 * x.sd) << x.name;
    EXPECT_LT(std::abs(y.value - kPlanted[i].truth), 0.02 * kPlanted[i].truth) << x.name;
  }
}

}  // namespace
}  // namespace vlab::identify::linear_test
