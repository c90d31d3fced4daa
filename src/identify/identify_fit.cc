#include "identify/identify_fit.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <thread>

#include <ceres/ceres.h>
#include <Eigen/Eigenvalues>

namespace vlab::identify {

namespace {

// rollouts of every window at several parameter vectors, on `threads` threads; each
// rollout writes only its own slice, so the results do not depend on the thread count
class RolloutPool {
 public:
  RolloutPool(const Problem& problem, int threads) : problem_(problem) {
    for (int i = 0; i < std::max(1, threads); ++i) workspaces_.push_back(problem.MakeWorkspace());
  }

  // out[v]: residual_count residuals at variants[v] (predicted likewise when not null);
  // false when any rollout diverged
  bool Run(const std::vector<std::vector<double>>& variants, std::vector<std::vector<double>>* out,
           std::vector<std::vector<double>>* predicted = nullptr) {
    const int windows = problem_.window_count();
    const long tasks = static_cast<long>(variants.size()) * windows;
    out->assign(variants.size(), std::vector<double>(problem_.residual_count()));
    if (predicted) predicted->assign(variants.size(), std::vector<double>(problem_.residual_count()));
    std::atomic<long> next{0};
    std::atomic<bool> ok{true};
    auto work = [&](Workspace& ws) {
      for (long t = next++; t < tasks && ok; t = next++) {
        const int v = static_cast<int>(t / windows), w = static_cast<int>(t % windows);
        const int offset = problem_.window_offset(w);
        double* pred = predicted ? (*predicted)[v].data() + offset : nullptr;
        if (!problem_.Rollout(w, variants[v], ws, (*out)[v].data() + offset, pred)) ok = false;
      }
    };
    std::vector<std::thread> threads;
    for (std::size_t i = 1; i < workspaces_.size(); ++i) threads.emplace_back(work, std::ref(workspaces_[i]));
    work(workspaces_[0]);
    for (std::thread& t : threads) t.join();
    rollouts_ += tasks;
    return ok;
  }

  long rollouts() const { return rollouts_; }

 private:
  const Problem& problem_;
  std::vector<Workspace> workspaces_;
  long rollouts_ = 0;
};

// the free parameters as Ceres sees them: u = value / scale
struct FreeSet {
  std::vector<int> index;    // into the problem's parameters
  std::vector<double> base;  // every parameter's value; the free ones are overwritten
  std::vector<double> lower, upper, scale;
  double jacobian_step = 1e-4;  // the central differences' step, in units of the scaled parameters

  std::vector<double> Values(const double* u) const {
    std::vector<double> v = base;
    for (std::size_t i = 0; i < index.size(); ++i) v[index[i]] = u[i] * scale[i];
    return v;
  }
};

// the residuals and their central-difference Jacobian (one-sided at a bound), every rollout
// of one evaluation run together on the pool
bool Evaluate(RolloutPool& pool, const FreeSet& set, const double* u, double* residuals, double* jacobian, int count) {
  const int n = static_cast<int>(set.index.size());
  std::vector<std::vector<double>> variants{set.Values(u)};
  std::vector<double> step(n);
  if (jacobian) {
    std::vector<double> x(u, u + n);
    for (int i = 0; i < n; ++i) {
      const double h = set.jacobian_step * std::max(1.0, std::abs(u[i]));
      const double hi = std::min(set.upper[i], u[i] + h), lo = std::max(set.lower[i], u[i] - h);
      step[i] = hi - lo;
      x[i] = hi;
      variants.push_back(set.Values(x.data()));
      x[i] = lo;
      variants.push_back(set.Values(x.data()));
      x[i] = u[i];
    }
  }
  std::vector<std::vector<double>> out;
  if (!pool.Run(variants, &out)) return false;
  std::copy(out[0].begin(), out[0].end(), residuals);
  if (jacobian) {
    for (int r = 0; r < count; ++r) {
      for (int i = 0; i < n; ++i) jacobian[r * n + i] = (out[1 + 2 * i][r] - out[2 + 2 * i][r]) / step[i];
    }
  }
  return true;
}

// the last point evaluated, its residuals and (when asked for) its Jacobian: Ceres asks again
// for a point it has evaluated (a candidate's residuals, then its Jacobian once accepted).
// Beside it, the last point Ceres accepted: the point it ends on when it did not keep its last
// try (a step that did not lower the cost, or one whose change fell below the tolerance), where
// the statistics want the Jacobian
struct Evaluations {
  struct Point {
    std::vector<double> u, residuals, jacobian;  // jacobian empty: not computed there
  };
  Point last, accepted;

  bool Get(RolloutPool& pool, const FreeSet& set, const std::vector<double>& at, bool with_jacobian, int count) {
    if (at == last.u && (!last.jacobian.empty() || !with_jacobian)) return true;
    if (at == accepted.u) {
      last = accepted;
      return true;
    }
    last.u.clear();
    last.residuals.resize(count);
    last.jacobian.assign(with_jacobian ? static_cast<std::size_t>(count) * at.size() : 0, 0.0);
    if (!Evaluate(pool, set, at.data(), last.residuals.data(), with_jacobian ? last.jacobian.data() : nullptr, count)) {
      return false;
    }
    last.u = at;
    return true;
  }
  // Ceres's iteration ended on x: keep x's evaluation when it is the last one, with its Jacobian
  void Accepted(const std::vector<double>& x) {
    if (x == last.u && !last.jacobian.empty()) accepted = last;
  }
};

// the cost Ceres sees: one residual block over every window
class WindowsCost : public ceres::CostFunction {
 public:
  WindowsCost(RolloutPool& pool, const FreeSet& set, int residuals, Evaluations& last)
      : pool_(pool), set_(set), last_(last) {
    set_num_residuals(residuals);
    mutable_parameter_block_sizes()->push_back(static_cast<int>(set.index.size()));
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const std::vector<double> u(parameters[0], parameters[0] + set_.index.size());
    double* jacobian = jacobians ? jacobians[0] : nullptr;
    if (!last_.Get(pool_, set_, u, jacobian != nullptr, num_residuals())) return false;
    std::copy(last_.last.residuals.begin(), last_.last.residuals.end(), residuals);
    if (jacobian) std::copy(last_.last.jacobian.begin(), last_.last.jacobian.end(), jacobian);
    return true;
  }

 private:
  RolloutPool& pool_;
  const FreeSet& set_;
  Evaluations& last_;
};

// each iteration's end: the progress line, and the point Ceres is at (u: Ceres updates it every
// iteration) kept when it took a step there
class Progress : public ceres::IterationCallback {
 public:
  Progress(const FitOptions& options, const std::vector<double>& u, Evaluations& last)
      : options_(options), u_(u), last_(last) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    if (summary.iteration == 0 || summary.step_is_successful) last_.Accepted(u_);
    if (options_.progress) options_.progress(summary.iteration, summary.cost);
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const FitOptions& options_;
  const std::vector<double>& u_;
  Evaluations& last_;
};

// J (residuals x free) at u, row-major as Ceres writes it
Eigen::MatrixXd JacobianAt(RolloutPool& pool, const FreeSet& set, const std::vector<double>& u, int count,
                           std::vector<double>* residuals, Evaluations& last) {
  if (!last.Get(pool, set, u, true, count)) {
    throw std::runtime_error("identify: a rollout diverged while computing the Jacobian");
  }
  *residuals = last.last.residuals;
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      last.last.jacobian.data(), count, static_cast<Eigen::Index>(u.size()));
}

double HalfSquares(const std::vector<double>& r) {
  double s = 0;
  for (double x : r) s += x * x;
  return 0.5 * s;
}

}  // namespace

std::string SixDigits(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g", x);
  return buffer;
}

FitResult Fit(const Problem& problem, const FitOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const std::vector<BoundParameter>& params = problem.parameters();
  const int count = problem.residual_count();
  RolloutPool pool(problem, options.threads);
  Evaluations last;
  FitResult result;
  result.residuals = count;
  result.windows = problem.window_count();
  FreeSet set;
  set.jacobian_step = problem.spec().jacobian_step;
  for (const BoundParameter& p : params) set.base.push_back(p.nominal);
  result.nominal_values = set.base;
  // the start: the linear estimate where it applies (identify_linear.h), else the nominal values
  result.first_estimate = "nominal";
  if (options.first_estimate.value_or(problem.spec().first_estimate) == FirstEstimate::kLinear) {
    result.linear = EstimateLinear(problem);
    if (result.linear.applies) {
      set.base = result.linear.values;
      result.first_estimate = "linear";
    } else {
      result.first_estimate_note = "the linear estimate does not apply: " + result.linear.why;
    }
  }
  for (std::size_t i = 0; i < params.size(); ++i) {
    Estimate e;
    e.name = params[i].spec.name;
    e.nominal = e.value = params[i].nominal;
    e.frozen = params[i].spec.frozen;
    e.sd = e.frozen ? 0.0 : std::numeric_limits<double>::infinity();
    e.sd_iid = e.sd;
    e.identifiable = !e.frozen;
    if (e.frozen) e.note = "frozen";
    result.estimates.push_back(e);
    if (e.frozen) continue;
    set.index.push_back(static_cast<int>(i));
    set.scale.push_back(params[i].scale);
    set.lower.push_back(params[i].spec.lower / params[i].scale);
    set.upper.push_back(params[i].spec.upper / params[i].scale);
  }
  std::vector<double> r_start;
  if (result.first_estimate == "linear") {
    // a start whose replay diverges (an estimate far off on poor data) falls back to nominal
    std::vector<std::vector<double>> out;
    if (!pool.Run({set.base}, &out)) {
      set.base = result.nominal_values;
      result.first_estimate = "nominal";
      result.first_estimate_note = "a rollout from the linear estimate diverged";
    }
  }
  std::vector<double> u0;
  for (std::size_t i = 0; i < set.index.size(); ++i) u0.push_back(set.base[set.index[i]] / set.scale[i]);
  // parameters the data do not move at all are kept at their nominal values, not fitted to noise
  if (!u0.empty()) {
    const Eigen::MatrixXd j0 = JacobianAt(pool, set, u0, count, &r_start, last);
    const Eigen::VectorXd norms = j0.colwise().norm();
    const double largest = norms.maxCoeff();
    FreeSet excited = set;
    excited.index.clear();
    excited.scale.clear();
    excited.lower.clear();
    excited.upper.clear();
    std::vector<double> u;
    for (std::size_t i = 0; i < set.index.size(); ++i) {
      Estimate& e = result.estimates[set.index[i]];
      if (!(norms[static_cast<Eigen::Index>(i)] > kUnexcitedColumn * largest)) {
        e.excited = e.identifiable = false;
        e.note = "not excited: the data do not depend on it (kept at its nominal value)";
        excited.base[set.index[i]] = params[set.index[i]].nominal;
        continue;
      }
      excited.index.push_back(set.index[i]);
      excited.scale.push_back(set.scale[i]);
      excited.lower.push_back(set.lower[i]);
      excited.upper.push_back(set.upper[i]);
      u.push_back(u0[i]);
    }
    if (excited.index.size() != set.index.size() || excited.base != set.base) last = Evaluations();
    set = excited;
    u0 = u;
  } else {
    std::vector<std::vector<double>> out;
    if (!pool.Run({set.base}, &out)) throw std::runtime_error("identify: the nominal model's rollout diverged");
    r_start = out[0];
  }
  result.start_values = set.base;
  result.cost_start = HalfSquares(r_start);
  result.cost_nominal = result.cost_start;
  if (result.start_values != result.nominal_values) {
    std::vector<std::vector<double>> out;
    if (!pool.Run({result.nominal_values}, &out)) {
      throw std::runtime_error("identify: the nominal model's rollout diverged");
    }
    result.cost_nominal = HalfSquares(out[0]);
  }
  if (options.message) {
    const LinearEstimate& l = result.linear;
    std::string line = "first estimate: " + result.first_estimate;
    if (result.first_estimate == "linear") {
      int covered = 0;
      for (LinearStatus s : l.status) covered += s != LinearStatus::kNotCovered;
      line += " (" + std::to_string(l.rank) + " of " + std::to_string(covered) + " parameters estimated from " +
              std::to_string(l.torque_rows) + " joint torques of " + std::to_string(l.samples) +
              " log rows); cost at nominal " + SixDigits(result.cost_nominal) + ", at the start " +
              SixDigits(result.cost_start);
    } else {
      line += result.first_estimate_note.empty() ? "" : " (" + result.first_estimate_note + ")";
      line += "; cost " + SixDigits(result.cost_start);
    }
    options.message(line);
  }
  std::vector<double> u = u0;
  const int n = static_cast<int>(u.size());
  if (n > 0) {
    ceres::Problem ceres_problem;
    ceres_problem.AddResidualBlock(new WindowsCost(pool, set, count, last), nullptr, u.data());
    for (int i = 0; i < n; ++i) {
      ceres_problem.SetParameterLowerBound(u.data(), i, set.lower[i]);
      ceres_problem.SetParameterUpperBound(u.data(), i, set.upper[i]);
    }
    ceres::Solver::Options solver;
    solver.minimizer_type = ceres::TRUST_REGION;
    solver.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
    solver.linear_solver_type = ceres::DENSE_QR;
    solver.max_num_iterations = problem.spec().max_iterations;
    // Ceres's defaults: stop once an iteration changes the cost by less than 1e-6 of it (a
    // change far below the noise), or the parameters by less than 1e-8 of their size
    solver.function_tolerance = 1e-6;
    solver.parameter_tolerance = 1e-8;
    solver.gradient_tolerance = 1e-10;
    solver.num_threads = 1;  // one residual block: the rollouts are threaded in the pool
    solver.logging_type = ceres::SILENT;
    solver.update_state_every_iteration = true;  // u is Ceres's point in the callback
    Progress progress(options, u, last);
    solver.callbacks.push_back(&progress);
    ceres::Solver::Summary summary;
    ceres::Solve(solver, &ceres_problem, &summary);
    result.iterations = static_cast<int>(summary.iterations.size());
    result.termination = summary.message;
    if (summary.termination_type == ceres::FAILURE) {
      throw std::runtime_error("identify: the fit failed: " + summary.message);
    }
  } else {
    result.termination = "nothing to fit";
  }
  // the estimates' statistics from the Jacobian at the optimum
  std::vector<double> r;
  const std::vector<double> values = set.Values(u.data());
  result.fitted_values = values;
  result.correlation = Eigen::MatrixXd::Zero(params.size(), params.size());
  if (n > 0) {
    const Eigen::MatrixXd j = JacobianAt(pool, set, u, count, &r, last);
    result.cost_fitted = HalfSquares(r);
    const double dof = std::max(1, count - problem.residuals_left_out() - problem.window_nuisances() - n);
    const double variance = 2 * result.cost_fitted / dof;
    result.residual_sd = std::sqrt(variance);
    // pseudo-inverse of J^T J: directions the data do not tell get an infinite variance
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(j.transpose() * j);
    const Eigen::VectorXd lambda = eig.eigenvalues();
    const double floor = 1e-12 * std::max(lambda.maxCoeff(), 0.0);
    Eigen::MatrixXd bread = Eigen::MatrixXd::Zero(n, n);
    Eigen::VectorXd singular = Eigen::VectorXd::Zero(n);
    for (int k = 0; k < n; ++k) {
      const Eigen::VectorXd v = eig.eigenvectors().col(k);
      if (lambda[k] > floor) {
        bread += v * v.transpose() / lambda[k];
      } else {
        singular += v.cwiseAbs2();
      }
    }
    // the noise of a window's start state runs through all its rows: its residuals are
    // correlated, and J^T J scaled by the residual variance understates the spread. The
    // cluster-robust ("sandwich") covariance takes each window as one independent sample:
    // bread (sum_w J_w^T r_w r_w^T J_w) bread, times G / (G - 1) for G windows.
    const Eigen::Map<const Eigen::VectorXd> rv(r.data(), count);
    Eigen::MatrixXd meat = Eigen::MatrixXd::Zero(n, n);
    const int windows = problem.window_count();
    for (int w = 0; w < windows; ++w) {
      const int offset = problem.window_offset(w), rows = problem.window_residuals(w);
      const Eigen::VectorXd score = j.middleRows(offset, rows).transpose() * rv.segment(offset, rows);
      meat += score * score.transpose();
    }
    const Eigen::MatrixXd cov_iid = variance * bread;
    const Eigen::MatrixXd cov = bread * meat * bread * (windows > 1 ? windows / (windows - 1.0) : 1.0);
    for (int a = 0; a < n; ++a) {
      Estimate& e = result.estimates[set.index[a]];
      e.value = values[set.index[a]];
      const bool undetermined = singular[a] > 1e-6;
      e.sd = undetermined ? std::numeric_limits<double>::infinity() : std::sqrt(cov(a, a)) * set.scale[a];
      e.sd_iid = undetermined ? std::numeric_limits<double>::infinity() : std::sqrt(cov_iid(a, a)) * set.scale[a];
      for (int b = 0; b < n; ++b) {
        const double c = undetermined || singular[b] > 1e-6 ? 0.0 : cov(a, b) / std::sqrt(cov(a, a) * cov(b, b));
        result.correlation(set.index[a], set.index[b]) = a == b ? 1.0 : c;
      }
    }
    for (int a = 0; a < n; ++a) {
      Estimate& e = result.estimates[set.index[a]];
      const double scale = set.scale[a];
      std::string why;
      if (!std::isfinite(e.sd)) {
        why = "not determined: the data cannot tell it from the others";
      } else if (e.sd > kPoorSd * scale) {
        why = "poorly determined: sd above " + std::to_string(static_cast<int>(kPoorSd * 100)) + " % of its scale";
      }
      for (int b = 0; b < n; ++b) {
        if (b != a && std::abs(result.correlation(set.index[a], set.index[b])) > kCorrelated) {
          why += std::string(why.empty() ? "" : "; ") + "correlated with " + result.estimates[set.index[b]].name;
        }
      }
      const double lo = params[set.index[a]].spec.lower, hi = params[set.index[a]].spec.upper;
      if (e.value <= lo + 1e-9 * scale || e.value >= hi - 1e-9 * scale) {
        why += std::string(why.empty() ? "" : "; ") + "at its " + (e.value <= lo + 1e-9 * scale ? "lower" : "upper") +
               " bound";
      }
      e.identifiable = why.empty();
      e.note = why;
    }
  } else {
    result.cost_fitted = result.cost_nominal;
  }
  result.rollouts = static_cast<int>(pool.rollouts());
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

bool Predict(const Problem& problem, const std::vector<double>& values, int threads, std::vector<double>* predicted) {
  RolloutPool pool(problem, threads);
  std::vector<std::vector<double>> residuals, out;
  if (!pool.Run({values}, &residuals, &out)) return false;
  *predicted = out[0];
  return true;
}

}  // namespace vlab::identify
