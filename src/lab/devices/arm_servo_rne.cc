#include "lab/devices/arm_servo_rne.h"

#include <cmath>
#include <string>

#include <Eigen/Geometry>

#include "core/core_errors.h"

namespace vlab::lab {

namespace {

using RowMatrix = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;

constexpr double kZero[3] = {0.0, 0.0, 0.0};

// 3-vector kernels on column-major 3x3 arrays, summing in the order Eigen's fixed-size
// expressions do (rows 0 and 1 of a product as one SSE2 pair, row 2 as a reduction, a dot as
// the pair then the third term), so that the scalar pass gives Eigen's results to the bit
inline void Times(const double* a, const double* x, double* out) {
  out[0] = a[0] * x[0] + a[3] * x[1] + a[6] * x[2];
  out[1] = a[1] * x[0] + a[4] * x[1] + a[7] * x[2];
  out[2] = a[2] * x[0] + (a[5] * x[1] + a[8] * x[2]);
}

// a^T x
inline void TransposeTimes(const double* a, const double* x, double* out) {
  out[0] = a[0] * x[0] + a[1] * x[1] + a[2] * x[2];
  out[1] = a[3] * x[0] + a[4] * x[1] + a[5] * x[2];
  out[2] = a[6] * x[0] + (a[7] * x[1] + a[8] * x[2]);
}

inline void Cross(const double* a, const double* b, double* out) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

inline double Dot(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

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
  // world's frame is the world's. Scalar arithmetic on the bodies' arrays (no temporaries),
  // each sum in the order of the Eigen expressions it replaced, so the torques are the same
  // to the bit (arm_servo_rne_test compares them with the general pass)
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
    const double* axis = kZero;
    if (b.joint >= 0) {
      const Joint& joint = joints_[b.joint];
      const double q = qpos[joint.qpos_adr] - joint.qpos0;
      qd = qvel[joint.dof_adr];
      axis = joint.local_axis.data();
      const double s = std::sin(q), c = std::cos(q);
      if (b.axis_index >= 0) {
        // about a frame axis: the other two columns turn
        const int u = (b.axis_index + 1) % 3, v = (b.axis_index + 2) % 3;
        for (int r = 0; r < 3; ++r) {
          const double cu = b.offset_rotation(r, u), cv = b.offset_rotation(r, v);
          b.rotation(r, u) = c * cu + s * cv;
          b.rotation(r, v) = c * cv - s * cu;
        }
      } else {
        b.rotation = b.offset_rotation * Eigen::AngleAxisd(q, joint.local_axis).toRotationMatrix();
      }
    }
    const double* rot = b.rotation.data();  // column-major: rot[3 * col + row]
    // the parent's motion carried to this origin, then into this frame
    double parent_omega[3], joint_rate[3], carried[3], rate_cross[3];
    TransposeTimes(rot, parent.omega.data(), parent_omega);
    for (int k = 0; k < 3; ++k) joint_rate[k] = axis[k] * qd;
    for (int k = 0; k < 3; ++k) b.omega[k] = parent_omega[k] + joint_rate[k];
    TransposeTimes(rot, parent.alpha.data(), carried);
    Cross(parent_omega, joint_rate, rate_cross);
    for (int k = 0; k < 3; ++k) b.alpha[k] = carried[k] + rate_cross[k];
    double lever[3], spin[3], whirl[3], origin_accel[3];
    Cross(parent.alpha.data(), b.offset.data(), lever);
    Cross(parent.omega.data(), b.offset.data(), spin);
    Cross(parent.omega.data(), spin, whirl);
    for (int k = 0; k < 3; ++k) origin_accel[k] = parent.accel[k] + lever[k] + whirl[k];
    TransposeTimes(rot, origin_accel, b.accel.data());
    // Newton-Euler at the centre of mass; the moment about the body's origin
    const double* c_i = b.inertial_pos.data();
    const double* omega = b.omega.data();
    double c_lever[3], c_spin[3], c_whirl[3];
    Cross(b.alpha.data(), c_i, c_lever);
    Cross(omega, c_i, c_spin);
    Cross(omega, c_spin, c_whirl);
    for (int k = 0; k < 3; ++k) b.force[k] = b.mass * (b.accel[k] + c_lever[k] + c_whirl[k]);
    double i_alpha[3], i_omega[3], gyro[3], c_force[3];
    Times(b.inertia_com.data(), b.alpha.data(), i_alpha);
    Times(b.inertia_com.data(), omega, i_omega);
    Cross(omega, i_omega, gyro);
    Cross(c_i, b.force.data(), c_force);
    for (int k = 0; k < 3; ++k) b.moment[k] = i_alpha[k] + gyro[k] + c_force[k];
  }

  // backward: the subtree's wrench about each origin, in its frame; a hinge takes its axis' part
  for (int i = m.nbody - 1; i > 0; --i) {
    Body& b = bodies_[i];
    if (b.joint >= 0) qfrc[joints_[b.joint].dof_adr] = Dot(joints_[b.joint].local_axis.data(), b.moment.data());
    Body& parent = bodies_[b.parent];
    const double* rot = b.rotation.data();
    double force[3], moment[3], arm[3];
    Times(rot, b.force.data(), force);
    Times(rot, b.moment.data(), moment);
    Cross(b.offset.data(), force, arm);
    for (int k = 0; k < 3; ++k) {
      parent.force[k] += force[k];
      parent.moment[k] += moment[k] + arm[k];
    }
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
