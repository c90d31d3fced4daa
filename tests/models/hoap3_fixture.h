// Test fixture for the HOAP-3 model tests: scenes/hoap3.xml at its zero keyframe, the
// zero-pose URDF link frames composed from models/hoap3_reference.h (our own forward
// kinematics of the URDF joint origins), and the model's mass properties per body or
// subtree, all relative to the pelvis origin.
#pragma once

#include <array>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "models/hoap3_reference.h"
#include "models/model_test_util.h"
#include "mujoco_fixture.h"

namespace vlab::models::testing {

/// A link frame in the zero pose: axes R (columns, world) and origin p (m, from the pelvis).
struct Frame {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
};

/// URDF fixed-axis roll-pitch-yaw: Rz(yaw) Ry(pitch) Rx(roll).
inline Eigen::Matrix3d Rpy(const std::array<double, 3>& rpy) {
  return (Eigen::AngleAxisd(rpy[2], Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(rpy[1], Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy[0], Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

/// std::array -> Eigen vector.
inline Eigen::Vector3d V(const std::array<double, 3>& a) { return Eigen::Vector3d(a[0], a[1], a[2]); }

/// Zero-pose URDF link frames by link name, origin = WAIST (the pelvis body origin).
inline std::map<std::string, Frame> UrdfFrames() {
  std::map<std::string, Frame> frames;
  frames["WAIST"].R = Rpy(kWaistRpy);
  for (const UrdfJoint& j : kUrdfJoints) {
    const Frame& parent = frames.at(j.parent);
    Frame& child = frames[j.child];
    child.R = parent.R * Rpy(j.rpy);
    child.p = parent.p + parent.R * V(j.xyz);
  }
  return frames;
}

/// Symmetric inertia tensor from (Ixx, Iyy, Izz, Ixy, Ixz, Iyz), kg m^2.
inline Eigen::Matrix3d Tensor(const std::array<double, 6>& i) {
  Eigen::Matrix3d t;
  t << i[0], i[3], i[4], i[3], i[1], i[5], i[4], i[5], i[2];
  return t;
}

/// m (|d|^2 I - d d'): the parallel-axis term of mass m at offset d, kg m^2.
inline Eigen::Matrix3d Shift(const Eigen::Vector3d& d, double m) {
  return m * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
}

/// Mass (kg), COM (m, from the pelvis origin) and inertia about the COM (world axes).
struct MassProps {
  double mass = 0;
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
};

/// scenes/hoap3.xml at its zero keyframe, positions relative to the pelvis origin.
class Hoap3Model : public vlab::test::MujocoTest {
 protected:
  void SetUp() override {
    model_ = LoadModel("scenes/hoap3.xml");
    data_ = MakeData(m());
    ResetToKey(m(), d(), "zero");
    pelvis_ = Vec3(d()->xpos + 3 * Id(m(), mjOBJ_BODY, "hoap3_pelvis"));
    frames_ = UrdfFrames();
  }
  const mjModel* m() const { return model_; }
  mjData* d() const { return data_; }
  Eigen::Vector3d BodyPos(const std::string& body) const {
    return Vec3(d()->xpos + 3 * Id(m(), mjOBJ_BODY, body)) - pelvis_;
  }
  Eigen::Vector3d SitePos(const std::string& site) const {
    return Vec3(d()->site_xpos + 3 * Id(m(), mjOBJ_SITE, site)) - pelvis_;
  }
  // mass, COM and central inertia of body b and (subtree) its descendants
  MassProps Props(int b, bool subtree) const {
    MassProps total;
    std::vector<int> bodies;
    for (int i = 0; i < m()->nbody; ++i) {
      bool in = i == b;
      for (int p = i; subtree && !in && p > 0; p = m()->body_parentid[p]) in = p == b;
      if (in) bodies.push_back(i);
    }
    for (int i : bodies) {
      total.mass += m()->body_mass[i];
      total.com += m()->body_mass[i] * (Vec3(d()->xipos + 3 * i) - pelvis_);
    }
    total.com /= total.mass;
    for (int i : bodies) {
      const Eigen::Matrix3d r = Mat3(d()->ximat + 9 * i);
      total.inertia += r * Vec3(m()->body_inertia + 3 * i).asDiagonal() * r.transpose() +
                       Shift(Vec3(d()->xipos + 3 * i) - pelvis_ - total.com, m()->body_mass[i]);
    }
    return total;
  }

  const mjModel* model_ = nullptr;
  mjData* data_ = nullptr;
  Eigen::Vector3d pelvis_;
  std::map<std::string, Frame> frames_;
};

}  // namespace vlab::models::testing
