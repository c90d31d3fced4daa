// scenes/hoap3_stand.yaml in process: the lab's devices bound to the HOAP-3 model
// (the 28-joint arm device over its torque motors, the feet with their pads and the
// robot's weight, the IMU), the run starting from the scene's `stand` keyframe, and
// the arm device's position servo holding that pose on the FSRs. The scenario's own
// checks decide: FSR sum within 2 % of m g, CoP inside the support polygon, servo
// following error, joint limits, upright chest. (The external controller runs in
// tests/hoap3/hoap3_serve_test.sh.)
#include <algorithm>
#include <cmath>
#include <iostream>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "core/core_errors.h"
#include "core/core_mujoco.h"
#include "lab/run/lab_runner.h"
#include "lab/scenario/lab_scenario.h"
#include "test_util.h"

namespace vlab::lab {
namespace {

constexpr const char* kScenario = VLAB_SOURCE_DIR "/scenes/hoap3_stand.yaml";

// The scenario without its external controller, in the fast clock.
Scenario InProcess(double duration_s) {
  Scenario s = LoadScenario(kScenario);
  s.controller = ControllerConfig{};
  s.clock = ClockMode::kFast;
  s.duration_s = duration_s;
  return s;
}

bool Has(const std::vector<std::string>& columns, const std::string& name) {
  return std::find(columns.begin(), columns.end(), name) != columns.end();
}

TEST(Hoap3ScenarioTest, StartsFromTheStandKeyframe) {
  std::unique_ptr<Lab> lab = Lab::Create(InProcess(1.0));
  const mjModel* m = lab->model();
  const int key = mj_name2id(m, mjOBJ_KEY, "stand");
  ASSERT_GE(key, 0);
  DataPtr d = MakeData(m);
  lab->InitialState(d.get());
  for (int i = 0; i < m->nq; ++i) EXPECT_EQ(d->qpos[i], m->key_qpos[key * m->nq + i]) << "qpos " << i;
  EXPECT_EQ(d->time, 0.0);
  const std::vector<std::string> columns = lab->Columns();
  for (const char* c : {"hoap3.q.RL_J1", "hoap3.q.LA_J6", "hoap3.following_error", "feet.hoap3_lfoot_bl", "feet.sum",
                        "feet.sum_error", "feet.cop_x", "feet.cop_y", "feet.cop_margin", "imu.hoap3_accel.z"}) {
    EXPECT_TRUE(Has(columns, c)) << c;
  }
  // 28 joints x (q, qd, tau) + limit_violation + following_error
  EXPECT_EQ(
      std::count_if(columns.begin(), columns.end(), [](const std::string& c) { return c.rfind("hoap3.", 0) == 0; }),
      28 * 3 + 2);
}

TEST(Hoap3ScenarioTest, AnUnknownKeyframeNamesTheFileLineAndKey) {
  // the keyframe key's line in the scenario file
  const std::vector<std::string> lines = vlab::testing::Lines(vlab::testing::ReadFile(kScenario));
  int line = 0;
  while (line < static_cast<int>(lines.size()) && lines[line].rfind("keyframe:", 0) != 0) ++line;
  ASSERT_LT(line, static_cast<int>(lines.size()));
  Scenario s = InProcess(1.0);
  EXPECT_EQ(s.keyframe, "stand");
  EXPECT_EQ(s.keyframe_where, std::string(kScenario) + ":" + std::to_string(line + 1));
  s.keyframe = "sit";
  try {
    Lab::Create(s);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(s.keyframe_where + ": keyframe: the scene"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("has no keyframe 'sit'"), std::string::npos) << e.what();
  }
}

// Without commands the arm device holds its initial pose (position servo with its own
// model's bias forces fed forward): the robot stands on its eight FSRs. Once the
// first seconds' sway has died out, the feet device's centre of pressure is the
// ground projection of the robot's centre of mass (moment balance at rest), and the
// FSR sum, over the last second, its weight.
TEST(Hoap3ScenarioTest, TheArmServoHoldsTheStandOnTheFsrs) {
  std::unique_ptr<Lab> lab = Lab::Create(InProcess(6.0));
  vlab::testing::TempDir dir;
  RunOptions options;
  options.out_dir = dir / "out";
  Eigen::Vector2d com_W = Eigen::Vector2d::Zero();
  double weight_N = 0;
  options.observe = [&](double, const mjModel* m, mjData* d) {
    const int pelvis = mj_name2id(m, mjOBJ_BODY, "hoap3_pelvis");
    com_W = Eigen::Vector2d(d->subtree_com[3 * pelvis], d->subtree_com[3 * pelvis + 1]);
    weight_N = m->body_subtreemass[pelvis] * -m->opt.gravity[2];
  };
  const RunResult r = lab->Run(options);
  EXPECT_EQ(r.exit_code, 0) << r.failure;
  ASSERT_FALSE(r.checks.empty());
  for (const CheckResult& c : r.checks) {
    EXPECT_TRUE(c.pass) << c.config.name << " = " << c.value;
    std::cout << "  " << c.config.name << " (" << ReduceName(c.config.reduce) << " " << c.config.signal
              << ") = " << c.value << "\n";
  }
  EXPECT_TRUE(r.warnings.empty());
  // the last row of the log against the last state observed
  const std::vector<std::string> lines = vlab::testing::Lines(vlab::testing::ReadFile(dir / "out/log.csv"));
  ASSERT_GT(lines.size(), 2u);
  const std::vector<std::string> header = vlab::testing::SplitCsv(lines.front());
  const std::vector<std::string> last = vlab::testing::SplitCsv(lines.back());
  const auto value = [&](const std::string& column) {
    const auto it = std::find(header.begin(), header.end(), column);
    return it == header.end() ? std::nan("") : std::stod(last[it - header.begin()]);
  };
  std::cout << "  CoP (" << 1000 * value("feet.cop_x") << ", " << 1000 * value("feet.cop_y") << ") mm, COM ("
            << 1000 * com_W.x() << ", " << 1000 * com_W.y() << ") mm, FSR sum " << value("feet.sum") << " N of "
            << weight_N << " N\n";
  EXPECT_NEAR(value("feet.cop_x"), com_W.x(), 5e-4);
  EXPECT_NEAR(value("feet.cop_y"), com_W.y(), 5e-4);
  // the FSR sum over the last second: the servo reads its joints in whole encoder counts, so
  // they hunt by a count and the body jiggles (the sum swings by 0.7 N in one row); over a
  // second the body's vertical momentum hardly changes, so the mean carries the weight
  const auto sum_column = std::find(header.begin(), header.end(), "feet.sum") - header.begin();
  double sum_N = 0.0;
  int rows = 0;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const std::vector<std::string> row = vlab::testing::SplitCsv(lines[i]);
    if (std::stod(row[0]) <= 5.0) continue;
    sum_N += std::stod(row[sum_column]);
    ++rows;
  }
  ASSERT_GT(rows, 100);
  EXPECT_NEAR(sum_N / rows, weight_N, 1e-3 * weight_N);
  EXPECT_NEAR(value("feet.sum_error"), value("feet.sum") / weight_N - 1, 1e-12);
}

}  // namespace
}  // namespace vlab::lab
