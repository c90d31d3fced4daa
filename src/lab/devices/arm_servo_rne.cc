#include "lab/devices/arm_servo_rne.h"

#include <cmath>
#include <string>

#include <Eigen/Geometry>

#include "core/core_errors.h"

namespace vlab::lab {

namespace {

using RowMatrix = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;

Eigen::Matrix3d QuatToMatrix(const double* quat) {
  double mat[9];
  mju_quat2Mat(mat, quat);
  return Eigen::Map<const RowMatrix>(mat);
}

}  // namespace

ChainRne::ChainRne(const mjModel& m) : bodies_(m.nbody), joints_(m.njnt), first_joint_(m.nbody), joint_count_(m.nbody) {
  for (int j = 0; j < m.njnt; ++j) {
    if (m.jnt_type[j] != mjJNT_HINGE && m.jnt_type[j] != mjJNT_SLIDE) {
      throw InputError("servo model: joint " + std::to_string(j) + " is not a hinge or slide");
    }
  }
  Refresh(m);
}

void ChainRne::Refresh(const mjModel& m) {
  for (int i = 0; i < m.nbody; ++i) {
    Body& b = bodies_[i];
    b.parent = m.body_parentid[i];
    b.offset = Eigen::Map<const Eigen::Vector3d>(m.body_pos + 3 * i);
    b.offset_rotation = QuatToMatrix(m.body_quat + 4 * i);
    b.offset_is_identity = b.offset_rotation == Eigen::Matrix3d::Identity();
    b.inertial_rotation = QuatToMatrix(m.body_iquat + 4 * i);
    b.inertial_pos = Eigen::Map<const Eigen::Vector3d>(m.body_ipos + 3 * i);
    b.principal = Eigen::Map<const Eigen::Vector3d>(m.body_inertia + 3 * i);
    b.mass = m.body_mass[i];
    first_joint_[i] = m.body_jntadr[i];
    joint_count_[i] = m.body_jntadr[i] >= 0 ? m.body_jntnum[i] : 0;
  }
  for (int j = 0; j < m.njnt; ++j) {
    Joint& joint = joints_[j];
    joint.local_axis = Eigen::Map<const Eigen::Vector3d>(m.jnt_axis + 3 * j);
    joint.local_pos = Eigen::Map<const Eigen::Vector3d>(m.jnt_pos + 3 * j);
    joint.hinge = m.jnt_type[j] == mjJNT_HINGE;
    joint.qpos_adr = m.jnt_qposadr[j];
    joint.dof_adr = m.jnt_dofadr[j];
    joint.qpos0 = m.qpos0[joint.qpos_adr];
  }
  gravity_accel_ = -Eigen::Map<const Eigen::Vector3d>(m.opt.gravity);
  if (m.opt.disableflags & mjDSBL_GRAVITY) gravity_accel_.setZero();

  // the local pass: one hinge at most per body, at its origin
  local_ = true;
  for (int i = 1; i < m.nbody; ++i) {
    Body& b = bodies_[i];
    b.inertia_com = b.inertial_rotation * b.principal.asDiagonal() * b.inertial_rotation.transpose();
    b.joint = joint_count_[i] == 1 ? first_joint_[i] : -1;
    b.axis_index = -1;
    if (joint_count_[i] > 1) local_ = false;
    if (b.joint < 0) continue;
    const Joint& joint = joints_[b.joint];
    if (!joint.hinge || !joint.local_pos.isZero(0.0)) local_ = false;
    for (int k = 0; k < 3; ++k) {
      if (joint.local_axis == Eigen::Vector3d::Unit(k)) b.axis_index = k;
    }
  }
}

void ChainRne::Bias(const mjModel& m, const double* qpos, const double* qvel, double* qfrc) {
  if (local_) {
    BiasLocal(m, qpos, qvel, qfrc);
  } else {
    BiasWorld(m, qpos, qvel, qfrc);
  }
}

void ChainRne::BiasLocal(const mjModel& m, const double* qpos, const double* qvel, double* qfrc) {
  // in each body's frame: omega, its rate, the origin's acceleration (gravity as -g); the
  // world's frame is the world's
  Body& world = bodies_[0];
  world.rotation.setIdentity();
  world.omega.setZero();
  world.alpha.setZero();
  world.accel = gravity_accel_;
  world.force.setZero();
  world.moment.setZero();

  for (int i = 1; i < m.nbody; ++i) {
    Body& b = bodies_[i];
    const Body& parent = bodies_[b.parent];
    // rotation: the body's frame in its parent's (offset, then its hinge), R = Q Rot(axis, q)
    double qd = 0.0;
    b.rotation = b.offset_rotation;
    Eigen::Vector3d axis = Eigen::Vector3d::Zero();
    if (b.joint >= 0) {
      const Joint& joint = joints_[b.joint];
      const double q = qpos[joint.qpos_adr] - joint.qpos0;
      qd = qvel[joint.dof_adr];
      axis = joint.local_axis;
      const double s = std::sin(q), c = std::cos(q);
      if (b.axis_index >= 0) {
        // about a frame axis: the other two columns turn
        const int u = (b.axis_index + 1) % 3, v = (b.axis_index + 2) % 3;
        const Eigen::Vector3d cu = b.offset_rotation.col(u), cv = b.offset_rotation.col(v);
        b.rotation.col(u) = c * cu + s * cv;
        b.rotation.col(v) = c * cv - s * cu;
      } else {
        b.rotation = b.offset_rotation * Eigen::AngleAxisd(q, axis).toRotationMatrix();
      }
    }
    const Eigen::Matrix3d rt = b.rotation.transpose();
    // the parent's motion carried to this origin, then into this frame
    const Eigen::Vector3d parent_omega = rt * parent.omega;
    const Eigen::Vector3d joint_rate = axis * qd;
    b.omega = parent_omega + joint_rate;
    b.alpha = rt * parent.alpha + parent_omega.cross(joint_rate);
    b.accel = rt * (parent.accel + parent.alpha.cross(b.offset) + parent.omega.cross(parent.omega.cross(b.offset)));
    // Newton-Euler at the centre of mass; the moment about the body's origin
    const Eigen::Vector3d& c_i = b.inertial_pos;
    const Eigen::Vector3d com_accel = b.accel + b.alpha.cross(c_i) + b.omega.cross(b.omega.cross(c_i));
    b.force = b.mass * com_accel;
    b.moment = b.inertia_com * b.alpha + b.omega.cross(b.inertia_com * b.omega) + c_i.cross(b.force);
  }

  // backward: the subtree's wrench about each origin, in its frame; a hinge takes its axis' part
  for (int i = m.nbody - 1; i > 0; --i) {
    Body& b = bodies_[i];
    if (b.joint >= 0) qfrc[joints_[b.joint].dof_adr] = joints_[b.joint].local_axis.dot(b.moment);
    Body& parent = bodies_[b.parent];
    const Eigen::Vector3d force = b.rotation * b.force;
    parent.force += force;
    parent.moment += b.rotation * b.moment + b.offset.cross(force);
  }
}

void ChainRne::BiasWorld(const mjModel& m, const double* qpos, const double* qvel, double* qfrc) {
  // the world: at rest, accelerating against gravity
  Body& world = bodies_[0];
  world.rotation.setIdentity();
  world.position.setZero();
  world.omega.setZero();
  world.velocity.setZero();
  world.alpha.setZero();
  world.force.setZero();
  world.moment.setZero();
  world.accel = gravity_accel_;

  // forward: frames, twists, accelerations; each body's own wrench
  for (int i = 1; i < m.nbody; ++i) {
    Body& b = bodies_[i];
    const Body& parent = bodies_[b.parent];
    b.position = parent.position + parent.rotation * b.offset;
    b.rotation = b.offset_is_identity ? parent.rotation : Eigen::Matrix3d(parent.rotation * b.offset_rotation);
    b.omega = parent.omega;
    b.velocity = parent.velocity;
    b.alpha = parent.alpha;
    b.accel = parent.accel;
    for (int j = first_joint_[i]; j < first_joint_[i] + joint_count_[i]; ++j) {
      Joint& joint = joints_[j];
      const double q = qpos[joint.qpos_adr] - joint.qpos0;
      const double qd = qvel[joint.dof_adr];
      joint.axis = b.rotation * joint.local_axis;
      joint.anchor = b.position + b.rotation * joint.local_pos;
      // the joint's motion S as a twist at the origin, and its rate
      Eigen::Vector3d s_angular = Eigen::Vector3d::Zero(), s_linear = joint.axis;
      if (joint.hinge) {
        b.rotation = b.rotation * Eigen::AngleAxisd(q, joint.local_axis).toRotationMatrix();
        b.position = joint.anchor - b.rotation * joint.local_pos;
        s_angular = joint.axis;
        s_linear = joint.anchor.cross(joint.axis);
      } else {
        b.position += joint.axis * q;
      }
      // A += (V x S) qd, then V += S qd
      b.alpha += b.omega.cross(s_angular) * qd;
      b.accel += (b.omega.cross(s_linear) + b.velocity.cross(s_angular)) * qd;
      b.omega += s_angular * qd;
      b.velocity += s_linear * qd;
    }
    // Newton-Euler at the centre of mass, then as a wrench about the origin
    const Eigen::Matrix3d r_inertial = b.rotation * b.inertial_rotation;
    const Eigen::Vector3d com = b.position + b.rotation * b.inertial_pos;
    // I x = R diag(principal) R^T x, without forming I
    const auto inertia_times = [&](const Eigen::Vector3d& x) -> Eigen::Vector3d {
      return r_inertial * b.principal.cwiseProduct(r_inertial.transpose() * x);
    };
    const Eigen::Vector3d com_velocity = b.velocity + b.omega.cross(com);
    const Eigen::Vector3d com_accel = b.accel + b.alpha.cross(com) + b.omega.cross(com_velocity);
    b.force = b.mass * com_accel;
    b.moment = inertia_times(b.alpha) + b.omega.cross(inertia_times(b.omega)) + com.cross(b.force);
  }

  // backward: subtree wrenches, projected on each joint's motion
  for (int i = m.nbody - 1; i > 0; --i) {
    Body& b = bodies_[i];
    for (int j = first_joint_[i]; j < first_joint_[i] + joint_count_[i]; ++j) {
      const Joint& joint = joints_[j];
      qfrc[joint.dof_adr] =
          joint.hinge ? joint.axis.dot(b.moment - joint.anchor.cross(b.force)) : joint.axis.dot(b.force);
    }
    Body& parent = bodies_[b.parent];
    parent.force += b.force;
    parent.moment += b.moment;
  }
}

}  // namespace vlab::lab
