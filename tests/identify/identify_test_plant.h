// A planted "real" PA10 for the identification tests: the shipped scene with known changes
// (identify_plant.h), driven by the lab through scenes/pa10_joint_pd.yaml (every joint moves).
#pragma once

#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include "identify/identify_output.h"
#include "identify/identify_plant.h"
#include "lab/run/lab_runner.h"
#include "lab/scenario/lab_scenario.h"
#include "test_util.h"

namespace vlab::identify::testing {

inline const std::string kScene = VLAB_SOURCE_DIR "/scenes/pa10.xml";
inline const std::string kScenario = VLAB_SOURCE_DIR "/scenes/pa10_joint_pd.yaml";

inline int Dof(const mjModel* m, const char* joint) { return m->jnt_dofadr[mj_name2id(m, mjOBJ_JOINT, joint)]; }
inline int Body(const mjModel* m, const char* body) { return mj_name2id(m, mjOBJ_BODY, body); }

/// The nominal PA10 of the identification tests: the shipped scene with S2's damping 3 N·m·s/rad
/// and E1's friction loss 1 N·m (the data sheet leaves both at 0), so that a planted change of
/// either is a change of a value the model has.
inline void EditNominal(mjModel* m) {
  m->dof_damping[Dof(m, "S2")] = 3.0;
  m->dof_frictionloss[Dof(m, "E1")] = 1.0;
}

/// Runs the scenario `file` with the overrides `sets` into `out_dir`; its log.csv.
inline std::string RunScenario(const std::string& file, const std::string& out_dir,
                               const std::vector<std::string>& sets) {
  const lab::Scenario s = lab::LoadScenario(file, sets);
  std::unique_ptr<lab::Lab> lab = lab::Lab::Create(s);
  lab::RunOptions options;
  options.out_dir = out_dir;
  const lab::RunResult result = lab->Run(options);
  EXPECT_EQ(result.exit_code, 0) << result.failure;
  return out_dir + "/log.csv";
}

/// Runs pa10_joint_pd (no checks, `duration` s, `sets` overrides after) on `scene` into
/// `out_dir`; its log.csv.
inline std::string RunLab(const std::string& scene, const std::string& out_dir, double duration,
                          const std::vector<std::string>& sets = {}) {
  std::vector<std::string> all = {"scene=" + scene, "checks=[]", "duration=" + std::to_string(duration)};
  all.insert(all.end(), sets.begin(), sets.end());
  return RunScenario(kScenario, out_dir, all);
}

}  // namespace vlab::identify::testing
