#include "control/robot_model.h"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace vlab::control {

namespace {

std::string Name(const mjModel* m, mjtObj type, int id) {
  const char* name = mj_id2name(m, type, id);
  return name ? name : "#" + std::to_string(id);
}

}  // namespace

RobotModel::RobotModel(const mjModel* model, mjData* data) : model_(model), data_(data) {}

RobotModel::~RobotModel() { mj_deleteData(data_); }

std::unique_ptr<RobotModel> RobotModel::Create(const mjModel* m, const Config& config) {
  if (!m) throw std::invalid_argument("robot model: no MuJoCo model");
  const int site = mj_name2id(m, mjOBJ_SITE, config.tip_site.c_str());
  if (site < 0) throw std::invalid_argument("robot model: no site '" + config.tip_site + "'");
  const int base = mj_name2id(m, mjOBJ_BODY, config.base_body.c_str());
  if (base < 0) throw std::invalid_argument("robot model: no body '" + config.base_body + "'");

  // walk from the tip body up to the base body, collecting joints
  std::vector<int> joints;
  int body = m->site_bodyid[site];
  while (body != base) {
    if (body == 0) {
      throw std::invalid_argument("robot model: body '" + config.base_body + "' is not an ancestor of site '" +
                                  config.tip_site + "'");
    }
    // a body's joints are stored consecutively; keep them in model order
    std::vector<int> body_joints;
    for (int j = m->body_jntadr[body]; j >= 0 && j < m->body_jntadr[body] + m->body_jntnum[body]; ++j) {
      const int type = m->jnt_type[j];
      if (type != mjJNT_HINGE && type != mjJNT_SLIDE) {
        throw std::invalid_argument("robot model: joint '" + Name(m, mjOBJ_JOINT, j) + "' between '" +
                                    config.base_body + "' and site '" + config.tip_site + "' is not a hinge or slide");
      }
      body_joints.push_back(j);
    }
    joints.insert(joints.begin(), body_joints.begin(), body_joints.end());
    body = m->body_parentid[body];
  }
  if (joints.empty()) {
    throw std::invalid_argument("robot model: no joints between body '" + config.base_body + "' and site '" +
                                config.tip_site + "'");
  }

  mjData* d = mj_makeData(m);
  if (!d) throw std::runtime_error("robot model: mj_makeData failed");
  std::unique_ptr<RobotModel> rm(new RobotModel(m, d));
  rm->site_id_ = site;
  rm->joint_ids_ = joints;
  const int n = static_cast<int>(joints.size());
  rm->lower_.resize(n);
  rm->upper_.resize(n);
  const double inf = std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i) {
    const int j = joints[i];
    rm->qpos_addresses_.push_back(m->jnt_qposadr[j]);
    rm->dof_addresses_.push_back(m->jnt_dofadr[j]);
    rm->joint_names_.push_back(Name(m, mjOBJ_JOINT, j));
    rm->lower_[i] = m->jnt_limited[j] ? m->jnt_range[2 * j] : -inf;
    rm->upper_[i] = m->jnt_limited[j] ? m->jnt_range[2 * j + 1] : inf;
  }
  rm->full_m_.resize(static_cast<size_t>(m->nv) * m->nv);
  rm->rne_.resize(m->nv);
  rm->jacp_.resize(3 * static_cast<size_t>(m->nv));
  rm->jacr_.resize(3 * static_cast<size_t>(m->nv));
  rm->Recompute();
  return rm;
}

Eigen::VectorXd RobotModel::ChainPositions(const mjData& d) const {
  Eigen::VectorXd q(dof());
  for (int i = 0; i < dof(); ++i) q[i] = d.qpos[qpos_addresses_[i]];
  return q;
}

Eigen::VectorXd RobotModel::ChainVelocities(const mjData& d) const {
  Eigen::VectorXd qd(dof());
  for (int i = 0; i < dof(); ++i) qd[i] = d.qvel[dof_addresses_[i]];
  return qd;
}

void RobotModel::SetState(const mjData& d) {
  std::copy(d.qpos, d.qpos + model_->nq, data_->qpos);
  std::copy(d.qvel, d.qvel + model_->nv, data_->qvel);
  Recompute();
}

void RobotModel::SetState(const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  if (q.size() != dof() || qd.size() != dof()) {
    throw std::invalid_argument("robot model: state size " + std::to_string(q.size()) + "/" +
                                std::to_string(qd.size()) + " != dof " + std::to_string(dof()));
  }
  std::fill(data_->qvel, data_->qvel + model_->nv, 0.0);
  for (int i = 0; i < dof(); ++i) {
    data_->qpos[qpos_addresses_[i]] = q[i];
    data_->qvel[dof_addresses_[i]] = qd[i];
  }
  Recompute();
}

void RobotModel::Recompute() {
  // kinematics now (every quantity needs it); inertia and velocity terms on demand
  mj_kinematics(model_, data_);
  mj_comPos(model_, data_);
  inertia_ready_ = false;
  velocity_ready_ = false;
}

void RobotModel::EnsureInertia() const {
  if (inertia_ready_) return;
  mj_crb(model_, data_);
  inertia_ready_ = true;
}

void RobotModel::EnsureVelocity() const {
  if (velocity_ready_) return;
  mj_comVel(model_, data_);
  velocity_ready_ = true;
}

Pose RobotModel::TipPose() const {
  Pose pose;
  for (int r = 0; r < 3; ++r) {
    pose.p_W[r] = data_->site_xpos[3 * site_id_ + r];
    for (int c = 0; c < 3; ++c) pose.R_W(r, c) = data_->site_xmat[9 * site_id_ + 3 * r + c];
  }
  return pose;
}

Eigen::MatrixXd RobotModel::Jacobian() const {
  mj_jacSite(model_, data_, jacp_.data(), jacr_.data(), site_id_);
  const int nv = model_->nv;
  Eigen::MatrixXd J(6, dof());
  for (int i = 0; i < dof(); ++i) {
    const int v = dof_addresses_[i];
    for (int r = 0; r < 3; ++r) {
      J(r, i) = jacp_[r * nv + v];
      J(3 + r, i) = jacr_[r * nv + v];
    }
  }
  return J;
}

Eigen::MatrixXd RobotModel::MassMatrix() const {
  EnsureInertia();
  mj_fullM(model_, full_m_.data(), data_->qM);
  const int nv = model_->nv;
  Eigen::MatrixXd H(dof(), dof());
  for (int i = 0; i < dof(); ++i) {
    for (int j = 0; j < dof(); ++j) H(i, j) = full_m_[dof_addresses_[i] * nv + dof_addresses_[j]];
  }
  return H;
}

Eigen::VectorXd RobotModel::Bias() const {
  Eigen::VectorXd h;
  Bias(&h);
  return h;
}

Eigen::VectorXd RobotModel::Gravity() const {
  Eigen::VectorXd g;
  Gravity(&g);
  return g;
}

void RobotModel::Bias(Eigen::VectorXd* out) const {
  EnsureVelocity();
  mj_rne(model_, data_, 0, rne_.data());
  out->resize(dof());
  for (int i = 0; i < dof(); ++i) (*out)[i] = rne_[dof_addresses_[i]];
}

void RobotModel::Gravity(Eigen::VectorXd* out) const {
  // rne with zero velocity leaves only gravity; restore the velocity state after
  const int nv = model_->nv;
  std::vector<mjtNum>& saved = jacp_;  // 3·nv >= nv scratch, refilled by Jacobian()
  std::copy(data_->qvel, data_->qvel + nv, saved.begin());
  std::fill(data_->qvel, data_->qvel + nv, 0.0);
  mj_comVel(model_, data_);
  mj_rne(model_, data_, 0, rne_.data());
  std::copy(saved.begin(), saved.begin() + nv, data_->qvel);
  velocity_ready_ = false;
  out->resize(dof());
  for (int i = 0; i < dof(); ++i) (*out)[i] = rne_[dof_addresses_[i]];
}

}  // namespace vlab::control
