// Force mode against the lab's truth: tests/data/task/force_mode.yaml runs in process
// (the PA10 with its position servo, its JR3 and the table of scenes/pa10.xml); the
// script finds the table, presses it and moves 5 cm along it. The force checked is
// MuJoCo's own contact force between the tool and the table (mj_contactForce summed
// over their contacts), not the JR3 reading the script sees.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/core_mujoco.h"
#include "lab/run/lab_runner.h"
#include "lab/scenario/lab_scenario.h"
#include "test_util.h"

namespace vlab::lab {
namespace {

constexpr const char* kScenario = VLAB_SOURCE_DIR "/tests/data/task/force_mode.yaml";
constexpr const char* kScript = VLAB_SOURCE_DIR "/tests/data/task/force_mode.lua";
constexpr double kPeriod = 0.002;

// the script's line that holds `marker` (a phase's comment)
int LineOf(const std::string& marker) {
  const std::vector<std::string> lines = vlab::testing::Lines(vlab::testing::ReadFile(kScript));
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (lines[i].find(marker) != std::string::npos) return static_cast<int>(i) + 1;
  }
  ADD_FAILURE() << "no line with " << marker;
  return -1;
}

struct Row {
  double t = 0, force_N = 0, tool_x = 0, planned_x = 0;
  int line = 0;
};

// runs the scenario pressing with `force_N`: one row per control period, the true normal
// force between the tool's body and the table's top beside the log's script line
std::vector<Row> Press(double force_N, std::string* output = nullptr) {
  Scenario s = LoadScenario(kScenario);
  s.controller.programs.at(0).params["force"] = std::to_string(force_N);
  std::unique_ptr<Lab> lab = Lab::Create(s);
  const mjModel* model = lab->model();
  const int table = mj_name2id(model, mjOBJ_GEOM, "table_top");
  const int tool = mj_name2id(model, mjOBJ_BODY, "tool_body");
  EXPECT_GE(table, 0);
  EXPECT_GE(tool, 0);
  std::map<long, double> truth;  // period -> N
  RunOptions options;
  vlab::testing::TempDir dir;
  options.out_dir = dir / "out";
  options.quiet = true;
  options.observe = [&](double t, const mjModel* m, mjData* d) {
    double sum = 0;
    for (int i = 0; i < d->ncon; ++i) {
      const mjContact& c = d->contact[i];
      const bool tool_1 = m->geom_bodyid[c.geom1] == tool, tool_2 = m->geom_bodyid[c.geom2] == tool;
      if (!((tool_1 && c.geom2 == table) || (tool_2 && c.geom1 == table))) continue;
      mjtNum f[6];
      mj_contactForce(m, d, i, f);
      sum += f[0];  // the normal force, contact frame: it pushes the two apart
    }
    truth[std::lround(t / kPeriod)] = sum;
  };
  const RunResult r = lab->Run(options);
  EXPECT_EQ(r.exit_code, 0) << r.failure << "\n" << r.task_output;
  if (output) *output = r.task_output;
  const std::vector<std::string> lines = vlab::testing::Lines(vlab::testing::ReadFile(dir / "out/log.csv"));
  const std::vector<std::string> header = vlab::testing::SplitCsv(lines.at(0));
  const auto column = [&](const std::string& name) {
    const auto it = std::find(header.begin(), header.end(), name);
    EXPECT_NE(it, header.end()) << name;
    return it - header.begin();
  };
  const auto line = column("task.pa10.line"), x = column("tool.x"), planned = column("task.pa10.tool.x");
  std::vector<Row> rows;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const std::vector<std::string> v = vlab::testing::SplitCsv(lines[i]);
    Row row;
    row.t = std::stod(v[0]);
    row.line = std::stoi(v[line]);
    row.tool_x = std::stod(v[x]);
    row.planned_x = std::stod(v[planned]);
    row.force_N = truth[std::lround(row.t / kPeriod)];
    rows.push_back(row);
  }
  // MuJoCo's contact between the pointer's flat end and the table drops out for a single
  // physics step now and then (the cylinder-box collision finds no point; the steps after,
  // deeper in, make up the impulse), and a period's row sees one of its two steps: the truth
  // is the force's mean over 50 ms (25 periods, centred), a force gauge of 20 Hz, well above
  // the loop's 3.5 Hz. (Per row, a dropout reads 0 N for 2 ms.)
  // (over the rows in force mode only, from force_mode to end_force_mode)
  const int first = LineOf("(phase: settle)"), last = LineOf("(phase: hold)");
  const auto in_mode = [&](const Row& row) { return row.line >= first && row.line <= last; };
  constexpr std::size_t kHalf = 12;
  std::vector<Row> mean = rows;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (!in_mode(rows[i])) continue;
    double sum = 0;
    int n = 0;
    for (std::size_t j = i > kHalf ? i - kHalf : 0; j <= i + kHalf && j < rows.size(); ++j) {
      if (in_mode(rows[j])) sum += rows[j].force_N, ++n;
    }
    mean[i].force_N = sum / n;
  }
  return mean;
}

struct Phases {
  double settle_s = 1e9;     // from force_mode's start until the force stays within the band
  double worst_slide_N = 0;  // the largest |F - target| while the tool slides 5 cm
  double worst_after_N = 0;  // ... from settled to end_force_mode
  double mean_hold_N = 0;    // the mean force in the hold after the slide
  double worst_hold_N = 0;   // its largest |F - target|
  double slid_m = 0;         // how far the planned tool moved along x while sliding
  double tool_slid_m = 0;    // ... the measured tool (friction holds it back)
};

Phases Measure(const std::vector<Row>& rows, double target_N, double band_N) {
  const int settle = LineOf("(phase: settle)"), slide = LineOf("(phase: slide)"), hold = LineOf("(phase: hold)");
  Phases p;
  double t0 = -1, last_out = -1, x0 = 0, x1 = 0, tool_x0 = 0, tool_x1 = 0, hold_sum = 0;
  int hold_rows = 0;
  bool sliding = false;
  for (const Row& row : rows) {
    const bool in_mode = row.line == settle || row.line == slide || row.line == hold;
    if (!in_mode) continue;
    if (t0 < 0) t0 = row.t;
    const double error = std::abs(row.force_N - target_N);
    if (error > band_N) last_out = row.t;
    if (row.line == slide) {
      if (!sliding) x0 = row.planned_x, tool_x0 = row.tool_x;
      sliding = true;
      x1 = row.planned_x;
      tool_x1 = row.tool_x;
      p.worst_slide_N = std::max(p.worst_slide_N, error);
    }
    if (row.line == hold) {
      p.worst_hold_N = std::max(p.worst_hold_N, error);
      hold_sum += row.force_N;
      ++hold_rows;
    }
  }
  p.settle_s = (last_out < 0 ? t0 : last_out + kPeriod) - t0;
  for (const Row& row : rows) {
    if (row.t >= t0 + p.settle_s && (row.line == settle || row.line == slide || row.line == hold)) {
      p.worst_after_N = std::max(p.worst_after_N, std::abs(row.force_N - target_N));
    }
  }
  p.mean_hold_N = hold_rows ? hold_sum / hold_rows : 0;
  p.slid_m = x1 - x0;
  p.tool_slid_m = tool_x1 - tool_x0;
  return p;
}

// The test: 10 N on the table while the tool moves 5 cm along it, the true force
// within ±0.5 N once settled (the settling within the script's 1 s wait), over the whole move.
TEST(TaskForceModeTest, HoldsTenNewtonsOnTheTableWhileSliding) {
  std::string output;
  const std::vector<Row> rows = Press(10, &output);
  const Phases p = Measure(rows, 10, 0.5);
  std::cout << "  10 N: settled (within 0.5 N) " << p.settle_s << " s after force_mode; worst while sliding "
            << p.worst_slide_N << " N, after settling " << p.worst_after_N << " N; slid " << 1000 * p.slid_m
            << " mm planned, " << 1000 * p.tool_slid_m << " mm measured; in the hold after it: mean " << p.mean_hold_N
            << " N, worst " << p.worst_hold_N << " N\n";
  EXPECT_LT(p.settle_s, 1.0);
  EXPECT_LE(p.worst_slide_N, 0.5);
  EXPECT_NEAR(p.slid_m, 0.05, 1e-3);
  EXPECT_GT(p.tool_slid_m, 0.045);
  // search: the planned tool where the guard fired, against the table's top (z = 0.40 m):
  // the plan leads the tool by the servo's lag (2 zeta / w = 32 ms at 10 Hz: 0.32 mm at
  // 10 mm/s), the JR3's filter delays the force (about 40 ms: 0.4 mm) and 2 N press the
  // contact in (0.2 mm at 1.1e4 N/m): 1 mm below the top at most, never above it
  const std::string key = "touched the table at z = ";
  const auto at = output.find(key);
  ASSERT_NE(at, std::string::npos) << output;
  const double z = std::stod(output.substr(at + key.size()));
  std::cout << "  search: the guard fired with the planned tool at z = " << z << " m\n";
  EXPECT_LT(z, 0.40);
  EXPECT_GT(z, 0.399);
}

// The target decides the force: 5 N presses with 5 N (and not 10).
TEST(TaskForceModeTest, FiveNewtonsPressWithFive) {
  const std::vector<Row> rows = Press(5);
  const Phases p = Measure(rows, 5, 0.5);
  std::cout << "  5 N: settled " << p.settle_s << " s; worst while sliding " << p.worst_slide_N
            << " N; mean in the hold " << p.mean_hold_N << " N\n";
  EXPECT_LT(p.settle_s, 1.0);
  EXPECT_LE(p.worst_slide_N, 0.5);
  EXPECT_NEAR(p.mean_hold_N, 5, 0.25);
  EXPECT_GT(std::abs(p.mean_hold_N - 10), 4);
}

}  // namespace
}  // namespace vlab::lab
