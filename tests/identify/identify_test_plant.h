// A planted "real" PA10 for the identification tests: the shipped scene with known changes,
// driven by the lab through scenes/pa10_joint_pd.yaml (every joint moves), its log with
// seeded encoder noise.
#pragma once

#include <charconv>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include "identify/identify_output.h"
#include "lab/run/lab_runner.h"
#include "lab/scenario/lab_scenario.h"
#include "scene/scene_csv.h"
#include "test_util.h"

namespace vlab::identify::testing {

inline const std::string kScene = VLAB_SOURCE_DIR "/scenes/pa10.xml";
inline const std::string kScenario = VLAB_SOURCE_DIR "/scenes/pa10_joint_pd.yaml";

inline int Dof(const mjModel* m, const char* joint) { return m->jnt_dofadr[mj_name2id(m, mjOBJ_JOINT, joint)]; }
inline int Body(const mjModel* m, const char* body) { return mj_name2id(m, mjOBJ_BODY, body); }

/// Scales a body's mass and its inertia with it (the centre of mass stays).
inline void ScaleMass(mjModel* m, const char* body, double factor) {
  const int b = Body(m, body);
  m->body_mass[b] *= factor;
  for (int k = 0; k < 3; ++k) m->body_inertia[3 * b + k] *= factor;
}

/// Runs pa10_joint_pd (no checks, `duration` s, `sets` overrides after) on `scene` into
/// `out_dir`; its log.csv.
inline std::string RunLab(const std::string& scene, const std::string& out_dir, double duration,
                          const std::vector<std::string>& sets = {}) {
  std::vector<std::string> all = {"scene=" + scene, "checks=[]", "duration=" + std::to_string(duration)};
  all.insert(all.end(), sets.begin(), sets.end());
  lab::Scenario s = lab::LoadScenario(kScenario, all);
  std::unique_ptr<lab::Lab> lab = lab::Lab::Create(s);
  lab::RunOptions options;
  options.out_dir = out_dir;
  const lab::RunResult result = lab->Run(options);
  EXPECT_EQ(result.exit_code, 0) << result.failure;
  return out_dir + "/log.csv";
}

/// Copies a log.csv with seeded Gaussian noise of `sigma` added to every column whose name
/// contains `columns` (e.g. ".q.").
inline void AddNoise(const std::string& in, const std::string& out, const std::string& columns, double sigma,
                     unsigned seed) {
  const scene::CsvTable table = scene::ReadCsvTable(in);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  std::string text;
  for (std::size_t c = 0; c < table.columns.size(); ++c) text += (c ? "," : "") + table.columns[c];
  text += "\n";
  char buffer[32];
  for (const std::vector<double>& row : table.rows) {
    for (std::size_t c = 0; c < row.size(); ++c) {
      double v = row[c];
      if (table.columns[c].find(columns) != std::string::npos) v += noise(rng);
      text += (c ? "," : "") + std::string(buffer, std::to_chars(buffer, buffer + sizeof buffer, v).ptr);
    }
    text += "\n";
  }
  vlab::testing::WriteFile(out, text);
}

}  // namespace vlab::identify::testing
