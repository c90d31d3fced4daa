#include "kinsim/kinsim_scene.h"

#include <mujoco/mujoco.h>

#include "core/core_errors.h"
#include "core/core_mujoco.h"

namespace vlab::kinsim {

const std::vector<std::string>& Pa10Joints() {
  static const std::vector<std::string> joints = {"S1", "S2", "S3", "E1", "E2", "W1", "W2"};
  return joints;
}

const std::vector<double>& Pa10ReadyPose() {
  static const std::vector<double> ready = {0, 0.523599, 0, 1.047198, 0, 1.570796, 0};
  return ready;
}

KinArmConfig ArmFromScene(const std::string& name, const std::string& scene, const std::vector<std::string>& joints,
                          const std::vector<double>& velocity_max, const std::vector<double>& initial) {
  const vlab::ModelPtr model = vlab::LoadModel(scene);
  const mjModel* m = model.get();
  KinArmConfig c;
  c.name = name;
  c.joints = joints;
  c.initial = initial;
  for (const std::string& joint : joints) {
    const std::string where = "scene '" + scene + "': joint '" + joint + "'";
    const int j = mj_name2id(m, mjOBJ_JOINT, joint.c_str());
    if (j < 0) throw vlab::InputError("scene '" + scene + "': no joint '" + joint + "'");
    if (m->jnt_type[j] != mjJNT_HINGE && m->jnt_type[j] != mjJNT_SLIDE) {
      throw vlab::InputError(where + " is not a hinge or slide");
    }
    if (!m->jnt_limited[j]) throw vlab::InputError(where + " has no range (a kinematic arm needs its limits)");
    c.position_min.push_back(m->jnt_range[2 * j]);
    c.position_max.push_back(m->jnt_range[2 * j + 1]);
  }
  // one velocity limit for all joints, or one per joint (KinArm::Create checks the count)
  c.velocity_max = velocity_max.size() == 1 ? std::vector<double>(joints.size(), velocity_max[0]) : velocity_max;
  return c;
}

}  // namespace vlab::kinsim
