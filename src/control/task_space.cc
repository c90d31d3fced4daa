#include "control/task_space.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "control/trajectory.h"

namespace vlab::control {

namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

void CheckNonNegative(const char* field, double value) {
  if (!std::isfinite(value) || value < 0.0) {
    throw std::invalid_argument(std::string("task space config: ") + field + " must be finite and >= 0, got " +
                                std::to_string(value));
  }
}

}  // namespace

Eigen::Vector3d OrientationError(const Eigen::Matrix3d& R_d_W, const Eigen::Matrix3d& R_W) {
  return RotationVector(R_d_W * R_W.transpose());
}

Eigen::MatrixXd DampedPseudoInverse(const Eigen::MatrixXd& J, double damping) {
  const Eigen::MatrixXd A = J * J.transpose() + damping * damping * Eigen::MatrixXd::Identity(J.rows(), J.rows());
  return J.transpose() * A.ldlt().solve(Eigen::MatrixXd::Identity(J.rows(), J.rows()));
}

std::unique_ptr<TaskSpaceController> TaskSpaceController::Create(const TaskSpaceConfig& config,
                                                                 const RobotModel& model) {
  CheckNonNegative("k_position", config.k_position);
  CheckNonNegative("k_orientation", config.k_orientation);
  CheckNonNegative("damping", config.damping);
  CheckNonNegative("adaptive_damping_max", config.adaptive_damping_max);
  CheckNonNegative("k_null", config.k_null);
  CheckNonNegative("k_joint_limit", config.k_joint_limit);
  if (config.adaptive_damping_max > 0.0 &&
      !(config.singular_value_threshold > 0.0 && std::isfinite(config.singular_value_threshold))) {
    throw std::invalid_argument("task space config: singular_value_threshold must be > 0");
  }
  if (!(config.joint_limit_margin > 0.0 && config.joint_limit_margin <= 0.5)) {
    throw std::invalid_argument("task space config: joint_limit_margin must lie in (0, 0.5]");
  }
  if (!(config.max_joint_speed > 0.0)) {
    throw std::invalid_argument("task space config: max_joint_speed must be > 0 (inf disables)");
  }
  const int n = model.dof();
  std::unique_ptr<TaskSpaceController> c(new TaskSpaceController());
  c->config_ = config;
  c->lower_ = model.lower_limits();
  c->upper_ = model.upper_limits();
  if (config.q_rest.size() == 0) {
    // centre of the range, 0 where a joint is unlimited
    c->q_rest_.setZero(n);
    for (int i = 0; i < n; ++i) {
      if (std::isfinite(c->lower_[i]) && std::isfinite(c->upper_[i])) {
        c->q_rest_[i] = 0.5 * (c->lower_[i] + c->upper_[i]);
      }
    }
  } else if (config.q_rest.size() != n) {
    throw std::invalid_argument("task space config: q_rest has size " + std::to_string(config.q_rest.size()) +
                                ", chain has " + std::to_string(n) + " joints");
  } else if (!config.q_rest.allFinite()) {
    throw std::invalid_argument("task space config: q_rest is not finite");
  } else {
    c->q_rest_ = config.q_rest;
  }
  c->nv_ = model.model().nv;
  c->jacp_.resize(3 * static_cast<size_t>(c->nv_));
  c->jacr_.resize(3 * static_cast<size_t>(c->nv_));
  c->J_.resize(6, n);
  c->qd0_.setZero(n);
  c->out_.qd_cmd.setZero(n);
  return c;
}

void TaskSpaceController::NullSpaceVelocity(const Eigen::VectorXd& q) {
  qd0_.noalias() = config_.k_null * (q_rest_ - q);
  if (config_.k_joint_limit <= 0.0) return;
  // push out of the band of width margin·range next to each finite limit
  for (Eigen::Index i = 0; i < q.size(); ++i) {
    if (!std::isfinite(lower_[i]) || !std::isfinite(upper_[i])) continue;
    const double band = config_.joint_limit_margin * (upper_[i] - lower_[i]);
    const double into_upper = q[i] - (upper_[i] - band);
    const double into_lower = (lower_[i] + band) - q[i];
    if (into_upper > 0.0) qd0_[i] -= config_.k_joint_limit * into_upper;
    if (into_lower > 0.0) qd0_[i] += config_.k_joint_limit * into_lower;
  }
}

const TaskSpaceOutput& TaskSpaceController::Update(const RobotModel& model, const Eigen::VectorXd& q,
                                                   const TaskSpaceTarget& target) {
  const int n = static_cast<int>(J_.cols());
  if (model.dof() != n || q.size() != n || model.model().nv != nv_) {
    throw std::invalid_argument("task space controller: built for " + std::to_string(n) + " joints, got model dof " +
                                std::to_string(model.dof()) + " and q size " + std::to_string(q.size()));
  }
  TaskSpaceOutput& out = out_;
  out.ok = q.allFinite() && target.pose.p_W.allFinite() && target.pose.R_W.allFinite() && target.v_W.allFinite() &&
           target.w_W.allFinite();
  if (!out.ok) {
    out.qd_cmd.setZero();
    return out;
  }

  // task error, world frame
  const Pose pose = model.TipPose();
  out.error_W.head<3>() = target.pose.p_W - pose.p_W;
  out.error_W.tail<3>() = OrientationError(target.pose.R_W, pose.R_W);
  out.position_error_m = out.error_W.head<3>().norm();
  out.orientation_error_rad = out.error_W.tail<3>().norm();

  // geometric Jacobian of the tip site, chain columns only
  const mjData& d = model.data();
  mj_jacSite(&model.model(), &d, jacp_.data(), jacr_.data(), model.tip_site_id());
  for (int i = 0; i < n; ++i) {
    const int v = model.dof_addresses()[i];
    for (int r = 0; r < 3; ++r) {
      J_(r, i) = jacp_[r * nv_ + v];
      J_(3 + r, i) = jacr_[r * nv_ + v];
    }
  }

  // damping, optionally raised near singularities
  Matrix6d A;
  A.noalias() = J_.lazyProduct(J_.transpose());
  double lambda2 = config_.damping * config_.damping;
  if (config_.adaptive_damping_max > 0.0) {
    Eigen::SelfAdjointEigenSolver<Matrix6d> eig(A, Eigen::EigenvaluesOnly);
    const double sigma_min = std::sqrt(std::max(0.0, eig.eigenvalues()[0]));
    const double eps = config_.singular_value_threshold;
    if (sigma_min < eps) {
      const double r = sigma_min / eps;
      lambda2 += config_.adaptive_damping_max * config_.adaptive_damping_max * (1.0 - r * r);
    }
  }
  out.damping = std::sqrt(lambda2);
  A.diagonal().array() += lambda2;

  // reference twist minus the task motion the posture velocity would cause
  NullSpaceVelocity(q);
  Vector6d x_ref;
  x_ref.head<3>() = target.v_W + config_.k_position * out.error_W.head<3>();
  x_ref.tail<3>() = target.w_W + config_.k_orientation * out.error_W.tail<3>();
  x_ref.noalias() -= J_.lazyProduct(qd0_);
  const Vector6d y = A.ldlt().solve(x_ref);
  out.qd_cmd.noalias() = J_.transpose().lazyProduct(y);
  out.qd_cmd += qd0_;

  // uniform scaling keeps the direction of the joint motion
  const double peak = out.qd_cmd.cwiseAbs().maxCoeff();
  out.speed_scale = peak > config_.max_joint_speed ? config_.max_joint_speed / peak : 1.0;
  if (out.speed_scale < 1.0) out.qd_cmd *= out.speed_scale;
  return out;
}

}  // namespace vlab::control
