#include "models/hoap3_balance.h"

#include <algorithm>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>

#include "models/support_polygon.h"

namespace vlab::models::testing {

namespace {

// FSR touch sensors and their sites share names: right foot FR, FL, BR, BL, then left
constexpr const char* kFsrNames[8] = {"hoap3_rfoot_fr", "hoap3_rfoot_fl", "hoap3_rfoot_br", "hoap3_rfoot_bl",
                                      "hoap3_lfoot_fr", "hoap3_lfoot_fl", "hoap3_lfoot_br", "hoap3_lfoot_bl"};

}  // namespace

std::unique_ptr<Hoap3Balance> Hoap3Balance::Create(const mjModel* m) {
  std::unique_ptr<Hoap3Balance> c(new Hoap3Balance());
  c->model_ = m;
  const int n = m->nu;
  c->kp_.resize(n);
  c->kd_.resize(n);
  c->lower_.resize(n);
  c->upper_.resize(n);
  for (int a = 0; a < n; ++a) {
    const int j = m->actuator_trnid[2 * a];
    if (m->actuator_trntype[a] != mjTRN_JOINT || m->jnt_type[j] != mjJNT_HINGE) {
      ADD_FAILURE() << "actuator " << a << " is not on a hinge joint";
      return nullptr;
    }
    c->actuators_.push_back(a);
    c->qpos_adr_.push_back(m->jnt_qposadr[j]);
    c->dof_adr_.push_back(m->jnt_dofadr[j]);
    // servo joints (|tau| <= 0.36 N m) move light links: a tenth of the gains
    const double scale = m->actuator_ctrlrange[2 * a + 1] > 1.0 ? 1.0 : 0.1;
    c->kp_[a] = kStiffness * scale;
    c->kd_[a] = kDamping * scale;
    c->lower_[a] = m->actuator_ctrlrange[2 * a];
    c->upper_[a] = m->actuator_ctrlrange[2 * a + 1];
  }
  c->right_sole_ = mj_name2id(m, mjOBJ_SITE, "hoap3_rfoot_sole");
  c->left_sole_ = mj_name2id(m, mjOBJ_SITE, "hoap3_lfoot_sole");
  if (c->right_sole_ < 0 || c->left_sole_ < 0) {
    ADD_FAILURE() << "no sole sites hoap3_rfoot_sole / hoap3_lfoot_sole";
    return nullptr;
  }
  for (const char* name : kFsrNames) {
    const int sensor = mj_name2id(m, mjOBJ_SENSOR, name);
    const int site = mj_name2id(m, mjOBJ_SITE, name);
    if (sensor < 0 || site < 0 || m->sensor_type[sensor] != mjSENS_TOUCH) {
      ADD_FAILURE() << "no touch sensor and site '" << name << "'";
      return nullptr;
    }
    c->fsr_sensors_.push_back(sensor);
    c->fsr_sites_.push_back(site);
  }
  c->jac_feet_.resize(12, m->nv);
  c->jacp_.resize(3 * m->nv);
  c->jacr_.resize(3 * m->nv);
  return c;
}

int Hoap3Balance::Index(const std::string& joint) const {
  const int j = mj_name2id(model_, mjOBJ_JOINT, joint.c_str());
  for (int i = 0; j >= 0 && i < dof(); ++i) {
    if (qpos_adr_[i] == model_->jnt_qposadr[j]) return i;
  }
  return -1;
}

Eigen::VectorXd Hoap3Balance::Positions(const mjData& d) const {
  Eigen::VectorXd q(dof());
  for (int i = 0; i < dof(); ++i) q[i] = d.qpos[qpos_adr_[i]];
  return q;
}

void Hoap3Balance::Actuate(const Eigen::VectorXd& q_ref, mjData& d) {
  const mjModel* m = model_;
  const int nv = m->nv;
  // foot Jacobians at the sole sites: rows 0-2 / 3-5 right force / moment, 6-11 left
  int row = 0;
  for (int site : {right_sole_, left_sole_}) {
    mj_jacSite(m, &d, jacp_.data(), jacr_.data(), site);
    for (int r = 0; r < 3; ++r) {
      for (int col = 0; col < nv; ++col) {
        jac_feet_(row + r, col) = jacp_[r * nv + col];
        jac_feet_(row + 3 + r, col) = jacr_[r * nv + col];
      }
    }
    row += 6;
  }
  // floating base (dofs 0-5): minimum-norm foot wrenches f with A f = bias_base
  const Eigen::Map<const Eigen::VectorXd> bias(d.qfrc_bias, nv);
  const Eigen::Matrix<double, 6, 12> a = jac_feet_.leftCols<6>().transpose();
  const Eigen::Matrix<double, 6, 1> y = (a * a.transpose()).ldlt().solve(bias.head<6>());
  const Eigen::Matrix<double, 12, 1> f = a.transpose() * y;
  for (int i = 0; i < dof(); ++i) {
    const int v = dof_adr_[i];
    const double tau_g = bias[v] - jac_feet_.col(v).dot(f);
    const double tau = tau_g + kp_[i] * (q_ref[i] - d.qpos[qpos_adr_[i]]) - kd_[i] * d.qvel[v];
    d.ctrl[actuators_[i]] = std::clamp(tau, lower_[i], upper_[i]);
  }
}

FootReading Hoap3Balance::ReadFeet(const mjData& d) const {
  std::vector<Eigen::Vector2d> pads;
  std::vector<double> forces;
  for (size_t i = 0; i < fsr_sites_.size(); ++i) {
    const mjtNum* p = d.site_xpos + 3 * fsr_sites_[i];
    pads.emplace_back(p[0], p[1]);
    forces.push_back(d.sensordata[model_->sensor_adr[fsr_sensors_[i]]]);
  }
  FootReading reading;
  for (double f : forces) reading.force_sum_N += f;
  reading.cop_W = CentreOfPressure(pads, forces);
  reading.margin_m = InsideMargin(ConvexHull(pads), reading.cop_W);
  return reading;
}

}  // namespace vlab::models::testing
