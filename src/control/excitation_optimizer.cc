#include "control/excitation_optimizer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>
#include <set>
#include <stdexcept>
#include <utility>

#include <Eigen/Eigenvalues>

namespace vlab::control {

namespace {

// seeded numbers from the standard's mt19937_64 (the same on every platform), not from the
// library's distributions (whose algorithms the standard leaves open)
class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}
  double Uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }  // [0, 1)
  double Symmetric() { return 2 * Uniform() - 1; }                               // [-1, 1)
  double Normal() {                                                              // Box-Muller
    const double u1 = 1 - Uniform(), u2 = Uniform();
    return std::sqrt(-2 * std::log(u1)) * std::cos(2 * mjPI * u2);
  }

 private:
  std::mt19937_64 engine_;
};

// the distance of the arm's geoms from everything else, by MuJoCo's collision detection on a
// copy of the model whose arm geoms carry the clearance as their margin
class Clearance {
 public:
  Clearance(const mjModel* model, int first_body, const std::vector<double>& reference, const std::vector<int>& adr,
            double clearance_m)
      : model_(mj_copyModel(nullptr, model)), reference_(reference), adr_(adr), clearance_(clearance_m) {
    data_ = mj_makeData(model_);
    arm_.assign(model_->nbody, false);
    for (int b = 1; b < model_->nbody; ++b) {
      arm_[b] = b == first_body || arm_[model_->body_parentid[b]];
    }
    for (int g = 0; g < model_->ngeom; ++g) {
      if (arm_[model_->geom_bodyid[g]]) model_->geom_margin[g] = clearance_m, model_->geom_gap[g] = 0;
    }
  }
  ~Clearance() {
    mj_deleteData(data_);
    mj_deleteModel(model_);
  }
  // the pairs within the clearance at q are excepted from here on
  void SetBaseline(const Eigen::VectorXd& q) {
    Detect(q);
    for (int c = 0; c < data_->ncon; ++c) baseline_.insert(Pair(data_->contact[c]));
  }
  // how far the pairs at q come within the clearance, summed (m); the closest in *closest
  double Violation(const Eigen::VectorXd& q, double* closest, std::pair<int, int>* pair) {
    Detect(q);
    double sum = 0;
    for (int c = 0; c < data_->ncon; ++c) {
      const mjContact& con = data_->contact[c];
      if (!arm_[model_->geom_bodyid[con.geom1]] && !arm_[model_->geom_bodyid[con.geom2]]) continue;
      if (baseline_.count(Pair(con))) continue;
      sum += std::max(0.0, clearance_ - con.dist);
      if (closest && con.dist < *closest) *closest = con.dist, *pair = Pair(con);
    }
    return sum;
  }
  std::string Name(int geom) const {
    const char* name = mj_id2name(model_, mjOBJ_GEOM, geom);
    return name ? name : "geom " + std::to_string(geom);
  }

 private:
  static std::pair<int, int> Pair(const mjContact& c) {
    return {std::min(c.geom1, c.geom2), std::max(c.geom1, c.geom2)};
  }
  void Detect(const Eigen::VectorXd& q) {
    std::copy(reference_.begin(), reference_.end(), data_->qpos);
    for (std::size_t i = 0; i < adr_.size(); ++i) data_->qpos[adr_[i]] = q[i];
    mj_kinematics(model_, data_);
    mj_collision(model_, data_);
  }
  mjModel* model_;
  mjData* data_ = nullptr;
  std::vector<double> reference_;
  std::vector<int> adr_;
  double clearance_;
  std::vector<bool> arm_;
  std::set<std::pair<int, int>> baseline_;
};

// the search's view of a trajectory: free coefficients x (per joint a_2..a_N, b_2..b_N; a_1
// and b_1 follow from Swevers' constraints), the samples the limits are checked at, the
// regressor's samples and the clearance
class Problem {
 public:
  Problem(const mjModel* model, DynamicsRegressor* regressor, const std::vector<double>& reference,
          const Eigen::VectorXd& q_start, const JointLimits& limits, const ExcitationConfig& c)
      : regressor_(regressor), config_(c), q_start_(q_start), n_(regressor->dof()), N_(c.harmonics) {
    w_ = 2 * mjPI / c.period_s;
    steps_ = std::lround(c.period_s / c.control_period_s);
    // the limits, less the margin and fraction
    lower_ = limits.lower.array() + c.position_margin_rad;
    upper_ = limits.upper.array() - c.position_margin_rad;
    v_ = c.rate_fraction * limits.v_max;
    a_ = c.rate_fraction * limits.a_max;
    // sin(w l t)/(w l) and (1 - cos(w l t))/(w l) at the control-period samples: the motion
    // about q_start is a·S + b·C
    S_.resize(N_, steps_ + 1);
    C_.resize(N_, steps_ + 1);
    for (long k = 0; k <= steps_; ++k) {
      for (int l = 1; l <= N_; ++l) {
        const double wl = w_ * l, t = k * c.control_period_s;
        S_(l - 1, k) = std::sin(wl * t) / wl;
        C_(l - 1, k) = (1 - std::cos(wl * t)) / wl;
      }
    }
    // the base parameters, from random states in the ranges (a fixed seed: the same columns
    // for every trajectory seed)
    Random random(1);
    const int states = 200;
    Eigen::MatrixXd W(n_ * states, regressor->parameters()), Y;
    Eigen::VectorXd q(n_), qd(n_), qdd(n_);
    for (int k = 0; k < states; ++k) {
      for (int i = 0; i < n_; ++i) {
        const double lo = std::isfinite(limits.lower[i]) ? limits.lower[i] : -mjPI;
        const double hi = std::isfinite(limits.upper[i]) ? limits.upper[i] : mjPI;
        q[i] = lo + (hi - lo) * random.Uniform();
        qd[i] = limits.v_max[i] * random.Symmetric();
        qdd[i] = limits.a_max[i] * random.Symmetric();
      }
      regressor->Compute(q, qd, qdd, &Y);
      W.middleRows(n_ * k, n_) = Y;
    }
    base_ = FindBaseParameters(W);
    clearance_ = std::make_unique<Clearance>(model, FirstBody(model, *regressor), reference,
                                             regressor->qpos_addresses(), c.clearance_m);
    clearance_->SetBaseline(q_start);
  }

  int free_per_joint() const { return 2 * (N_ - 1); }
  const BaseParameters& base() const { return base_; }

  FourierExcitation Trajectory(const Eigen::MatrixXd& x) const {
    FourierExcitation t;
    t.period_s = config_.period_s;
    t.q_start = q_start_;
    t.a.resize(n_, N_);
    t.b.resize(n_, N_);
    for (int i = 0; i < n_; ++i) {
      double sum_a = 0, sum_lb = 0;
      for (int l = 2; l <= N_; ++l) {
        t.a(i, l - 1) = x(i, l - 2);
        t.b(i, l - 1) = x(i, N_ - 1 + l - 2);
        sum_a += t.a(i, l - 1);
        sum_lb += l * t.b(i, l - 1);
      }
      t.a(i, 0) = -sum_a;
      t.b(i, 0) = -sum_lb;
    }
    return t;
  }

  // scales each joint's coefficients so that its samples keep its limits
  void Project(Eigen::MatrixXd* x) const {
    const FourierExcitation t = Trajectory(*x);
    const double T = config_.control_period_s;
    for (int i = 0; i < n_; ++i) {
      const Eigen::RowVectorXd d = t.a.row(i) * S_ + t.b.row(i) * C_;  // q - q_start at the samples
      double v_peak = 0, a_peak = 0, v_prev = 0;
      for (long k = 1; k <= steps_ + 1; ++k) {
        const double v = k <= steps_ ? (d[k] - d[k - 1]) / T : 0.0;
        v_peak = std::max(v_peak, std::abs(v));
        a_peak = std::max(a_peak, std::abs(v - v_prev) / T);
        v_prev = v;
      }
      double s = 1;
      if (v_peak > v_[i]) s = std::min(s, v_[i] / v_peak);
      if (a_peak > a_[i]) s = std::min(s, a_[i] / a_peak);
      if (d.maxCoeff() > upper_[i] - q_start_[i]) s = std::min(s, (upper_[i] - q_start_[i]) / d.maxCoeff());
      if (d.minCoeff() < lower_[i] - q_start_[i]) s = std::min(s, (lower_[i] - q_start_[i]) / d.minCoeff());
      x->row(i) *= s;
    }
  }

  // cond of the base regressor over one period
  double Condition(const Eigen::MatrixXd& x) {
    const FourierExcitation t = Trajectory(x);
    const int p = static_cast<int>(base_.independent.size());
    Eigen::MatrixXd G = Eigen::MatrixXd::Zero(p, p), Yb(n_, p);
    Eigen::VectorXd q, qd, qdd;
    for (int k = 0; k < config_.regressor_samples; ++k) {
      t.Evaluate(config_.period_s * k / config_.regressor_samples, &q, &qd, &qdd);
      regressor_->Compute(q, qd, qdd, &Y_);
      for (int c = 0; c < p; ++c) Yb.col(c) = Y_.col(base_.independent[c]);
      G.noalias() += Yb.transpose() * Yb;
    }
    const Eigen::VectorXd e = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(G, Eigen::EigenvaluesOnly).eigenvalues();
    return e[0] > 0 ? std::sqrt(e[p - 1] / e[0]) : std::numeric_limits<double>::infinity();
  }

  // summed intrusion into the clearance over `samples` samples of one period (m)
  double Intrusion(const Eigen::MatrixXd& x, long samples, double* closest, std::pair<int, int>* pair) const {
    const FourierExcitation t = Trajectory(x);
    Eigen::VectorXd q;
    double sum = 0;
    for (long k = 1; k < samples; ++k) {
      t.Evaluate(config_.period_s * k / samples, &q, nullptr, nullptr);
      sum += clearance_->Violation(q, closest, pair);
    }
    return sum;
  }
  std::string GeomName(int g) const { return clearance_->Name(g); }

  // the search's criterion: log10(cond), plus a penalty above any value a clear one has
  double Criterion(const Eigen::MatrixXd& x, double* cond) {
    *cond = Condition(x);
    const double intrusion = Intrusion(x, config_.clearance_samples, nullptr, nullptr);
    const double value = std::isfinite(*cond) ? std::log10(*cond) : 100.0;
    return intrusion > 0 ? 200 + 1000 * intrusion : value;
  }

 private:
  static int FirstBody(const mjModel* model, const DynamicsRegressor& r) {
    return model->jnt_bodyid[mj_name2id(model, mjOBJ_JOINT, r.joint_names()[0].c_str())];
  }
  DynamicsRegressor* regressor_;
  ExcitationConfig config_;
  Eigen::VectorXd q_start_;
  int n_, N_;
  double w_ = 0;
  long steps_ = 0;
  Eigen::VectorXd lower_, upper_, v_, a_;
  Eigen::MatrixXd S_, C_;
  BaseParameters base_;
  std::unique_ptr<Clearance> clearance_;
  Eigen::MatrixXd Y_;
};

void Validate(const DynamicsRegressor& r, const Eigen::VectorXd& q_start, const JointLimits& limits,
              const ExcitationConfig& c) {
  const int n = r.dof();
  if (c.harmonics < 2 || c.harmonics > 50) throw std::invalid_argument("excitation: harmonics must be 2 ... 50");
  if (!(c.period_s > 0) || !(c.control_period_s > 0) || !std::isfinite(c.period_s)) {
    throw std::invalid_argument("excitation: the period and the control period must be > 0 s");
  }
  const double steps = c.period_s / c.control_period_s;
  if (std::abs(steps - std::round(steps)) > 1e-6 || steps < 10) {
    throw std::invalid_argument("excitation: the period must be a whole number (at least 10) of control periods");
  }
  if (c.restarts < 1 || c.evaluations < c.restarts) {
    throw std::invalid_argument("excitation: at least one evaluation per start");
  }
  if (q_start.size() != n || limits.lower.size() != n || limits.upper.size() != n || limits.v_max.size() != n ||
      limits.a_max.size() != n) {
    throw std::invalid_argument("excitation: expected " + std::to_string(n) + " values per joint");
  }
  for (int i = 0; i < n; ++i) {
    const std::string& j = r.joint_names()[i];
    if (!(limits.v_max[i] > 0) || !(limits.a_max[i] > 0) || !std::isfinite(limits.v_max[i]) ||
        !std::isfinite(limits.a_max[i])) {
      throw std::invalid_argument("excitation: joint " + j + ": its speed and acceleration limits must be > 0");
    }
    if (!(q_start[i] >= limits.lower[i] + c.position_margin_rad &&
          q_start[i] <= limits.upper[i] - c.position_margin_rad)) {
      char why[200];
      std::snprintf(why, sizeof why,
                    "starts at %.6g deg, not inside its range %.6g .. %.6g deg less the margin %.6g deg",
                    q_start[i] * 180 / mjPI, limits.lower[i] * 180 / mjPI, limits.upper[i] * 180 / mjPI,
                    c.position_margin_rad * 180 / mjPI);
      throw std::invalid_argument("excitation: joint " + j + " " + why);
    }
  }
}

}  // namespace

ExcitationResult OptimizeExcitation(const mjModel* model, DynamicsRegressor* regressor,
                                    const std::vector<double>& reference_qpos, const Eigen::VectorXd& q_start,
                                    const JointLimits& limits, const ExcitationConfig& config) {
  Validate(*regressor, q_start, limits, config);
  Problem problem(model, regressor, reference_qpos, q_start, limits, config);
  const int n = regressor->dof(), m = problem.free_per_joint();
  Random random(config.seed);
  // a coefficient's scale: the speed limit shared by the harmonics
  Eigen::VectorXd scale = limits.v_max * (config.rate_fraction / config.harmonics);
  ExcitationResult result;
  double best = std::numeric_limits<double>::infinity();
  Eigen::MatrixXd best_x;
  result.cond_initial = std::numeric_limits<double>::infinity();
  double best_start = std::numeric_limits<double>::infinity();
  const int budget = config.evaluations / config.restarts;
  for (int r = 0; r < config.restarts; ++r) {
    Eigen::MatrixXd x(n, m);
    for (int i = 0; i < n; ++i) {
      for (int k = 0; k < m; ++k) x(i, k) = scale[i] * random.Symmetric();
    }
    problem.Project(&x);
    double cond = 0;
    double f = problem.Criterion(x, &cond);
    ++result.evaluations;
    for (int shrink = 0; shrink < 8 && f >= 200; ++shrink) {  // a start in the way: closer to q_start
      x *= 0.5;
      f = problem.Criterion(x, &cond);
      ++result.evaluations;
    }
    if (f < best_start) best_start = f, result.cond_initial = cond;
    // (1+1)-ES, one-fifth success rule
    Eigen::VectorXd sigma = 0.3 * scale;
    for (int e = 1; e < budget; ++e) {
      Eigen::MatrixXd y = x;
      for (int i = 0; i < n; ++i) {
        for (int k = 0; k < m; ++k) y(i, k) += sigma[i] * random.Normal();
      }
      problem.Project(&y);
      double cond_y = 0;
      const double fy = problem.Criterion(y, &cond_y);
      ++result.evaluations;
      if (fy <= f) {
        x = y, f = fy, cond = cond_y;
        sigma *= 1.5;
      } else {
        sigma *= std::pow(1.5, -0.25);
      }
    }
    if (f < best) best = f, best_x = x, result.cond_final = cond;
  }
  result.trajectory = problem.Trajectory(best_x);
  result.base = problem.base();
  result.peaks = MeasurePeaks(result.trajectory, config.control_period_s);
  // the clearance at every control period
  double closest = config.clearance_m;
  std::pair<int, int> pair{-1, -1};
  const double intrusion =
      problem.Intrusion(best_x, std::lround(config.period_s / config.control_period_s), &closest, &pair);
  result.clearance_m = closest;
  if (pair.first >= 0) result.closest = problem.GeomName(pair.first) + " / " + problem.GeomName(pair.second);
  if (best >= 200 || intrusion > 0) {
    char why[200];
    std::snprintf(why, sizeof why,
                  "no trajectory found that keeps %.3g mm from the scene: the closest came within %.3g mm",
                  config.clearance_m * 1000, closest * 1000);
    throw std::invalid_argument(std::string("excitation: ") + why + " (" + result.closest + ")");
  }
  return result;
}

}  // namespace vlab::control
