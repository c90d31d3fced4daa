// HOAP-3 model (scenes/hoap3.xml, mjcf/hoap3/) against its sources: joints and masses.
//
// Reference data (models/hoap3_reference.h) is typed from DATASHEET 3.2-3.4 and the
// jrl-umi3218 URDF, not from the MJCF. The URDF joint origins are composed into zero-pose
// link frames (models/hoap3_fixture.h); the model's bodies, joint axes, masses, COMs and
// inertias must match those frames and the manufacturer table:
//   - 28 hinge joints + a free joint, the SL names, SL limits (left = mirror image);
//   - joint anchors and axes on the URDF's, with the SL sign of each joint;
//   - per-link mass and COM as DATASHEET 3.4 prints them (copied: to 1e-9), inertia to
//     the data sheet's rounding (forearm: the forearm + wrist + finger subtree, derived by
//     mjcf/hoap3/derive_inertials.py, so also to that script's print rounding);
//   - the total is the sum of the data sheet's link masses (1e-9) and its stated 8.802 kg.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

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

// Masses and right-side COMs are copied from DATASHEET 3.4 (the link frames are signed axis
// permutations of the world, so no digit is lost): 1e-9. The data sheet prints inertias to
// 4 significant digits while the model carries the SL file's 5 (e.g. chest Ixx 1.21947e-2 vs
// 1.2195e-2): each element within half a unit of the data sheet's last digit, 5e-4 of it.
constexpr double kCopied = 1e-9;         // kg, m: copied values, round-off only
constexpr double kPrintedDigits = 5e-4;  // DATASHEET 3.4 inertias: 4 significant digits

// |model - reference| per element, in units of the element's data-sheet rounding plus `extra`
double WorstInertiaRatio(const Eigen::Matrix3d& model, const Eigen::Matrix3d& reference, double extra) {
  double worst = 0;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const double allowed = kPrintedDigits * std::abs(reference(i, j)) + extra + 1e-15;
      worst = std::max(worst, std::abs(model(i, j) - reference(i, j)) / allowed);
    }
  }
  return worst;
}

TEST_F(Hoap3Model, LinkMassPropertiesAreTheManufacturerValues) {
  const Eigen::Matrix3d mirror = Eigen::Vector3d(1, -1, 1).asDiagonal();
  double worst_mass = 0, worst_com = 0, worst_inertia = 0, worst_left_com = 0, worst_left_inertia = 0;
  for (const LinkMass& link : kLinkMasses) {
    SCOPED_TRACE(link.body);
    const Frame& f = frames_.at(link.link);
    const Eigen::Vector3d com = f.p + f.R * V(link.com);
    const Eigen::Matrix3d inertia = f.R * Tensor(link.inertia) * f.R.transpose();
    const bool subtree = std::string(link.link) == "R_EB";  // forearm incl. wrist and hand
    const MassProps right = Props(Id(m(), mjOBJ_BODY, link.body), subtree);
    EXPECT_NEAR(right.mass, link.mass, kCopied);
    // the forearm body's COM and inertia are derived and printed with 6 decimals (m) and 6
    // significant digits: its COM is off by up to 5e-7 m per axis, the subtree's by 181/216
    // of that; the inertia by that shift's parallel-axis change plus the printed digits
    double com_tol = kCopied, inertia_extra = 1e-12;
    if (subtree) {
      const int forearm = Id(m(), mjOBJ_BODY, link.body);
      const double m_f = m()->body_mass[forearm], delta = 5e-7 * std::sqrt(3.0);
      const double arm = (Vec3(d()->xipos + 3 * forearm) - pelvis_ - right.com).norm();
      com_tol = m_f / right.mass * delta;
      inertia_extra = 2 * m_f * (2 * arm * delta + delta * delta) + 5e-10;
    }
    worst_mass = std::max(worst_mass, std::abs(right.mass - link.mass));
    worst_com = std::max(worst_com, (right.com - com).norm() / com_tol);
    worst_inertia = std::max(worst_inertia, WorstInertiaRatio(right.inertia, inertia, inertia_extra));
    EXPECT_LT((right.com - com).norm(), com_tol);
    EXPECT_LT(WorstInertiaRatio(right.inertia, inertia, inertia_extra), 1.0) << right.inertia << "\n vs\n" << inertia;
    if (*link.mirror == '\0') continue;
    SCOPED_TRACE(link.mirror);
    // left side: the SL file's own LL_*/LA_* rows, the same masses as the data sheet's right
    // side; their COMs and inertias are not the exact mirror (mjcf/hoap3/README.md: within
    // 0.2 mm and 1 %), and the data sheet has no left-side numbers to pin them to
    const MassProps left = Props(Id(m(), mjOBJ_BODY, link.mirror), subtree);
    EXPECT_NEAR(left.mass, link.mass, kCopied);
    worst_mass = std::max(worst_mass, std::abs(left.mass - link.mass));
    worst_left_com = std::max(worst_left_com, (left.com - mirror * com).norm());
    worst_left_inertia = std::max(worst_left_inertia, (left.inertia - mirror * inertia * mirror).cwiseAbs().maxCoeff() /
                                                          inertia.diagonal().maxCoeff());
    EXPECT_LT((left.com - mirror * com).norm(), 2e-4);  // README: SL left rows within 0.2 mm
    // README: within 1 % (of the largest diagonal element)
    EXPECT_LT((left.inertia - mirror * inertia * mirror).cwiseAbs().maxCoeff(), 0.01 * inertia.diagonal().maxCoeff());
  }
  std::printf(
      "mass error max %.1e kg; right COM and inertia at most %.2f and %.2f of their bounds; left vs mirror: "
      "COM %.3f mm, inertia %.2f %%\n",
      worst_mass, worst_com, worst_inertia, 1e3 * worst_left_com, 100 * worst_left_inertia);
}

TEST_F(Hoap3Model, TotalMassIsTheDatasheetSum) {
  double total = 0, datasheet_sum = 0;
  for (int b = 0; b < m()->nbody; ++b) total += m()->body_mass[b];
  for (const LinkMass& link : kLinkMasses) datasheet_sum += link.mass * (*link.mirror == '\0' ? 1 : 2);
  EXPECT_NEAR(total, datasheet_sum, kCopied) << "sum of the DATASHEET 3.4 link masses (8.8024 kg)";
  EXPECT_NEAR(total, kTotalMass, 5e-4) << "DATASHEET 3.4 total, printed to 1 g";
  EXPECT_NEAR(SubtreeMass(m(), Id(m(), mjOBJ_BODY, "hoap3_pelvis")), total, 1e-12) << "mass outside the robot";
}
}  // namespace
}  // namespace vlab::models::testing
