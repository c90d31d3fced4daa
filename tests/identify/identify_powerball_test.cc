// vlab identify's second worked example (docs/identify.md, "Worked example: the PowerBall's
// rotor"): the rotor's inertia and bearing loss of a planted "real" PowerBall recovered from
// the spin-up and spin-down the lab records with cases/powerball/spin_down.txt, fitted by the
// shipped spec cases/powerball/identify/rotor.yaml from what the real ball and wrist report: the
// counter's speed and the JR3.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include "identify/identify_fit.h"
#include "identify/identify_output.h"
#include "identify/identify_problem.h"
#include "identify/identify_spec.h"
#include "test_util.h"

namespace vlab::identify::powerball_test {
namespace {

using vlab::testing::RunVlab;
using vlab::testing::TempDir;

const std::string kScene = VLAB_SOURCE_DIR "/scenes/pa10_powerball.xml";
const std::string kCase = VLAB_SOURCE_DIR "/cases/powerball";

// the shipped ball: I_s 2e-5 kg m^2, damping 1.5e-7 N m s, friction loss 2e-5 N m
// (mjcf/powerball/README.md, "Losses"); planted: I_s +15 %, damping x1.5, friction loss +20 %
struct Planted {
  const char* name;
  double nominal, truth;
};
const std::vector<Planted> kPlanted = {
    {"I_s", 2e-5, 2.3e-5},
    {"c", 1.5e-7, 2.25e-7},
    {"T", 2e-5, 2.4e-5},
};

TEST(IdentifyPowerball, RecoversThePlantedRotorFromItsSpinDown) {
  TempDir tmp;
  WriteEditedScene(
      kScene,
      [](mjModel* m) {
        const int rotor = mj_name2id(m, mjOBJ_BODY, "pb_rotor");
        const int spin = m->jnt_dofadr[mj_name2id(m, mjOBJ_JOINT, "pb_spin")];
        ASSERT_GE(rotor, 0);
        ASSERT_EQ(m->body_inertia[3 * rotor + 1], kPlanted[0].nominal);  // the axle is the rotor's y
        ASSERT_EQ(m->dof_damping[spin], kPlanted[1].nominal);
        ASSERT_EQ(m->dof_frictionloss[spin], kPlanted[2].nominal);
        m->body_inertia[3 * rotor + 1] = kPlanted[0].truth;
        m->dof_damping[spin] = kPlanted[1].truth;
        m->dof_frictionloss[spin] = kPlanted[2].truth;
      },
      tmp / "truth.xml");
  // the recording, as a user makes it (the drive is the case's own powerball_spin)
  const testing::ProcessResult run =
      RunVlab("run " + kCase + "/stage1.yaml --overrides " + kCase +
              "/spin_down.txt --set scene=" + (tmp / "truth.xml") + " --out " + (tmp / "real") + " --quiet");
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;

  Spec spec = LoadSpec(kCase + "/identify/rotor.yaml");
  spec.logs = {(tmp / "real") + "/log.csv"};
  const std::unique_ptr<Problem> problem = Problem::Create(spec, 2);
  ASSERT_EQ(problem->parameters().size(), kPlanted.size());
  // 2 windows of the slow coast, 2 of the fast; each window's start speed profiled out
  EXPECT_EQ(problem->window_count(), 4);
  EXPECT_EQ(problem->window_nuisances(), 4);

  // the replay with the planted values reproduces the counter and the couple at their noise
  // (the weights are 1/sigma: a residual sd near 1)
  const int counted = problem->residual_count() - problem->residuals_left_out();
  std::vector<double> truth;
  for (const Planted& p : kPlanted) truth.push_back(p.truth);
  std::vector<double> r(problem->residual_count());
  std::vector<char> ok(problem->window_count());
  problem->ForEachWindow(2, [&](int w, Workspace& ws) {
    ok[w] = problem->Rollout(w, truth, ws, r.data() + problem->window_offset(w), nullptr);
  });
  for (char replayed : ok) ASSERT_TRUE(replayed);
  double squares = 0;
  for (double x : r) squares += x * x;
  const double sd_truth = std::sqrt(squares / counted);
  std::printf("residual sd with the planted values: %.3f\n", sd_truth);
  EXPECT_LT(sd_truth, 1.3);

  FitOptions options;
  options.threads = 2;
  const auto start = std::chrono::steady_clock::now();
  const FitResult fit = Fit(*problem, options);
  std::printf("fit: %d windows, %d residuals (%d held at 0), %d iterations, %d rollouts, %.1f s, residual sd %.3f\n",
              fit.windows, fit.residuals, problem->residuals_left_out(), fit.iterations, fit.rollouts,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), fit.residual_sd);
  EXPECT_LT(fit.residual_sd, 1.3);
  // the nominal ball does not reproduce them
  const double sd_nominal = std::sqrt(2 * fit.cost_nominal / counted);
  std::printf("residual sd with the nominal values: %.3f\n", sd_nominal);
  EXPECT_GT(sd_nominal, 5.0);
  ASSERT_EQ(fit.estimates.size(), kPlanted.size());
  // each within 2 % of its planted value, and told apart from the others
  for (std::size_t i = 0; i < kPlanted.size(); ++i) {
    const Estimate& e = fit.estimates[i];
    const double error = std::abs(e.value - kPlanted[i].truth);
    std::printf("%-4s nominal %-9.4g planted %-9.4g fitted %-11.6g (%+.2f %%) sd %-9.3g (%.1f sd off) %s\n",
                e.name.c_str(), e.nominal, kPlanted[i].truth, e.value, 100 * (e.value / kPlanted[i].truth - 1), e.sd,
                error / e.sd, e.note.c_str());
    EXPECT_EQ(e.name, kPlanted[i].name);
    EXPECT_LE(error, 0.02 * kPlanted[i].truth) << e.name;
    EXPECT_TRUE(e.identifiable) << e.name << ": " << e.note;
    // and the check can fail: the nominal value is far outside it
    EXPECT_GT(std::abs(e.nominal - kPlanted[i].truth), 0.02 * kPlanted[i].truth);
  }
}

}  // namespace
}  // namespace vlab::identify::powerball_test
