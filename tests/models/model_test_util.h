// Small helpers of the model-validation tests (their scenes load with the MuJoCo
// fixture, tests/mujoco_fixture.h): keyframes, element ids, Eigen views, subtree masses.
#pragma once

#include <string>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace vlab::models::testing {

/// Resets to the named keyframe (fails the test when there is none).
inline void ResetToKey(const mjModel* m, mjData* d, const char* key) {
  const int id = mj_name2id(m, mjOBJ_KEY, key);
  ASSERT_GE(id, 0) << "no keyframe '" << key << "'";
  mj_resetDataKeyframe(m, d, id);
  mj_forward(m, d);
}

inline int Id(const mjModel* m, mjtObj type, const std::string& name) { return mj_name2id(m, type, name.c_str()); }

inline Eigen::Vector3d Vec3(const mjtNum* v) { return Eigen::Vector3d(v[0], v[1], v[2]); }

inline Eigen::Matrix3d Mat3(const mjtNum* rowmajor) {
  return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(rowmajor);
}

/// qpos address of a named hinge joint (-1 when absent).
inline int QposAdr(const mjModel* m, const std::string& joint) {
  const int j = Id(m, mjOBJ_JOINT, joint);
  return j < 0 ? -1 : m->jnt_qposadr[j];
}

/// Total mass of the subtree rooted at body b, kg.
inline double SubtreeMass(const mjModel* m, int b) {
  double mass = 0;
  for (int i = b; i < m->nbody; ++i) {
    for (int p = i; p > 0; p = m->body_parentid[p]) {
      if (p == b) {
        mass += m->body_mass[i];
        break;
      }
    }
  }
  return mass;
}

}  // namespace vlab::models::testing
