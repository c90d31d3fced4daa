#include "lab/devices/arm_welded.h"

#include <Eigen/Geometry>

namespace vlab::lab {

namespace {

// a body with one joint, a free joint, hanging from the world
bool IsFreeBody(const mjModel& m, int b) {
  return b > 0 && m.body_parentid[b] == 0 && m.body_jntnum[b] == 1 && m.jnt_type[m.body_jntadr[b]] == mjJNT_FREE;
}

// b is `root` or one of its descendants
bool InSubtree(const mjModel& m, int b, int root) {
  for (; b > 0; b = m.body_parentid[b]) {
    if (b == root) return true;
  }
  return false;
}

}  // namespace

ArmWelds ArmWelds::Find(const mjModel& m, const std::vector<int>& joint_ids) {
  ArmWelds out;
  if (joint_ids.empty()) return out;
  const int root = m.jnt_bodyid[joint_ids.front()];
  for (int e = 0; e < m.neq; ++e) {
    if (m.eq_type[e] != mjEQ_WELD || !m.eq_active[e]) continue;
    const int b1 = m.eq_obj1id[e], b2 = m.eq_obj2id[e];
    Weld w;
    w.eq = e;
    if (InSubtree(m, b1, root) && IsFreeBody(m, b2) && !InSubtree(m, b2, root)) {
      w.free_body = b2;
      w.arm_body = b1;
      w.free_is_body2 = true;
    } else if (InSubtree(m, b2, root) && IsFreeBody(m, b1) && !InSubtree(m, b1, root)) {
      w.free_body = b1;
      w.arm_body = b2;
      w.free_is_body2 = false;
    } else {
      continue;
    }
    const int j = m.body_jntadr[w.free_body];
    w.qpos_adr = m.jnt_qposadr[j];
    w.dof_adr = m.jnt_dofadr[j];
    out.welds_.push_back(w);
  }
  return out;
}

void ArmWelds::Place(const mjModel& m, mjData& d) const {
  for (const Weld& w : welds_) {
    // eq_data of a weld (MuJoCo 2.2.2): anchor (3, on body2), relpose position (3, on body1)
    // and quaternion (4); the weld holds q1 * q_rel = q2 and x1 + R1 p_rel = x2 + R2 anchor
    const mjtNum* data = m.eq_data + mjNEQDATA * w.eq;
    const Eigen::Vector3d anchor(data[0], data[1], data[2]);
    const Eigen::Vector3d p_rel(data[3], data[4], data[5]);
    const Eigen::Quaterniond q_rel = Eigen::Quaterniond(data[6], data[7], data[8], data[9]).normalized();
    const mjtNum* xq = d.xquat + 4 * w.arm_body;
    const Eigen::Quaterniond q_arm(xq[0], xq[1], xq[2], xq[3]);
    const Eigen::Vector3d x_arm(d.xpos[3 * w.arm_body], d.xpos[3 * w.arm_body + 1], d.xpos[3 * w.arm_body + 2]);
    Eigen::Quaterniond q;
    Eigen::Vector3d x;
    if (w.free_is_body2) {
      q = (q_arm * q_rel).normalized();
      x = x_arm + q_arm * p_rel - q * anchor;
    } else {
      q = (q_arm * q_rel.conjugate()).normalized();
      x = x_arm + q_arm * anchor - q * p_rel;
    }
    mjtNum* qpos = d.qpos + w.qpos_adr;
    qpos[0] = x.x();
    qpos[1] = x.y();
    qpos[2] = x.z();
    qpos[3] = q.w();
    qpos[4] = q.x();
    qpos[5] = q.y();
    qpos[6] = q.z();
    for (int k = 0; k < 6; ++k) d.qvel[w.dof_adr + k] = 0;
  }
}

}  // namespace vlab::lab
