// vlab identify's fit: planted parameters recovered from logs the lab makes in-test.
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
#include "test_util.h"

namespace vlab::identify {
namespace {

using testing::AddNoise;
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
                                      "  - {name: m2, target: body pa10_link2 mass, lower: 1, upper: 20}\n"));
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

}  // namespace
}  // namespace vlab::identify
