// Loading scene models for the model-validation tests, with every MuJoCo warning
// (compiler and runtime) turned into a test failure.
#pragma once

#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

namespace vlab::models::testing {

struct ModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct DataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using ModelPtr = std::unique_ptr<mjModel, ModelDeleter>;
using DataPtr = std::unique_ptr<mjData, DataDeleter>;

/// Collects MuJoCo's runtime warning texts while alive (MuJoCo's handler is
/// process-global; tests run single-threaded).
class WarningCatcher {
 public:
  WarningCatcher() {
    Texts().clear();
    previous_ = mju_user_warning;
    mju_user_warning = [](const char* text) { Texts().emplace_back(text); };
  }
  ~WarningCatcher() { mju_user_warning = previous_; }
  WarningCatcher(const WarningCatcher&) = delete;
  WarningCatcher& operator=(const WarningCatcher&) = delete;

  /// Warning texts reported so far, oldest first.
  static std::vector<std::string>& Texts() {
    static std::vector<std::string> texts;
    return texts;
  }

 private:
  void (*previous_)(const char*) = nullptr;
};

/// Loads VLAB_SOURCE_DIR/relative_path. A load error or a compiler warning (both
/// reported through mj_loadXML's error buffer) fails the calling test.
inline ModelPtr LoadScene(const std::string& relative_path) {
  const std::string path = std::string(VLAB_SOURCE_DIR) + "/" + relative_path;
  char error[1000] = "";
  mjModel* m = mj_loadXML(path.c_str(), nullptr, error, sizeof(error));
  EXPECT_STREQ(error, "") << path << ": load error or compiler warning";
  EXPECT_NE(m, nullptr) << path;
  return ModelPtr(m);
}

inline DataPtr MakeData(const mjModel* m) { return DataPtr(mj_makeData(m)); }

/// Resets to the named keyframe (fails the test when there is none).
inline void ResetToKey(const mjModel* m, mjData* d, const char* key) {
  const int id = mj_name2id(m, mjOBJ_KEY, key);
  ASSERT_GE(id, 0) << "no keyframe '" << key << "'";
  mj_resetDataKeyframe(m, d, id);
  mj_forward(m, d);
}

/// Sum of MuJoCo's runtime warning counters (mjData::warning).
inline int WarningCount(const mjData* d) {
  int count = 0;
  for (int i = 0; i < mjNWARNING; ++i) count += d->warning[i].number;
  return count;
}

inline int Id(const mjModel* m, mjtObj type, const std::string& name) {
  return mj_name2id(m, type, name.c_str());
}

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
