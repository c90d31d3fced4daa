// HOAP-3 model (scenes/hoap3.xml, mjcf/hoap3/) against its sources: joints and masses.
//
// Reference data (models/hoap3_reference.h) is typed from DATASHEET 3.2-3.4 and the
// jrl-umi3218 URDF, not from the MJCF. The URDF joint origins are composed into zero-pose
// link frames (models/hoap3_fixture.h); the model's bodies, joint axes, masses, COMs and
// inertias must match those frames and the manufacturer table:
//   - 28 hinge joints + a free joint, the SL names, SL limits (left = mirror image);
//   - joint anchors and axes on the URDF's, with the SL sign of each joint;
//   - per-link mass within 1 %, total within 1 % of 8.802 kg, COM within 0.2 mm and
//     inertia within 1 % (forearm: the forearm + wrist + finger subtree).
#include <cmath>
#include <string>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "models/hoap3_fixture.h"

namespace vlab::models::testing {
namespace {

TEST_F(Hoap3Model, Has28HingeJointsWithTheSlNamesAndAFreeBase) {
  int hinges = 0, free_joints = 0;
  for (int j = 0; j < m()->njnt; ++j) {
    hinges += m()->jnt_type[j] == mjJNT_HINGE;
    free_joints += m()->jnt_type[j] == mjJNT_FREE;
  }
  EXPECT_EQ(hinges, 28);
  EXPECT_EQ(free_joints, 1);
  EXPECT_EQ(m()->nv, 28 + 6);
  EXPECT_EQ(m()->jnt_type[0], mjJNT_FREE) << "the free joint must be the root's";
  for (const SlLimit& limit : kSlLimits) {
    for (const char* name : {limit.joint, limit.mirror}) {
      if (*name == '\0') continue;
      const int j = Id(m(), mjOBJ_JOINT, name);
      ASSERT_GE(j, 0) << name;
      EXPECT_EQ(m()->jnt_type[j], mjJNT_HINGE) << name;
      EXPECT_TRUE(m()->jnt_limited[j]) << name;
    }
  }
}

TEST_F(Hoap3Model, JointLimitsAreTheSlLimits) {
  constexpr double kTol = 1e-5;  // rad (the MJCF writes degrees with 4 decimals)
  for (const SlLimit& limit : kSlLimits) {
    const int j = Id(m(), mjOBJ_JOINT, limit.joint);
    ASSERT_GE(j, 0) << limit.joint;
    EXPECT_NEAR(m()->jnt_range[2 * j], limit.lower, kTol) << limit.joint;
    EXPECT_NEAR(m()->jnt_range[2 * j + 1], limit.upper, kTol) << limit.joint;
    if (*limit.mirror == '\0') continue;
    const int k = Id(m(), mjOBJ_JOINT, limit.mirror);
    ASSERT_GE(k, 0) << limit.mirror;
    EXPECT_NEAR(m()->jnt_range[2 * k], -limit.upper, kTol) << limit.mirror;
    EXPECT_NEAR(m()->jnt_range[2 * k + 1], -limit.lower, kTol) << limit.mirror;
  }
  // the left-side values DATASHEET 3.2 spells out
  const int ll1 = Id(m(), mjOBJ_JOINT, "LL_J1"), la2 = Id(m(), mjOBJ_JOINT, "LA_J2");
  EXPECT_NEAR(m()->jnt_range[2 * ll1], -0.52, kTol);
  EXPECT_NEAR(m()->jnt_range[2 * ll1 + 1], 1.57, kTol);
  EXPECT_NEAR(m()->jnt_range[2 * la2], 0.0, kTol);
  EXPECT_NEAR(m()->jnt_range[2 * la2 + 1], 1.65, kTol);
}

TEST_F(Hoap3Model, JointAnchorsAndAxesAreTheUrdfsWithSlSigns) {
  for (const UrdfJoint& uj : kUrdfJoints) {
    if (*uj.sl_joint == '\0') continue;
    SCOPED_TRACE(uj.sl_joint);
    const int j = Id(m(), mjOBJ_JOINT, uj.sl_joint);
    ASSERT_GE(j, 0);
    EXPECT_EQ(std::string(mj_id2name(m(), mjOBJ_BODY, m()->jnt_bodyid[j])), uj.body);
    const Frame& f = frames_.at(uj.child);
    const Eigen::Vector3d axis_urdf = f.R * V(uj.axis);
    EXPECT_LT((Vec3(d()->xaxis + 3 * j) - uj.sign * axis_urdf).norm(), 1e-9);
    // the anchor lies on the URDF axis line (the wrists sit elsewhere along it)
    const Eigen::Vector3d anchor = Vec3(d()->xanchor + 3 * j) - pelvis_;
    EXPECT_LT((anchor - f.p).cross(axis_urdf).norm(), 1e-9);
    const bool wrist = uj.child[2] == 'W';
    if (!wrist) {
      EXPECT_LT((BodyPos(uj.body) - f.p).norm(), 1e-9);
    }
    // the SL sign maps the URDF limits onto the SL limits (DATASHEET 3.2 notes the
    // sources' disagreement on B_J's upper limit and LA_J5's range)
    const std::string sl = uj.sl_joint;
    const double lower = uj.sign > 0 ? uj.lower : -uj.upper, upper = uj.sign > 0 ? uj.upper : -uj.lower;
    if (sl != "LA_J5") {
      EXPECT_NEAR(m()->jnt_range[2 * j], lower, 0.1);
    }
    if (sl != "LA_J5" && sl != "B_J") {
      EXPECT_NEAR(m()->jnt_range[2 * j + 1], upper, 0.1);
    }
  }
}

TEST_F(Hoap3Model, LinkMassPropertiesAreTheManufacturerValues) {
  const Eigen::Matrix3d mirror = Eigen::Vector3d(1, -1, 1).asDiagonal();
  for (const LinkMass& link : kLinkMasses) {
    SCOPED_TRACE(link.body);
    const Frame& f = frames_.at(link.link);
    const Eigen::Vector3d com = f.p + f.R * V(link.com);
    const Eigen::Matrix3d inertia = f.R * Tensor(link.inertia) * f.R.transpose();
    const double tol_inertia = 0.01 * inertia.diagonal().maxCoeff();
    const bool subtree = std::string(link.link) == "R_EB";  // forearm incl. wrist and hand
    const MassProps right = Props(Id(m(), mjOBJ_BODY, link.body), subtree);
    EXPECT_NEAR(right.mass, link.mass, 0.01 * link.mass);
    EXPECT_LT((right.com - com).norm(), 2e-4);
    EXPECT_LT((right.inertia - inertia).cwiseAbs().maxCoeff(), tol_inertia) << right.inertia << "\n vs\n" << inertia;
    if (*link.mirror == '\0') continue;
    SCOPED_TRACE(link.mirror);
    const MassProps left = Props(Id(m(), mjOBJ_BODY, link.mirror), subtree);
    EXPECT_NEAR(left.mass, link.mass, 0.01 * link.mass);
    EXPECT_LT((left.com - mirror * com).norm(), 1e-3);
    EXPECT_LT((left.inertia - mirror * inertia * mirror).cwiseAbs().maxCoeff(), 3 * tol_inertia);
  }
}

TEST_F(Hoap3Model, TotalMassIsTheDatasheetSum) {
  double total = 0;
  for (int b = 0; b < m()->nbody; ++b) total += m()->body_mass[b];
  EXPECT_NEAR(total, kTotalMass, 0.01 * kTotalMass);
  EXPECT_NEAR(SubtreeMass(m(), Id(m(), mjOBJ_BODY, "hoap3_pelvis")), total, 1e-12) << "mass outside the robot";
}
}  // namespace
}  // namespace vlab::models::testing
