#include "control/joint_pd.h"

#include <stdexcept>
#include <string>

namespace vlab::control {

namespace {

void CheckSize(const char* name, const Eigen::VectorXd& v, Eigen::Index n) {
  if (v.size() != n) {
    throw std::invalid_argument(std::string("joint pd: ") + name + " has size " + std::to_string(v.size()) +
                                ", q has size " + std::to_string(n));
  }
}

}  // namespace

Eigen::VectorXd JointPdGravityTorque(const JointPdGains& gains, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                     const Eigen::VectorXd& q_des, const Eigen::VectorXd& qd_des,
                                     const Eigen::VectorXd& g) {
  Eigen::VectorXd tau;
  JointPdGravityTorque(gains, q, qd, q_des, qd_des, g, &tau);
  return tau;
}

void JointPdGravityTorque(const JointPdGains& gains, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                          const Eigen::VectorXd& q_des, const Eigen::VectorXd& qd_des, const Eigen::VectorXd& g,
                          Eigen::VectorXd* tau) {
  const Eigen::Index n = q.size();
  CheckSize("kp", gains.kp, n);
  CheckSize("kd", gains.kd, n);
  CheckSize("qd", qd, n);
  CheckSize("q_des", q_des, n);
  CheckSize("qd_des", qd_des, n);
  CheckSize("g", g, n);
  tau->resize(n);
  tau->noalias() = gains.kp.cwiseProduct(q_des - q) + gains.kd.cwiseProduct(qd_des - qd) + g;
}

}  // namespace vlab::control
