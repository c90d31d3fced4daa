// Every robot scene loads without a MuJoCo compiler warning, simulates 1 s from each of
// its keyframes without a runtime warning, and has the DOF count of its robot:
// HOAP-3 28 hinges + a free base, the humanoid head 7 hinges, the PA10 7 hinges.
#include <string>

#include <gtest/gtest.h>

#include "models/model_test_util.h"

namespace vlab::models::testing {
namespace {

struct SceneCase {
  const char* path;
  const char* root_body;  // the robot's root body
  int hinges;             // hinge joints in the robot's subtree
  int free_joints;
};

class SceneLoads : public ::testing::TestWithParam<SceneCase> {};

TEST_P(SceneLoads, QuietlyWithTheRobotsDofCount) {
  const SceneCase& c = GetParam();
  WarningCatcher warnings;
  const ModelPtr model = LoadScene(c.path);
  ASSERT_NE(model, nullptr);
  const mjModel* m = model.get();
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
  const DataPtr data = MakeData(m);
  for (int key = 0; key < m->nkey; ++key) {
    SCOPED_TRACE(mj_id2name(m, mjOBJ_KEY, key));
    mj_resetDataKeyframe(m, data.get(), key);
    for (int step = 0; step * m->opt.timestep < 1.0; ++step) mj_step(m, data.get());
    EXPECT_EQ(WarningCount(data.get()), 0);
  }
  EXPECT_TRUE(WarningCatcher::Texts().empty()) << WarningCatcher::Texts().front();
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
