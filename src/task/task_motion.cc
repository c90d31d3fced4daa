#include "task/task_motion.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "control/time_scaling.h"
#include "control/trajectory.h"
#include "task/task_units.h"

namespace vlab::task {

namespace {

constexpr double kTolPos_m = 1e-9;
constexpr double kTolRot_rad = 1e-9;
constexpr int kMaxIterations = 200;
constexpr int kStretchRounds = 8;  // plans tried with a longer timing before giving up

std::string Percent(int i, int n) { return "at " + FormatNumber(100.0 * (i + 1) / n, "%.0f") + "% of the path"; }

// a speed profile over a path of length L that starts at speed v0 (m/s),
// ramps to the peak vp at a, cruises, and stops at a (or, when it cannot stop
// within L at a, decelerates at the rate that stops it at L)
struct StartSpeedProfile {
  double L = 0, v0 = 0, vp = 0, a = 0, a_stop = 0;
  double t1 = 0, t2 = 0, T = 0;  // end of the ramp, of the cruise, of the move
  double d1 = 0, d2 = 0;         // distance at t1, t2
  StartSpeedProfile(double length, double start_speed, double v, double accel) : L(length), v0(start_speed), a(accel) {
    if (v0 * v0 / (2 * a) >= L) {  // no room to speed up or cruise: one deceleration to rest at L
      vp = v0;
      a_stop = v0 > 0 ? v0 * v0 / (2 * L) : a;
      T = v0 > 0 ? v0 / a_stop : 0;
      return;
    }
    a_stop = a;
    if (v0 <= v) {
      vp = (v * v - v0 * v0) / (2 * a) + v * v / (2 * a) <= L ? v : std::sqrt((2 * a * L + v0 * v0) / 2);
    } else {
      vp = v;  // v0 * v0 / (2 a) < L: down to v, cruise, stop
    }
    t1 = std::abs(vp - v0) / a;
    d1 = (v0 + vp) / 2 * t1;
    const double d_stop = vp * vp / (2 * a);
    d2 = L - d_stop;
    t2 = t1 + (vp > 0 ? (d2 - d1) / vp : 0);
    T = t2 + vp / a;
  }
  // distance and speed at time t
  void At(double t, double* s, double* v) const {
    if (t >= T) {
      *s = L;
      *v = 0;
      return;
    }
    if (t2 == 0 && t1 == 0) {  // the deceleration alone
      *s = v0 * t - a_stop * t * t / 2;
      *v = v0 - a_stop * t;
      return;
    }
    if (t < t1) {
      const double acc = vp >= v0 ? a : -a;
      *s = v0 * t + acc * t * t / 2;
      *v = v0 + acc * t;
    } else if (t < t2) {
      *s = d1 + vp * (t - t1);
      *v = vp;
    } else {
      const double u = t - t2;
      *s = d2 + vp * u - a * u * u / 2;
      *v = vp - a * u;
    }
    *s = std::min(*s, L);
  }
};

}  // namespace

void TrapezoidTiming(double d, double v, double a, double* duration_s, double* accel_fraction) {
  if (d <= 0) {
    *duration_s = 0;
    *accel_fraction = 0.5;
    return;
  }
  if (d >= v * v / a) {
    *duration_s = d / v + v / a;
    *accel_fraction = (v / a) / *duration_s;
  } else {
    *duration_s = 2.0 * std::sqrt(d / a);
    *accel_fraction = 0.5;
  }
}

MotionPlanner::MotionPlanner(control::RobotModel* model, double period_s)
    : model_(model), period_s_(period_s), rates_(DefaultRateLimits(model->dof())),
      zero_(Eigen::VectorXd::Zero(model->dof())) {}

void MotionPlanner::set_rate_limits(const JointRateLimits& limits) {
  const long n = model_->dof();
  if (limits.v_rps.size() != n || limits.a_rps2.size() != n) {
    throw std::invalid_argument("joint speed and acceleration limits: expected " + std::to_string(n) +
                                " values each, got " + std::to_string(limits.v_rps.size()) + " and " +
                                std::to_string(limits.a_rps2.size()));
  }
  for (long j = 0; j < n; ++j) {
    if (!(limits.v_rps[j] > 0 && limits.a_rps2[j] > 0 && std::isfinite(limits.v_rps[j]) &&
          std::isfinite(limits.a_rps2[j]))) {
      throw std::invalid_argument("joint " + model_->joint_names()[j] +
                                  ": its speed and acceleration limits must be finite and > 0");
    }
  }
  rates_ = limits;
}

template <class Replan>
Plan MotionPlanner::Within(const Eigen::VectorXd& q_before, const Eigen::VectorXd& q_start, Replan replan) const {
  double k = 1;
  Plan plan = replan(k);
  std::vector<Eigen::VectorXd> path;
  for (int round = 0;; ++round) {
    // the commanded sequence: the two samples before, the plan, at rest at its end
    path.assign({q_before, q_start});
    path.insert(path.end(), plan.q.begin(), plan.q.end());
    if (!plan.q.empty()) path.push_back(plan.q.back());
    const JointRates rates = PeakRates(path, period_s_);
    const RateExcess e = Excess(rates, rates_);
    if (e.stretch <= 1 + 1e-9) return plan;
    const std::string name = model_->joint_names()[e.joint];
    if (rates_.refuse) throw std::invalid_argument(ExcessMessage(rates, rates_, e, name));
    if (round == kStretchRounds) {
      throw std::invalid_argument("slowing the move down by " + FormatNumber(k, "%.3g") +
                                  " times does not keep joint " + name +
                                  " within its limits (a move entered from a blend keeps the speed it enters with): " +
                                  ExcessMessage(rates, rates_, e, name));
    }
    // the same path, slower: speeds scale by 1/k, accelerations by 1/k² (a margin for whole periods)
    k *= e.stretch * 1.0005;
    plan = replan(k);
  }
}

Frame MotionPlanner::ToolPose(const Eigen::VectorXd& q) const {
  model_->SetState(q, zero_);
  const control::Pose tip = model_->TipPose();
  Frame f;
  const Eigen::Quaterniond q_tip(tip.R_W);
  f.p = tip.p_W + q_tip * tool_.p;
  f.q = (q_tip * tool_.q).normalized();
  return f;
}

Eigen::VectorXd MotionPlanner::Solve(const Eigen::VectorXd& q_start, const Frame& goal_W, int* iterations,
                                     double* pos_err, double* rot_err) const {
  Eigen::VectorXd q = q_start;
  const int n = model_->dof();
  for (*iterations = 0; *iterations < kMaxIterations; ++*iterations) {
    const Frame x = ToolPose(q);  // also sets the model's state for the Jacobian
    Eigen::Matrix<double, 6, 1> e;
    e.head<3>() = goal_W.p - x.p;
    e.tail<3>() = control::RotationVector((goal_W.q * x.q.conjugate()).toRotationMatrix());
    *pos_err = e.head<3>().norm();
    *rot_err = e.tail<3>().norm();
    if (*pos_err < kTolPos_m && *rot_err < kTolRot_rad) return q;
    Eigen::MatrixXd J = model_->Jacobian();  // tip site, world
    const Eigen::Vector3d r = x.p - model_->TipPose().p_W;
    J.topRows(3) -= Skew(r) * J.bottomRows(3);  // the tool point: v = v_tip + ω × r
    const Eigen::Matrix<double, 6, 6> JJt =
        J * J.transpose() + kIkDamping * kIkDamping * Eigen::Matrix<double, 6, 6>::Identity();
    Eigen::VectorXd dq = J.transpose() * JJt.ldlt().solve(e);
    if (dq.norm() > kIkMaxStep_rad) dq *= kIkMaxStep_rad / dq.norm();
    q += dq;
    (void)n;
  }
  return q;
}

std::string MotionPlanner::Singularity(const Eigen::VectorXd& q) const {
  const int n = model_->dof();
  model_->SetState(q, zero_);
  const Eigen::MatrixXd J = model_->Jacobian();  // tip site, world: rows 0-2 linear, 3-5 angular
  const Eigen::Vector3d p = model_->TipPose().p_W;
  // each joint's axis line: direction a, and its point closest to the tip, p + a × v
  std::vector<Eigen::Vector3d> a(n), o(n);
  for (int i = 0; i < n; ++i) {
    a[i] = J.block<3, 1>(3, i);
    const double len = a[i].norm();
    if (len < 0.5) return "";  // not a hinge
    a[i] /= len;
    o[i] = p + a[i].cross(J.block<3, 1>(0, i) / len);
  }
  constexpr double kAngle = 10 * kDeg, kDistance_m = 1e-3;
  std::string best;
  double best_angle = kAngle;
  for (int i = 0; i < n; ++i) {
    for (int j = i + 2; j < n; ++j) {
      const double angle = std::asin(std::min(1.0, a[i].cross(a[j]).norm()));
      if (angle >= best_angle) continue;
      // the lines must meet (within 1 mm) near the arm (within 1 m of the tip), not merely be parallel
      const Eigen::Vector3d d = o[j] - o[i];
      const double b = a[i].dot(a[j]), den = 1 - b * b;
      if (den < 1e-12) {
        if (d.cross(a[i]).norm() > kDistance_m) continue;  // parallel: the same line or none
      } else {
        const double si = (d.dot(a[i]) - b * d.dot(a[j])) / den, sj = (b * d.dot(a[i]) - d.dot(a[j])) / den;
        const Eigen::Vector3d ci = o[i] + si * a[i], cj = o[j] + sj * a[j];
        if ((ci - cj).norm() > kDistance_m || (ci - p).norm() > 1.0) continue;
      }
      // the joint between them nearest 0 or 180 deg aligns them
      int k_best = i + 1;
      for (int k = i + 1; k < j; ++k)
        if (std::abs(std::sin(q[k])) < std::abs(std::sin(q[k_best]))) k_best = k;
      const char* kind = k_best >= n - 3 ? "wrist" : (k_best <= 1 ? "shoulder" : "elbow");
      best_angle = angle;
      best = std::string(kind) + " singularity near " + model_->joint_names()[k_best] + " = " +
             FormatNumber(q[k_best] / kDeg, "%.3g") + " deg (the axes of " + model_->joint_names()[i] + " and " +
             model_->joint_names()[j] + " line up)";
    }
  }
  return best;
}

std::string MotionPlanner::Unreached(const Eigen::VectorXd& q_end, double pe, double re, int it) const {
  std::string s = "out of reach: the IK's closest pose is " + FormatNumber(pe, "%.3g") +
                  " m from the target position and " + FormatNumber(re / kDeg, "%.3g") +
                  " deg from its orientation (final residual after " + std::to_string(it) + " iterations)";
  const std::string sing = Singularity(q_end);
  if (!sing.empty()) s += "; it ended near a singularity: " + sing;
  return s;
}

std::string MotionPlanner::PathFailure(int i, int n, const Eigen::VectorXd& q_good, const Frame& goal,
                                       const std::string& what) const {
  // the target itself: from the last good sample, can the IK reach it at all?
  int it;
  double pe, re;
  const Eigen::VectorXd q_goal = Solve(q_good, goal, &it, &pe, &re);
  if (!(pe < kTolPos_m * 10 && re < kTolRot_rad * 10)) {
    return "the target is " + Unreached(q_goal, pe, re, it) + "; the path fails " + Percent(i, n);
  }
  const std::string sing = Singularity(q_good);
  if (!sing.empty()) return Percent(i, n) + ": the path passes through a " + sing + ": " + what;
  return Percent(i, n) + ": " + what;
}

Eigen::VectorXd MotionPlanner::Ik(const Eigen::VectorXd& q0, const Frame& goal_W) const {
  int it;
  double pe, re;
  const Eigen::VectorXd q = Solve(q0, goal_W, &it, &pe, &re);
  if (!(pe < kTolPos_m * 10 && re < kTolRot_rad * 10)) throw std::invalid_argument(Unreached(q, pe, re, it));
  try {
    CheckLimits(q, "at the target");
  } catch (const std::invalid_argument& e) {
    const std::string sing = Singularity(q);
    throw std::invalid_argument(sing.empty() ? e.what()
                                             : std::string(e.what()) + " (the IK ended near a " + sing + ")");
  }
  return q;
}

bool MotionPlanner::Track(const Eigen::VectorXd& q0, const Frame& goal_W, Eigen::VectorXd* q, std::string* why) const {
  int it;
  double pe, re;
  *q = Solve(q0, goal_W, &it, &pe, &re);
  if (!(pe < kTolPos_m * 10 && re < kTolRot_rad * 10)) {
    *why = Unreached(*q, pe, re, it);
    return false;
  }
  try {
    CheckLimits(*q, "the IK's solution");
  } catch (const std::invalid_argument& e) {
    *why = e.what();
    return false;
  }
  return true;
}

void MotionPlanner::CheckLimits(const Eigen::VectorXd& q, const std::string& where) const {
  for (int i = 0; i < q.size(); ++i) {
    const double lo = model_->lower_limits()[i], hi = model_->upper_limits()[i];
    if (!std::isfinite(q[i]) || q[i] < lo - 1e-9 || q[i] > hi + 1e-9) {
      const bool below = q[i] < lo;
      throw std::invalid_argument(where + ": joint " + model_->joint_names()[i] + " = " + FormatNumber(q[i] / kDeg) +
                                  " deg is beyond its " + (below ? "lower" : "upper") + " limit " +
                                  FormatNumber((below ? lo : hi) / kDeg) + " deg");
    }
  }
}

Plan MotionPlanner::Joint(const Eigen::VectorXd& q0, const Eigen::VectorXd& q1, const MotionLimits& limits,
                          double duration_s) const {
  if (q1.size() != model_->dof()) {
    throw std::invalid_argument("expected " + std::to_string(model_->dof()) + " joint values, got " +
                                std::to_string(q1.size()));
  }
  CheckLimits(q1, "the target");
  double T0 = duration_s, frac = 0.25;
  if (T0 <= 0) {
    // the fastest joint's speed and acceleration, lowered so that every joint keeps its own limits
    const double D = (q1 - q0).cwiseAbs().maxCoeff();
    double v = limits.joint_speed_rps, a = limits.joint_accel_rps2;
    for (int j = 0; j < q1.size() && !rates_.refuse; ++j) {
      const double d = std::abs(q1[j] - q0[j]);
      if (d <= 0) continue;
      v = std::min(v, rates_.v_rps[j] * D / d);
      a = std::min(a, rates_.a_rps2[j] * D / d);
    }
    TrapezoidTiming(D, v, a, &T0, &frac);
  }
  return Within(q0, q0, [&](double k) {
    const int N = std::max(1, static_cast<int>(std::ceil(T0 * k / period_s_ - 1e-9)));
    const double T = N * period_s_;
    control::TimeScaling scaling{control::TimeScalingType::kTrapezoidal, std::clamp(frac, 1e-3, 0.5)};
    Plan plan;
    plan.duration_s = T;
    for (int i = 0; i < N; ++i) {
      const double s = control::EvaluateTimeScaling(scaling, T, (i + 1) * period_s_).s;
      plan.q.push_back(i == N - 1 ? q1 : Eigen::VectorXd(q0 + s * (q1 - q0)));
    }
    return plan;
  });
}

template <class PoseAt>
Plan MotionPlanner::Cartesian(const Eigen::VectorXd& q0, double T, double frac, double length_m, PoseAt pose_at) const {
  const int N = std::max(1, static_cast<int>(std::ceil(T / period_s_ - 1e-9)));
  T = N * period_s_;
  control::TimeScaling scaling{control::TimeScalingType::kTrapezoidal, std::clamp(frac, 1e-3, 0.5)};
  std::vector<Frame> goals(N);
  std::vector<double> speeds(N);
  for (int i = 0; i < N; ++i) {
    const control::ScalingSample s = control::EvaluateTimeScaling(scaling, T, (i + 1) * period_s_);
    goals[i] = pose_at(s.s);
    speeds[i] = s.sd * length_m;
  }
  Plan plan = SolvePath(q0, goals, speeds);
  plan.duration_s = T;
  return plan;
}

Plan MotionPlanner::SolvePath(const Eigen::VectorXd& q0, const std::vector<Frame>& goals,
                              const std::vector<double>& speeds) const {
  const int N = static_cast<int>(goals.size());
  Plan plan;
  Eigen::VectorXd q = q0, guess;
  plan.q.reserve(N);
  plan.tool_W.reserve(N);
  plan.speed_mps = speeds;
  for (int i = 0; i < N; ++i) {
    const Frame& goal = goals[i];
    int it;
    double pe, re;
    // Newton from the previous sample: its minimum-norm steps add no self-motion, so the
    // joints come to rest with the tool (extrapolating the last two samples would carry
    // a self-motion on at constant speed past the end of the path: a jump in joint speed there)
    guess = q;
    q = Solve(guess, goal, &it, &pe, &re);
    const Eigen::VectorXd& q_good = i > 0 ? plan.q[i - 1] : q0;
    if (!(pe < kTolPos_m * 10 && re < kTolRot_rad * 10)) {
      throw std::invalid_argument(PathFailure(i, N, q_good, goals.back(),
                                              "the IK cannot reach this pose of the path (" + FormatNumber(pe, "%.3g") +
                                                  " m and " + FormatNumber(re / kDeg, "%.3g") +
                                                  " deg away, its final residual)"));
    }
    try {
      CheckLimits(q, "the IK's solution");
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(PathFailure(i, N, q_good, goals.back(), e.what()));
    }
    plan.q.push_back(q);
    plan.tool_W.push_back(goal);
  }
  return plan;
}

Plan MotionPlanner::Linear(const Eigen::VectorXd& q0, const Frame& goal_W, const MotionLimits& limits,
                           double duration_s) const {
  const Frame start = ToolPose(q0);
  const Eigen::Quaterniond q1 = start.q.dot(goal_W.q) < 0 ? Eigen::Quaterniond(-goal_W.q.coeffs()) : goal_W.q;
  double T = duration_s, frac = 0.25;
  if (T <= 0) {
    double T_lin, f_lin, T_rot, f_rot;
    TrapezoidTiming((goal_W.p - start.p).norm(), limits.speed_mps, limits.accel_mps2, &T_lin, &f_lin);
    TrapezoidTiming(start.q.angularDistance(q1), limits.rot_speed_rps, limits.rot_accel_rps2, &T_rot, &f_rot);
    T = std::max(T_lin, T_rot);
    frac = T_lin >= T_rot ? f_lin : f_rot;
  }
  return Within(q0, q0, [&](double k) {
    return Cartesian(q0, T * k, frac, (goal_W.p - start.p).norm(), [&](double s) {
      Frame f;
      f.p = start.p + s * (goal_W.p - start.p);
      f.q = start.q.slerp(s, q1);
      return f;
    });
  });
}

Plan MotionPlanner::Arc(const Eigen::VectorXd& q0, const Eigen::Vector3d& via, const Frame& goal_W,
                        const MotionLimits& limits, double duration_s) const {
  const Frame start = ToolPose(q0);
  const Eigen::Vector3d a = via - start.p, b = goal_W.p - start.p;
  const Eigen::Vector3d n = a.cross(b);
  if (n.norm() < 1e-9 || a.norm() < 1e-6 || b.norm() < 1e-6) {
    throw std::invalid_argument("the start, via and goal points are on one line (or coincide): no circle through them");
  }
  // circumcentre of start, via, goal
  const Eigen::Vector3d c =
      start.p + (b.squaredNorm() * n.cross(a) + a.squaredNorm() * b.cross(n)) / (2 * n.squaredNorm());
  const double r = (start.p - c).norm();
  const Eigen::Vector3d u = (start.p - c) / r, w = n.normalized().cross(u);
  auto angle_of = [&](const Eigen::Vector3d& p) {
    double t = std::atan2((p - c).dot(w), (p - c).dot(u));
    return t < 0 ? t + 2 * M_PI : t;
  };
  const double theta = angle_of(goal_W.p);  // via lies between 0 and theta by the normal's orientation
  const Eigen::Quaterniond q1 = start.q.dot(goal_W.q) < 0 ? Eigen::Quaterniond(-goal_W.q.coeffs()) : goal_W.q;
  double T = duration_s, frac = 0.25;
  if (T <= 0) {
    double T_lin, f_lin, T_rot, f_rot;
    TrapezoidTiming(r * theta, limits.speed_mps, limits.accel_mps2, &T_lin, &f_lin);
    TrapezoidTiming(start.q.angularDistance(q1), limits.rot_speed_rps, limits.rot_accel_rps2, &T_rot, &f_rot);
    T = std::max(T_lin, T_rot);
    frac = T_lin >= T_rot ? f_lin : f_rot;
  }
  return Within(q0, q0, [&](double k) {
    Plan plan = Cartesian(q0, T * k, frac, r * theta, [&](double s) {
      Frame f;
      f.p = c + r * (u * std::cos(theta * s) + w * std::sin(theta * s));
      f.q = start.q.slerp(s, q1);
      return f;
    });
    plan.tool_W.back().p = goal_W.p;  // equal up to rounding
    return plan;
  });
}

Plan MotionPlanner::FromBlend(const BlendStart& b, const Frame& goal_W, const MotionLimits& limits) const {
  const Eigen::Vector3d P1 = b.entry.p, B = b.corner, C = goal_W.p;
  const double d1 = (B - P1).norm();
  const double seg = (C - B).norm();
  if (seg < 1e-9) throw std::invalid_argument("the target is the corner of the blend: nothing to blend into");
  const Eigen::Vector3d u2 = (C - B) / seg;
  const Eigen::Vector3d P2 = B + d1 * u2;
  // the cubic Bézier from P1 along the motion to P2 along the new line (after a line: the
  // quadratic P1, B, P2, degree-elevated); its arc length by a table
  const Eigen::Vector3d t1 = b.tangent.norm() > 0.5 ? b.tangent.normalized() : Eigen::Vector3d((B - P1).normalized());
  const Eigen::Vector3d C1 = P1 + (2.0 / 3.0) * d1 * t1, C2 = P2 - (2.0 / 3.0) * d1 * u2;
  constexpr int kTable = 512;
  std::vector<double> arc(kTable + 1, 0.0);
  auto bezier = [&](double t) {
    const double s = 1 - t;
    return Eigen::Vector3d(s * s * s * P1 + 3 * s * s * t * C1 + 3 * s * t * t * C2 + t * t * t * P2);
  };
  for (int k = 1; k <= kTable; ++k)
    arc[k] = arc[k - 1] + (bezier(double(k) / kTable) - bezier(double(k - 1) / kTable)).norm();
  const double Lb = arc[kTable];
  const double L = Lb + (C - P2).norm();
  const Eigen::Quaterniond q1 = b.entry.q.dot(goal_W.q) < 0 ? Eigen::Quaterniond(-goal_W.q.coeffs()) : goal_W.q;
  const double angle = b.entry.q.angularDistance(q1);
  // the path speed: limited so that the SLERP over the path keeps the angular speed limit
  double v = limits.speed_mps;
  if (angle > 1e-12) v = std::min(v, limits.rot_speed_rps * L / angle);
  const Eigen::VectorXd& q_before = b.q_before.size() == b.q.size() ? b.q_before : b.q;
  // slower by k: the cruise speed by 1/k, the acceleration by 1/k² (the entry speed stays)
  return Within(q_before, b.q, [&](double k) {
    const StartSpeedProfile profile(L, b.speed_mps, v / k, limits.accel_mps2 / (k * k));
    const int N = std::max(1, static_cast<int>(std::ceil(profile.T / period_s_ - 1e-9)));
    std::vector<Frame> goals(N);
    std::vector<double> speeds(N);
    for (int i = 0; i < N; ++i) {
      double s, sv;
      profile.At(std::min((i + 1) * period_s_, profile.T), &s, &sv);
      if (i == N - 1) s = L, sv = 0;
      Frame f;
      if (s < Lb) {
        const int k = static_cast<int>(std::upper_bound(arc.begin(), arc.end(), s) - arc.begin());
        const int k0 = std::clamp(k - 1, 0, kTable - 1);
        const double t = (k0 + (s - arc[k0]) / std::max(1e-15, arc[k0 + 1] - arc[k0])) / kTable;
        f.p = bezier(std::clamp(t, 0.0, 1.0));
      } else {
        f.p = P2 + (s - Lb) * u2;
      }
      if (i == N - 1) f.p = C;
      f.q = b.entry.q.slerp(L > 0 ? s / L : 1.0, q1);
      goals[i] = f;
      speeds[i] = sv;
    }
    Plan plan = SolvePath(b.q, goals, speeds);
    plan.duration_s = N * period_s_;
    return plan;
  });
}

namespace {

// one piece of a path: a line from a to b, or an arc from a (tangent d) turning by `angle` about
// its centre c (radius R, the turn's in-plane normal m: from the arc's start towards c)
struct PathPiece {
  bool arc = false;
  Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero(), c = Eigen::Vector3d::Zero(),
                  d = Eigen::Vector3d::Zero(), m = Eigen::Vector3d::Zero();
  double radius = 0, angle = 0, length = 0;
  Eigen::Vector3d At(double sigma) const {  // the point `sigma` m along the piece
    if (!arc) return a + (b - a) * (length > 0 ? sigma / length : 0.0);
    const double phi = sigma / radius;
    return c - radius * m * std::cos(phi) + radius * d * std::sin(phi);
  }
};

constexpr std::size_t kSplineSteps = 400;  // table samples per spline segment

// a natural cubic spline through points in 3-D, parametrised by chord length, tabulated by arc
// length: point i of the table at u[i], with its arc length; the least radius of curvature
struct SplineTable {
  std::vector<double> u, length;
  std::vector<Eigen::Vector3d> point;
  double min_radius = 1e300;
  Eigen::Vector3d At(double sigma) const {  // the point `sigma` m along (linear between samples)
    const auto it = std::upper_bound(length.begin(), length.end(), sigma);
    if (it == length.begin()) return point.front();
    if (it == length.end()) return point.back();
    const std::size_t i = static_cast<std::size_t>(it - length.begin());
    const double span = length[i] - length[i - 1];
    return point[i - 1] + (span > 0 ? (sigma - length[i - 1]) / span : 0.0) * (point[i] - point[i - 1]);
  }
};

SplineTable SplineThrough(const std::vector<Frame>& p) {
  const std::size_t n = p.size();
  std::vector<double> knot(n, 0.0);  // chord length
  for (std::size_t k = 1; k < n; ++k) knot[k] = knot[k - 1] + (p[k].p - p[k - 1].p).norm();
  // second derivatives m (natural ends: m = 0) by the tridiagonal system, per coordinate
  std::vector<Eigen::Vector3d> m(n, Eigen::Vector3d::Zero());
  if (n > 2) {
    std::vector<double> diag(n, 0.0), upper(n, 0.0);
    std::vector<Eigen::Vector3d> rhs(n, Eigen::Vector3d::Zero());
    for (std::size_t k = 1; k + 1 < n; ++k) {
      const double h0 = knot[k] - knot[k - 1], h1 = knot[k + 1] - knot[k];
      diag[k] = 2 * (h0 + h1);
      upper[k] = h1;
      rhs[k] = 6 * ((p[k + 1].p - p[k].p) / h1 - (p[k].p - p[k - 1].p) / h0);
    }
    for (std::size_t k = 2; k + 1 < n; ++k) {  // forward sweep (lower of row k = h0 of row k)
      const double lower = knot[k] - knot[k - 1], f = lower / diag[k - 1];
      diag[k] -= f * upper[k - 1];
      rhs[k] -= f * rhs[k - 1];
    }
    for (std::size_t k = n - 2; k >= 1; --k) {
      m[k] = (rhs[k] - upper[k] * m[k + 1]) / diag[k];
      if (k == 1) break;
    }
  }
  SplineTable t;
  for (std::size_t k = 0; k + 1 < n; ++k) {
    const double h = knot[k + 1] - knot[k];
    for (std::size_t j = 0; j < kSplineSteps; ++j) {
      const double a = static_cast<double>(j) / kSplineSteps, b = 1 - a;  // weights of p[k+1], p[k]
      const Eigen::Vector3d x =
          b * p[k].p + a * p[k + 1].p + h * h / 6 * ((b * b * b - b) * m[k] + (a * a * a - a) * m[k + 1]);
      const Eigen::Vector3d d1 =
          (p[k + 1].p - p[k].p) / h + h / 6 * ((3 * a * a - 1) * m[k + 1] - (3 * b * b - 1) * m[k]);
      const Eigen::Vector3d d2 = b * m[k] + a * m[k + 1];
      const double curvature = d1.cross(d2).norm() / std::pow(d1.norm(), 3);
      if (curvature > 1e-12) t.min_radius = std::min(t.min_radius, 1 / curvature);
      t.u.push_back(knot[k] + a * h);
      t.length.push_back(t.point.empty() ? 0.0 : t.length.back() + (x - t.point.back()).norm());
      t.point.push_back(x);
    }
  }
  t.u.push_back(knot[n - 1]);
  t.length.push_back(t.length.back() + (p[n - 1].p - t.point.back()).norm());
  t.point.push_back(p[n - 1].p);
  return t;
}

}  // namespace

double PathCornerGap(double l, double theta) {
  if (theta <= 0) return 0;
  const double radius = l / std::tan(theta / 2);
  return radius / std::cos(theta / 2) - radius;
}

Plan MotionPlanner::Path(const Eigen::VectorXd& q0, const std::vector<Frame>& points, double radius_m,
                         const MotionLimits& limits, bool spline) const {
  if (points.empty()) throw std::invalid_argument("no point to move through");
  if (!spline && points.size() > 1 && !(radius_m > 0)) {
    throw std::invalid_argument("a path through several points needs a corner radius r > 0 m (got " +
                                FormatNumber(radius_m, "%g") +
                                "): a sharp corner at constant speed is an infinite "
                                "acceleration");
  }
  std::vector<Frame> p;  // the start, then the points
  p.push_back(ToolPose(q0));
  p.insert(p.end(), points.begin(), points.end());
  const std::size_t n = p.size();
  for (std::size_t k = 1; k < n; ++k) {
    if ((p[k].p - p[k - 1].p).norm() < 1e-6) {
      throw std::invalid_argument("point " + std::to_string(k) + " is where the path already is (" +
                                  (k == 1 ? std::string("the start") : "point " + std::to_string(k - 1)) +
                                  "): every line of the path must be at least 1e-6 m long");
    }
  }
  // the corners: an arc at each interior point, starting l before it
  std::vector<PathPiece> pieces;
  std::vector<double> at_point(n, 0.0);  // path length where each point's orientation is reached
  Eigen::Vector3d from = p[0].p;
  double length = 0, min_radius = 1e300;
  for (std::size_t k = 1; k < n && !spline; ++k) {
    const Eigen::Vector3d d_in = (p[k].p - p[k - 1].p).normalized();
    double l = 0, theta = 0;
    Eigen::Vector3d d_out = d_in;
    if (k + 1 < n) {
      d_out = (p[k + 1].p - p[k].p).normalized();
      theta = std::acos(std::clamp(d_in.dot(d_out), -1.0, 1.0));
      if (theta > M_PI - 1e-6) {
        throw std::invalid_argument("the path turns back on itself at point " + std::to_string(k) +
                                    ": no arc rounds a 180 deg corner");
      }
      if (theta > 1e-9) {
        l = std::min({radius_m, (p[k].p - p[k - 1].p).norm() / 2, (p[k + 1].p - p[k].p).norm() / 2});
      }
    }
    PathPiece line;
    line.a = from;
    line.b = p[k].p - l * d_in;
    line.length = (line.b - line.a).norm();
    length += line.length;
    pieces.push_back(line);
    if (l > 0) {
      PathPiece arc;
      arc.arc = true;
      arc.a = line.b;
      arc.d = d_in;
      arc.m = (d_out - d_out.dot(d_in) * d_in).normalized();
      arc.radius = l / std::tan(theta / 2);
      arc.c = arc.a + arc.radius * arc.m;
      arc.angle = theta;
      arc.length = arc.radius * theta;
      min_radius = std::min(min_radius, arc.radius);
      at_point[k] = length + arc.length / 2;
      length += arc.length;
      pieces.push_back(arc);
      from = p[k].p + l * d_out;
    } else {
      at_point[k] = length;
      from = p[k].p;
    }
  }
  if (!spline) at_point[n - 1] = length;
  // the spline: natural cubic through every point, in the chord length u; positions by arc
  // length from a table of kSplineSteps samples per segment (linear between them)
  SplineTable table;
  if (spline) {
    table = SplineThrough(p);
    length = table.length.back();
    for (std::size_t k = 0; k < n; ++k) at_point[k] = table.length[k * kSplineSteps];
    min_radius = table.min_radius;
  }
  // orientations along the path: SLERP between the points' (shorter arcs)
  std::vector<Eigen::Quaterniond> q(n);
  q[0] = p[0].q;
  for (std::size_t k = 1; k < n; ++k) q[k] = q[k - 1].dot(p[k].q) < 0 ? Eigen::Quaterniond(-p[k].q.coeffs()) : p[k].q;
  // the cruise speed: the settings', the arcs' acceleration across the path, the tool's turn
  double v = limits.speed_mps;
  if (min_radius < 1e300) v = std::min(v, std::sqrt(limits.accel_mps2 * min_radius));
  for (std::size_t k = 1; k < n; ++k) {
    const double turn = q[k - 1].angularDistance(q[k]), span = at_point[k] - at_point[k - 1];
    if (turn > 1e-12) v = std::min(v, limits.rot_speed_rps * span / turn);
  }
  double T = 0, frac = 0.25;
  TrapezoidTiming(length, v, limits.accel_mps2, &T, &frac);
  const auto pose_at = [&](double s) {
    const double sigma = std::clamp(s, 0.0, 1.0) * length;
    Frame f;
    if (spline) {
      f.p = table.At(sigma);
    } else {
      double left = sigma;
      std::size_t i = 0;
      while (i + 1 < pieces.size() && left > pieces[i].length) left -= pieces[i++].length;
      f.p = pieces[i].At(std::min(left, pieces[i].length));
    }
    std::size_t k = 1;
    while (k + 1 < n && sigma > at_point[k]) ++k;
    const double span = at_point[k] - at_point[k - 1];
    f.q = q[k - 1].slerp(span > 0 ? std::clamp((sigma - at_point[k - 1]) / span, 0.0, 1.0) : 1.0, q[k]);
    return f;
  };
  return Within(q0, q0, [&](double k) {
    Plan plan = Cartesian(q0, T * k, frac, length, pose_at);
    plan.tool_W.back() = p[n - 1];  // equal up to rounding
    return plan;
  });
}

Plan MotionPlanner::Self(const Eigen::VectorXd& q0, int joint, double delta, double duration_s) const {
  const int n = model_->dof();
  if (n != 7)
    throw std::invalid_argument("selfmove needs a chain of 7 joints (one redundant), this one has " +
                                std::to_string(n));
  if (joint < 0 || joint >= n)
    throw std::invalid_argument("joint " + std::to_string(joint + 1) + " is not a joint of the chain (1.." +
                                std::to_string(n) + ")");
  if (!(duration_s > 0)) throw std::invalid_argument("t must be > 0 s");
  const Frame held = ToolPose(q0);
  return Within(q0, q0, [&](double k) {
    const int N = std::max(1, static_cast<int>(std::ceil(duration_s * k / period_s_ - 1e-9)));
    const double T = N * period_s_;
    const control::TimeScaling quintic{control::TimeScalingType::kQuintic, 0.25};
    Plan plan;
    plan.duration_s = T;
    Eigen::VectorXd q = q0;
    for (int i = 0; i < N; ++i) {
      const double qj = q0[joint] + delta * control::EvaluateTimeScaling(quintic, T, (i + 1) * period_s_).s;
      // Newton on the square system [J_tool; e_jᵀ] dq = [pose error; qj − q_j]
      double pe = 1, re = 1, je = 1;
      for (int it = 0; it < kMaxIterations && !(pe < kTolPos_m && re < kTolRot_rad && je < kTolRot_rad); ++it) {
        const Frame x = ToolPose(q);
        Eigen::Matrix<double, 7, 1> e;
        e.head<3>() = held.p - x.p;
        e.segment<3>(3) = control::RotationVector((held.q * x.q.conjugate()).toRotationMatrix());
        e[6] = qj - q[joint];
        pe = e.head<3>().norm();
        re = e.segment<3>(3).norm();
        je = std::abs(e[6]);
        Eigen::MatrixXd J = model_->Jacobian();
        J.topRows(3) -= Skew(x.p - model_->TipPose().p_W) * J.bottomRows(3);
        Eigen::Matrix<double, 7, 7> A;
        A.topRows(6) = J;
        A.row(6).setZero();
        A(6, joint) = 1.0;
        q += A.colPivHouseholderQr().solve(e);
      }
      if (!(pe < kTolPos_m * 10 && re < kTolRot_rad * 10 && je < kTolRot_rad * 10)) {
        throw std::invalid_argument(Percent(i, N) + ": the tool pose cannot be held while joint " +
                                    model_->joint_names()[joint] + " moves (a singular configuration?)");
      }
      CheckLimits(q, Percent(i, N));
      plan.q.push_back(q);
      plan.tool_W.push_back(held);
    }
    return plan;
  });
}

}  // namespace vlab::task
