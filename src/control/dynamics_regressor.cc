#include "control/dynamics_regressor.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Geometry>
#include <Eigen/QR>
#include <Eigen/SVD>

namespace vlab::control {

namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using Matrix3x10 = Eigen::Matrix<double, 3, 10>;

Matrix3d Skew(const Vector3d& v) {
  Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

// I·w as a linear map of (Ixx, Iyy, Izz, Ixy, Ixz, Iyz)
Eigen::Matrix<double, 3, 6> InertiaTimes(const Vector3d& w) {
  Eigen::Matrix<double, 3, 6> l;
  l << w.x(), 0, 0, w.y(), w.z(), 0,  //
      0, w.y(), 0, w.x(), 0, w.z(),   //
      0, 0, w.z(), 0, w.x(), w.y();
  return l;
}

Matrix3d BodyRotation(const mjData& d, int body) { return Eigen::Map<const Matrix3d>(d.xmat + 9 * body).transpose(); }
Vector3d BodyPosition(const mjData& d, int body) { return Eigen::Map<const Vector3d>(d.xpos + 3 * body); }

}  // namespace

DynamicsRegressor::DynamicsRegressor(const mjModel* model, mjData* data) : model_(model), data_(data) {}

DynamicsRegressor::~DynamicsRegressor() { mj_deleteData(data_); }

std::unique_ptr<DynamicsRegressor> DynamicsRegressor::Create(const mjModel* model,
                                                             const std::vector<std::string>& joints,
                                                             const std::vector<double>& reference_qpos) {
  if (joints.empty()) throw std::invalid_argument("dynamics regressor: no joints given");
  if (!reference_qpos.empty() && static_cast<int>(reference_qpos.size()) != model->nq) {
    throw std::invalid_argument("dynamics regressor: the reference pose has " + std::to_string(reference_qpos.size()) +
                                " values, the model " + std::to_string(model->nq));
  }
  std::unique_ptr<DynamicsRegressor> r(new DynamicsRegressor(model, mj_makeData(model)));
  r->reference_qpos_ = reference_qpos;
  if (r->reference_qpos_.empty()) r->reference_qpos_.assign(model->qpos0, model->qpos0 + model->nq);
  const int n = static_cast<int>(joints.size());
  r->lower_.resize(n);
  r->upper_.resize(n);
  for (int i = 0; i < n; ++i) {
    const std::string& name = joints[i];
    Joint j;
    j.id = mj_name2id(model, mjOBJ_JOINT, name.c_str());
    if (j.id < 0) throw std::invalid_argument("dynamics regressor: the model has no joint '" + name + "'");
    const int type = model->jnt_type[j.id];
    if (type != mjJNT_HINGE && type != mjJNT_SLIDE) {
      throw std::invalid_argument("dynamics regressor: joint '" + name + "' is not a hinge or slide");
    }
    j.hinge = type == mjJNT_HINGE;
    j.body = model->jnt_bodyid[j.id];
    j.qpos_adr = model->jnt_qposadr[j.id];
    j.dof_adr = model->jnt_dofadr[j.id];
    if (model->body_jntnum[j.body] != 1) {
      throw std::invalid_argument("dynamics regressor: joint '" + name + "' shares its body with another joint");
    }
    if (i > 0) {  // below the previous joint's body
      int b = model->body_parentid[j.body];
      while (b > 0 && b != r->joints_.back().body) b = model->body_parentid[b];
      if (b != r->joints_.back().body) {
        throw std::invalid_argument("dynamics regressor: joint '" + name + "' is not below joint '" + joints[i - 1] +
                                    "'");
      }
    }
    const bool limited = model->jnt_limited[j.id];
    r->lower_[i] = limited ? model->jnt_range[2 * j.id] : -std::numeric_limits<double>::infinity();
    r->upper_[i] = limited ? model->jnt_range[2 * j.id + 1] : std::numeric_limits<double>::infinity();
    r->joints_.push_back(j);
    r->joint_names_.push_back(name);
    r->qpos_adr_.push_back(j.qpos_adr);
  }
  // each body's link: the nearest chain joint's body at or above it (bodies come after their parents)
  r->link_of_body_.assign(model->nbody, -1);
  for (int i = 0; i < n; ++i) r->link_of_body_[r->joints_[i].body] = i;
  for (int b = 1; b < model->nbody; ++b) {
    if (r->link_of_body_[b] < 0) r->link_of_body_[b] = r->link_of_body_[model->body_parentid[b]];
  }
  static const char* const kLinkNames[kLinkParameters] = {"m",   "mx",  "my",  "mz",  "Ixx",
                                                          "Iyy", "Izz", "Ixy", "Ixz", "Iyz"};
  for (int i = 0; i < n; ++i) {
    const char* body = mj_id2name(model, mjOBJ_BODY, r->joints_[i].body);
    const std::string prefix = body ? body : "body" + std::to_string(r->joints_[i].body);
    for (const char* p : kLinkNames) r->names_.push_back(prefix + "." + p);
  }
  for (const char* p : {"damping", "frictionloss", "armature"}) {
    for (const std::string& joint : joints) r->names_.push_back(joint + "." + p);
  }
  return r;
}

Eigen::VectorXd DynamicsRegressor::Parameters(const mjModel& model) const {
  const int n = dof();
  Eigen::VectorXd pi = Eigen::VectorXd::Zero(parameters());
  std::copy(reference_qpos_.begin(), reference_qpos_.end(), data_->qpos);
  mj_kinematics(&model, data_);
  for (int b = 1; b < model.nbody; ++b) {
    const int link = link_of_body_[b];
    if (link < 0) continue;
    const int lb = joints_[link].body;
    // the body's inertia in the link's frame, about the link's origin (parallel axes)
    const Matrix3d R_L = BodyRotation(*data_, lb);
    const Matrix3d R_rel = R_L.transpose() * BodyRotation(*data_, b);
    const Vector3d p_rel = R_L.transpose() * (BodyPosition(*data_, b) - BodyPosition(*data_, lb));
    const double m = model.body_mass[b];
    const Vector3d c = p_rel + R_rel * Eigen::Map<const Vector3d>(model.body_ipos + 3 * b);
    const Eigen::Quaterniond iq(model.body_iquat[4 * b], model.body_iquat[4 * b + 1], model.body_iquat[4 * b + 2],
                                model.body_iquat[4 * b + 3]);
    const Matrix3d R_i = R_rel * iq.normalized().toRotationMatrix();
    const Matrix3d I_com = R_i * Eigen::Map<const Vector3d>(model.body_inertia + 3 * b).asDiagonal() * R_i.transpose();
    const Matrix3d I_o = I_com + m * (c.squaredNorm() * Matrix3d::Identity() - c * c.transpose());
    double* p = pi.data() + kLinkParameters * link;
    p[0] += m;
    for (int k = 0; k < 3; ++k) p[1 + k] += m * c[k];
    p[4] += I_o(0, 0), p[5] += I_o(1, 1), p[6] += I_o(2, 2);
    p[7] += I_o(0, 1), p[8] += I_o(0, 2), p[9] += I_o(1, 2);
  }
  for (int j = 0; j < n; ++j) {
    const int dof_adr = joints_[j].dof_adr;
    pi[kLinkParameters * n + j] = model.dof_damping[dof_adr];
    pi[kLinkParameters * n + n + j] = model.dof_frictionloss[dof_adr];
    pi[kLinkParameters * n + 2 * n + j] = model.dof_armature[dof_adr];
  }
  return pi;
}

void DynamicsRegressor::Compute(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd,
                                Eigen::MatrixXd* Y) {
  const int n = dof();
  if (q.size() != n || qd.size() != n || qdd.size() != n) {
    throw std::invalid_argument("dynamics regressor: expected " + std::to_string(n) + " joint values");
  }
  Y->setZero(n, parameters());
  std::copy(reference_qpos_.begin(), reference_qpos_.end(), data_->qpos);
  for (int i = 0; i < n; ++i) data_->qpos[joints_[i].qpos_adr] = q[i];
  mj_kinematics(model_, data_);
  // the chain's motion, world frame: the base at rest, accelerating against gravity
  Vector3d w = Vector3d::Zero(), dw = Vector3d::Zero();
  Vector3d o = BodyPosition(*data_, joints_[0].body), v = Vector3d::Zero();
  Vector3d a = -Eigen::Map<const Vector3d>(model_->opt.gravity);
  for (int i = 0; i < n; ++i) {
    const Joint& j = joints_[i];
    const Vector3d u = Eigen::Map<const Vector3d>(data_->xaxis + 3 * j.id);
    const Vector3d anchor = Eigen::Map<const Vector3d>(data_->xanchor + 3 * j.id);
    const Vector3d o_next = BodyPosition(*data_, j.body);
    if (j.hinge) {
      // the anchor moves with the parent; the link turns about it
      const Vector3d r_a = anchor - o;
      const Vector3d v_a = v + w.cross(r_a);
      const Vector3d a_a = a + dw.cross(r_a) + w.cross(w.cross(r_a));
      const Vector3d w_next = w + u * qd[i];
      dw = dw + u * qdd[i] + w.cross(u * qd[i]);
      w = w_next;
      const Vector3d r = o_next - anchor;
      v = v_a + w.cross(r);
      a = a_a + dw.cross(r) + w.cross(w.cross(r));
    } else {
      const Vector3d r = o_next - o;
      a = a + dw.cross(r) + w.cross(w.cross(r)) + 2 * w.cross(u * qd[i]) + u * qdd[i];
      v = v + w.cross(r) + u * qd[i];
    }
    o = o_next;
    // the link's wrench at its origin, body frame, as a linear map of its parameters:
    // f = m a + dw x h + w x (w x h), n = I dw + w x (I w) + h x a (Atkeson et al. 1986)
    const Matrix3d R = BodyRotation(*data_, j.body);
    const Vector3d wb = R.transpose() * w, dwb = R.transpose() * dw, ab = R.transpose() * a;
    Matrix3x10 F = Matrix3x10::Zero(), N = Matrix3x10::Zero();
    F.col(0) = ab;
    F.block<3, 3>(0, 1) = Skew(dwb) + Skew(wb) * Skew(wb);
    N.block<3, 3>(0, 1) = -Skew(ab);
    N.block<3, 6>(0, 4) = InertiaTimes(dwb) + Skew(wb) * InertiaTimes(wb);
    const Matrix3x10 F_W = R * F, N_W = R * N;
    // every joint at or above the link carries it
    for (int k = 0; k <= i; ++k) {
      const Joint& jk = joints_[k];
      const Vector3d uk = Eigen::Map<const Vector3d>(data_->xaxis + 3 * jk.id);
      if (jk.hinge) {
        const Vector3d lever = o - Eigen::Map<const Vector3d>(data_->xanchor + 3 * jk.id);
        Y->block<1, 10>(k, kLinkParameters * i) = uk.transpose() * (N_W + Skew(lever) * F_W);
      } else {
        Y->block<1, 10>(k, kLinkParameters * i) = uk.transpose() * F_W;
      }
    }
  }
  for (int i = 0; i < n; ++i) {
    (*Y)(i, kLinkParameters * n + i) = qd[i];
    (*Y)(i, kLinkParameters * n + n + i) = (qd[i] > 0) - (qd[i] < 0);
    (*Y)(i, kLinkParameters * n + 2 * n + i) = qdd[i];
  }
}

BaseParameters FindBaseParameters(const Eigen::MatrixXd& W, double relative_tolerance) {
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(W);
  const Eigen::MatrixXd R = qr.matrixR().template triangularView<Eigen::Upper>();
  const int p = static_cast<int>(W.cols());
  const int diag = static_cast<int>(std::min(W.rows(), W.cols()));
  const double largest = diag > 0 ? std::abs(R(0, 0)) : 0.0;
  int rank = 0;
  while (rank < diag && std::abs(R(rank, rank)) > relative_tolerance * largest) ++rank;
  const Eigen::VectorXi perm = qr.colsPermutation().indices();
  BaseParameters base;
  // K = R11^-1 R12 in pivoted order, then both lists sorted into Y's order
  const Eigen::MatrixXd K_pivoted =
      R.topLeftCorner(rank, rank).triangularView<Eigen::Upper>().solve(R.block(0, rank, rank, p - rank));
  std::vector<int> ind_order(rank), dep_order(p - rank);
  for (int k = 0; k < rank; ++k) ind_order[k] = k;
  for (int k = 0; k < p - rank; ++k) dep_order[k] = k;
  std::sort(ind_order.begin(), ind_order.end(), [&](int x, int y) { return perm[x] < perm[y]; });
  std::sort(dep_order.begin(), dep_order.end(), [&](int x, int y) { return perm[rank + x] < perm[rank + y]; });
  base.K.resize(rank, p - rank);
  for (int r = 0; r < rank; ++r) {
    base.independent.push_back(perm[ind_order[r]]);
    for (int c = 0; c < p - rank; ++c) base.K(r, c) = K_pivoted(ind_order[r], dep_order[c]);
  }
  for (int c = 0; c < p - rank; ++c) base.dependent.push_back(perm[rank + dep_order[c]]);
  return base;
}

double ConditionNumber(const Eigen::MatrixXd& A) {
  if (A.size() == 0) return std::numeric_limits<double>::infinity();
  const Eigen::VectorXd s = Eigen::JacobiSVD<Eigen::MatrixXd>(A).singularValues();
  const double smallest = s[s.size() - 1];
  return smallest > 0 ? s[0] / smallest : std::numeric_limits<double>::infinity();
}

}  // namespace vlab::control
