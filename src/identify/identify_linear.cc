#include "identify/identify_linear.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>

#include <Eigen/QR>

#include "control/dynamics_regressor.h"

namespace vlab::identify {

bool LinearKind(TargetKind kind) {
  switch (kind) {
    case TargetKind::kBodyMass:     // m, m·c and the inertia scale together at a fixed centre
    case TargetKind::kPayloadMass:  // a point mass at a fixed place: m, m·c and m (|c|² 1 − c cᵀ)
    case TargetKind::kJointDamping:
    case TargetKind::kJointArmature:
    case TargetKind::kJointFrictionLoss:
      return true;
    case TargetKind::kColumnBias:
    case TargetKind::kColumnGain:
    case TargetKind::kColumnDelay:
    case TargetKind::kBodyCom:      // m·c is linear in it, the inertia about the joint quadratic
    case TargetKind::kBodyInertia:  // linear, but about axes the regression does not carry
    case TargetKind::kPayloadCom:
    case TargetKind::kServoBandwidth:  // the servo's gains shape the torques, they are no term of them
    case TargetKind::kServoDampingRatio:
      return false;
  }
  return false;
}

const char* LinearStatusText(LinearStatus status) {
  switch (status) {
    case LinearStatus::kEstimated:
      return "estimated";
    case LinearStatus::kUndetermined:
      return "undetermined: nominal";
    case LinearStatus::kNotCovered:
      return "not covered: nominal";
  }
  return "";
}

namespace {

// one arm device's chain: its regressor, its joints (indices into Problem::joints()), the
// regressor's parameters at the nominal values and their derivatives by each estimated one
struct Chain {
  std::unique_ptr<control::DynamicsRegressor> regressor;
  std::vector<int> joints;
  Eigen::VectorXd pi0;
  Eigen::MatrixXd dpi;  // 13·dof x estimated parameters
};

// the joint torque per unit of a motor's control (gear · gain), 0 when it is no plain torque
// motor (dynamics, a bias or another transmission)
double TorquePerControl(const mjModel* m, int a) {
  if (m->actuator_trntype[a] != mjTRN_JOINT || m->actuator_dyntype[a] != mjDYN_NONE ||
      m->actuator_gaintype[a] != mjGAIN_FIXED || m->actuator_biastype[a] != mjBIAS_NONE) {
    return 0;
  }
  return m->actuator_gear[6 * a] * m->actuator_gainprm[mjNGAIN * a];
}

// Savitzky-Golay polynomial of `degree` over rows i = -H..H: the weights (per row) of its value
// at x, or of its slope at x (per row)
Eigen::VectorXd SavitzkyGolay(int half, int degree, double x, bool slope) {
  Eigen::MatrixXd a(2 * half + 1, degree + 1);
  for (int i = -half; i <= half; ++i) {
    for (int k = 0; k <= degree; ++k) a(i + half, k) = std::pow(static_cast<double>(i), k);
  }
  // (degree + 1) x rows: the least-squares coefficients of the rows' values
  const Eigen::MatrixXd p = a.colPivHouseholderQr().solve(Eigen::MatrixXd::Identity(a.rows(), a.rows()));
  Eigen::VectorXd w = Eigen::VectorXd::Zero(a.rows());
  for (int k = slope ? 1 : 0; k <= degree; ++k) {
    w += (slope ? k * std::pow(x, k - 1) : std::pow(x, k)) * p.row(k).transpose();
  }
  return w;
}

// the columns of `a` (scaled) that QR with column pivoting finds independent, in column order
std::vector<int> IndependentColumns(const Eigen::MatrixXd& a, double tolerance) {
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
  qr.setThreshold(tolerance);
  std::vector<int> kept;
  for (Eigen::Index i = 0; i < qr.rank(); ++i) kept.push_back(qr.colsPermutation().indices()[i]);
  std::sort(kept.begin(), kept.end());
  return kept;
}

}  // namespace

LinearEstimate EstimateLinear(const Problem& problem, const LinearOptions& options) {
  const std::vector<BoundParameter>& params = problem.parameters();
  const std::vector<Problem::Joint>& joints = problem.joints();
  const mjModel* model = problem.model();
  LinearEstimate out;
  for (const BoundParameter& p : params) out.values.push_back(p.nominal);
  out.raw = out.values;
  out.status.assign(params.size(), LinearStatus::kNotCovered);
  const std::vector<double> nominal = out.values;
  std::vector<int> estimated;  // parameters in the regression
  for (std::size_t i = 0; i < params.size(); ++i) {
    if (!params[i].spec.frozen && LinearKind(params[i].spec.kind)) estimated.push_back(static_cast<int>(i));
  }
  if (estimated.empty()) {
    out.why = "no free parameter of a kind it covers (body mass, payload mass, joint damping, armature, friction loss)";
    return out;
  }
  // a free centre of mass moves the torques too, and an estimate that holds it at its nominal
  // puts its effect into the masses: a worse start than the nominal values (measured in the
  // planted recovery with a payload: 11 iterations from such an estimate, 6 from nominal)
  for (const BoundParameter& p : params) {
    if (!p.spec.frozen && (p.spec.kind == TargetKind::kBodyCom || p.spec.kind == TargetKind::kPayloadCom)) {
      out.why = "'" + TargetText(p.spec.kind, p.spec.element, p.spec.axis) +
                "' is free: the torques are not linear in a centre of mass";
      return out;
    }
  }
  // the joint torque per unit of each logged tau, and each joint's torque limits
  const int n = static_cast<int>(joints.size());
  std::vector<double> gain(n), tau_lo(n), tau_hi(n);
  for (int j = 0; j < n; ++j) {
    const int a = joints[j].actuator;
    gain[j] = TorquePerControl(model, a);
    if (gain[j] == 0) {
      out.why = "motor of joint '" + joints[j].name + "' is no plain torque motor (gear and fixed gain only)";
      return out;
    }
    constexpr double inf = std::numeric_limits<double>::infinity();
    tau_lo[j] = model->actuator_ctrllimited[a] ? model->actuator_ctrlrange[2 * a] : -inf;
    tau_hi[j] = model->actuator_ctrllimited[a] ? model->actuator_ctrlrange[2 * a + 1] : inf;
    if (model->actuator_forcelimited[a]) {
      tau_lo[j] = std::max(tau_lo[j], model->actuator_forcerange[2 * a] / gain[j]);
      tau_hi[j] = std::min(tau_hi[j], model->actuator_forcerange[2 * a + 1] / gain[j]);
    }
  }
  // one chain per arm device
  std::vector<Chain> chains;
  for (int j = 0; j < n; ++j) {
    if (j == 0 || joints[j].device != joints[j - 1].device) chains.emplace_back();
    chains.back().joints.push_back(j);
  }
  Workspace ws = problem.MakeWorkspace();
  for (Chain& c : chains) {
    std::vector<std::string> names;
    for (int j : c.joints) names.push_back(joints[j].name);
    try {
      c.regressor = control::DynamicsRegressor::Create(model, names, problem.initial_qpos());
    } catch (const std::invalid_argument& e) {
      out.why = std::string("the arm is no chain the regressor takes: ") + e.what();
      return out;
    }
  }
  // pi is affine in each estimated parameter: its derivative from one step, checked by a second
  auto pi_at = [&](const std::vector<double>& values, Chain& c) {
    problem.Apply(values, ws);
    return c.regressor->Parameters(*ws.model);
  };
  for (Chain& c : chains) {
    c.pi0 = pi_at(nominal, c);
    c.dpi.resize(c.pi0.size(), static_cast<Eigen::Index>(estimated.size()));
    for (std::size_t k = 0; k < estimated.size(); ++k) {
      const int p = estimated[k];
      const double h = params[p].scale;
      std::vector<double> v = nominal;
      v[p] = nominal[p] + h;
      const Eigen::VectorXd d1 = pi_at(v, c) - c.pi0;
      v[p] = nominal[p] + 2 * h;
      const Eigen::VectorXd d2 = pi_at(v, c) - c.pi0;
      if ((d2 - 2 * d1).norm() > 1e-9 * (d2.norm() + 1e-300)) {
        throw std::logic_error("identify: the regressor's parameters are not affine in '" +
                               TargetText(params[p].spec.kind, params[p].spec.element) + "' (LinearKind lists it)");
      }
      c.dpi.col(static_cast<Eigen::Index>(k)) = d1 / h;
    }
  }
  problem.Apply(nominal, ws);
  // a joint with friction loss (the model's, or estimated) is Coulomb only in motion
  std::vector<bool> friction(n, false);
  for (int j = 0; j < n; ++j) friction[j] = ws.model->dof_frictionloss[joints[j].dof] > 0;
  for (int p : estimated) {
    if (params[p].spec.kind != TargetKind::kJointFrictionLoss) continue;
    for (int j = 0; j < n; ++j) friction[j] = friction[j] || joints[j].dof == params[p].index;
  }

  const int degree = std::max(2, options.degree);
  const int half = std::max(degree + 1, options.half_window);
  // where in the period that ends at a row (x rows from it) the model's forces act: the period's
  // mean acceleration is the slope at its middle, x = -1/2; MuJoCo's Euler steps (semi-implicit)
  // take the forces at the state at the start of each of the period's n steps (mean x = -1/2 -
  // 1/(2n)) and the damping, implicit, at each step's end (-1/2 + 1/(2n)); RK4 about the middle
  const double period = problem.row_period();
  const int steps = std::max(1, static_cast<int>(std::lround(period / model->opt.timestep)));
  const bool euler = model->opt.integrator == mjINT_EULER;
  const double x_state = euler ? -0.5 - 0.5 / steps : -0.5, x_damping = euler ? -0.5 + 0.5 / steps : -0.5;
  const Eigen::VectorXd w_state = SavitzkyGolay(half, degree, x_state, false),
                        w_damping = SavitzkyGolay(half, degree, x_damping, false),
                        w_slope = SavitzkyGolay(half, degree, -0.5, true);
  const int cols = static_cast<int>(estimated.size());
  std::vector<double> rows_a, rows_b;  // row-major A (torque rows x cols) and b
  std::vector<int> row_joint;
  mjData* d = ws.data.get();
  Eigen::MatrixXd y;
  for (int l = 0; l < problem.log_count(); ++l) {
    const Eigen::MatrixXd &q = problem.log_q(l), &qd = problem.log_qd(l), &tau = problem.log_tau(l);
    const int rows = static_cast<int>(q.rows());
    // the recorded states in contact (the scene's geometry at the recorded joint angles)
    std::vector<bool> contact(rows);
    for (int r = 0; r < rows; ++r) {
      std::copy(problem.initial_qpos().begin(), problem.initial_qpos().end(), d->qpos);
      for (int j = 0; j < n; ++j) d->qpos[joints[j].qpos] = q(r, j);
      mj_fwdPosition(ws.model.get(), d);
      contact[r] = d->ncon > 0;
    }
    // rows after the last contact at or before each row: a sample's filter sees no contact
    std::vector<int> since(rows);
    for (int r = 0; r < rows; ++r) since[r] = contact[r] ? 0 : (r > 0 ? since[r - 1] + 1 : rows);
    for (int r = half; r + half < rows; ++r) {
      if (since[r + half] <= 2 * half) {
        ++out.left_out_contact;
        continue;
      }
      ++out.samples;
      for (const Chain& c : chains) {
        const int m = static_cast<int>(c.joints.size());
        Eigen::VectorXd qs(m), qds(m), qdds(m);
        for (int i = 0; i < m; ++i) {
          const int j = c.joints[i];
          qs[i] = q.col(j).segment(r - half, 2 * half + 1).dot(w_state);
          qds[i] = qd.col(j).segment(r - half, 2 * half + 1).dot(w_state);
          qdds[i] = qd.col(j).segment(r - half, 2 * half + 1).dot(w_slope) / period;
        }
        c.regressor->Compute(qs, qds, qdds, &y);
        // the damping column (Y's qd after the links' columns) at the damping's own time
        for (int i = 0; i < m; ++i) {
          y(i, control::DynamicsRegressor::kLinkParameters * m + i) =
              qd.col(c.joints[i]).segment(r - half, 2 * half + 1).dot(w_damping);
        }
        const Eigen::VectorXd known = y * c.pi0;
        const Eigen::MatrixXd a = y * c.dpi;
        for (int i = 0; i < m; ++i) {
          const int j = c.joints[i];
          const double t = tau(r, j);
          const double margin = 1e-9 * std::max(1.0, std::abs(t));
          if (t <= tau_lo[j] + margin || t >= tau_hi[j] - margin) {
            ++out.left_out_clipped;
            continue;
          }
          if (friction[j] && std::abs(qds[i]) < options.min_speed) {
            ++out.left_out_slow;
            continue;
          }
          rows_b.push_back(gain[j] * t - known[i]);
          for (int k = 0; k < cols; ++k) rows_a.push_back(a(i, k));
          row_joint.push_back(j);
        }
      }
    }
  }
  const int count = static_cast<int>(rows_b.size());
  out.torque_rows = count;
  if (count == 0) {
    out.why = "no log row left (every one within " + std::to_string(half) +
              " rows of a log's end, in contact, clipped or too slow)";
    return out;
  }
  Eigen::MatrixXd a = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      rows_a.data(), count, cols);
  const Eigen::Map<const Eigen::VectorXd> b(rows_b.data(), count);
  for (int k = 0; k < cols; ++k) a.col(k) *= params[estimated[k]].scale;  // unknowns value / scale
  // the least squares over the independent columns with row weights w; the full solution
  auto solve = [&](const Eigen::VectorXd& w, std::vector<int>* kept) {
    const Eigen::MatrixXd aw = w.asDiagonal() * a;
    *kept = IndependentColumns(aw, options.rank_tolerance);
    Eigen::MatrixXd reduced(count, static_cast<Eigen::Index>(kept->size()));
    for (std::size_t k = 0; k < kept->size(); ++k) reduced.col(static_cast<Eigen::Index>(k)) = aw.col((*kept)[k]);
    Eigen::VectorXd x = Eigen::VectorXd::Zero(cols);
    if (!kept->empty()) {
      const Eigen::VectorXd xr = reduced.colPivHouseholderQr().solve(w.asDiagonal() * b);
      for (std::size_t k = 0; k < kept->size(); ++k) x[(*kept)[k]] = xr[static_cast<Eigen::Index>(k)];
    }
    return x;
  };
  // each joint's rms torque residual
  auto rms = [&](const Eigen::VectorXd& x) {
    const Eigen::VectorXd e = b - a * x;
    std::vector<double> sum(n, 0.0), rows(n, 0.0);
    for (int i = 0; i < count; ++i) {
      sum[row_joint[i]] += e[i] * e[i];
      rows[row_joint[i]] += 1;
    }
    std::vector<double> out_rms(n, 0.0);
    for (int j = 0; j < n; ++j) out_rms[j] = rows[j] > 0 ? std::sqrt(sum[j] / rows[j]) : 0.0;
    return out_rms;
  };
  std::vector<int> kept;
  const Eigen::VectorXd x_ols = solve(Eigen::VectorXd::Ones(count), &kept);
  const std::vector<double> rms_ols = rms(x_ols);
  double largest = 0;
  for (double v : rms_ols) largest = std::max(largest, v);
  Eigen::VectorXd w(count);
  for (int i = 0; i < count; ++i) w[i] = 1.0 / std::max(rms_ols[row_joint[i]], 1e-12 * largest + 1e-300);
  const Eigen::VectorXd x = solve(w, &kept);
  out.residual_rms = rms(x);
  out.rank = static_cast<int>(kept.size());
  for (int k = 0; k < cols; ++k) out.status[estimated[k]] = LinearStatus::kUndetermined;
  for (int k : kept) {
    const int p = estimated[k];
    out.status[p] = LinearStatus::kEstimated;
    out.raw[p] = nominal[p] + x[k] * params[p].scale;
    out.values[p] = std::min(std::max(out.raw[p], params[p].spec.lower), params[p].spec.upper);
  }
  out.applies = true;
  return out;
}

}  // namespace vlab::identify
