// Every robot scene loads without a MuJoCo compiler warning, simulates 1 s from each of
// its keyframes without a runtime warning (both checked by the MuJoCo fixture), and has the
// DOF count of its robot: HOAP-3 28 hinges + a free base, the humanoid head 7 hinges, the
// PA10 7 hinges.
#include <string>

#include <gtest/gtest.h>

#include "models/model_test_util.h"
#include "mujoco_fixture.h"

namespace vlab::models::testing {
namespace {

struct SceneCase {
  const char* path;
  const char* root_body;  // the robot's root body
  int hinges;             // hinge joints in the robot's subtree
  int free_joints;
};

class SceneLoads : public vlab::test::MujocoTest, public ::testing::WithParamInterface<SceneCase> {};

TEST_P(SceneLoads, QuietlyWithTheRobotsDofCount) {
  const SceneCase& c = GetParam();
  const mjModel* m = LoadModel(c.path);
  const int root = Id(m, mjOBJ_BODY, c.root_body);
  ASSERT_GE(root, 0) << c.root_body;
  int hinges = 0, free_joints = 0;
  for (int j = 0; j < m->njnt; ++j) {
    for (int b = m->jnt_bodyid[j]; b > 0; b = m->body_parentid[b]) {
      if (b != root) continue;
      hinges += m->jnt_type[j] == mjJNT_HINGE;
      free_joints += m->jnt_type[j] == mjJNT_FREE;
      break;
    }
  }
  EXPECT_EQ(hinges, c.hinges);
  EXPECT_EQ(free_joints, c.free_joints);
  EXPECT_GE(m->nkey, 1) << "a keyframe to start from";
  for (int key = 0; key < m->nkey; ++key) {
    mjData* data = MakeData(m);  // one per keyframe: mj_resetData clears the warning counters
    mj_resetDataKeyframe(m, data, key);
    for (int step = 0; step * m->opt.timestep < 1.0; ++step) mj_step(m, data);
  }
}

INSTANTIATE_TEST_SUITE_P(Robots, SceneLoads,
                         ::testing::Values(SceneCase{"scenes/hoap3.xml", "hoap3_pelvis", 28, 1},
                                           SceneCase{"scenes/head.xml", "head_base", 7, 0},
                                           SceneCase{"scenes/pa10.xml", "pa10_base", 7, 0}),
                         [](const ::testing::TestParamInfo<SceneCase>& info) {
                           const std::string path = info.param.path;
                           return path.substr(7, path.size() - 11);  // scenes/NAME.xml -> NAME
                         });

}  // namespace
}  // namespace vlab::models::testing
