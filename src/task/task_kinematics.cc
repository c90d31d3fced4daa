#include "task/task_kinematics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <utility>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "control/trajectory.h"
#include "task/task_units.h"

namespace vlab::task {

namespace {

constexpr double kTol = 1e-9;       // m and rad: a solution's residual
constexpr double kMeet_m = 1e-7;    // axes closer than this meet
constexpr double kSame_rad = 1e-6;  // two solutions closer than this (each joint) are one
constexpr double kSingular = 1e-6;  // a vector this close to a rotation axis (relative) leaves it free
constexpr int kSeeds = 64;          // Newton seeds when the closed form does not apply

Eigen::Matrix3d Rot(const Eigen::Vector3d& w, double angle) { return Eigen::AngleAxisd(angle, w).toRotationMatrix(); }

// the part of v perpendicular to the unit axis w
Eigen::Vector3d Across(const Eigen::Vector3d& w, const Eigen::Vector3d& v) { return v - w * w.dot(v); }

// the closest points of two lines (point r, unit direction w): their midpoint and gap;
// false when the lines are parallel
bool Meet(const Eigen::Vector3d& r1, const Eigen::Vector3d& w1, const Eigen::Vector3d& r2, const Eigen::Vector3d& w2,
          Eigen::Vector3d* point, double* gap) {
  const Eigen::Vector3d d = r2 - r1;
  const double b = w1.dot(w2), den = 1 - b * b;
  if (den < 1e-12) return false;
  const double t1 = (d.dot(w1) - b * d.dot(w2)) / den, t2 = (b * d.dot(w1) - d.dot(w2)) / den;
  const Eigen::Vector3d c1 = r1 + t1 * w1, c2 = r2 + t2 * w2;
  *point = (c1 + c2) / 2;
  *gap = (c1 - c2).norm();
  return true;
}

// Paden–Kahan subproblem 1: the angle about unit axis w that turns p onto q; `free` when p
// lies on the axis (any angle does)
double TurnOnto(const Eigen::Vector3d& w, const Eigen::Vector3d& p, const Eigen::Vector3d& q, bool* free) {
  const Eigen::Vector3d a = Across(w, p), b = Across(w, q);
  if (a.norm() < kSingular * std::max(1.0, p.norm())) *free = true;
  return std::atan2(w.dot(a.cross(b)), a.dot(b));
}

// Paden–Kahan subproblem 2: the angles (t1, t2) with Rot(w1, t1)·Rot(w2, t2)·p = q, axes
// through one point (the origin here), |p| = |q|: none, or two (equal when tangent)
std::vector<std::pair<double, double>> TurnTwice(const Eigen::Vector3d& w1, const Eigen::Vector3d& w2,
                                                 const Eigen::Vector3d& p, const Eigen::Vector3d& q, bool* free) {
  const double c12 = w1.dot(w2), den = c12 * c12 - 1;
  const double alpha = (c12 * w2.dot(p) - w1.dot(q)) / den, beta = (c12 * w1.dot(q) - w2.dot(p)) / den;
  const Eigen::Vector3d n = w1.cross(w2);
  const double g2 = (p.squaredNorm() - alpha * alpha - beta * beta - 2 * alpha * beta * c12) / n.squaredNorm();
  if (g2 < -1e-9 * p.squaredNorm()) return {};
  const double g = std::sqrt(std::max(0.0, g2));
  std::vector<std::pair<double, double>> out;
  for (const double sign : {1.0, -1.0}) {
    // the point between the two turns: Rot(w2, t2)·p = z = Rot(w1, -t1)·q
    const Eigen::Vector3d z = alpha * w1 + beta * w2 + sign * g * n;
    const double t2 = TurnOnto(w2, p, z, free), t1 = TurnOnto(w1, z, q, free);
    out.emplace_back(t1, t2);
  }
  return out;
}

// "joint E1 = 150 deg is beyond its upper limit 137 deg"
std::string Beyond(const std::string& name, double value, double lo, double hi) {
  const bool below = value < lo;
  return "joint " + name + " = " + FormatNumber(value / kDeg) + " deg is beyond its " + (below ? "lower" : "upper") +
         " limit " + FormatNumber((below ? lo : hi) / kDeg) + " deg";
}

// the i-th point (from 1) of the Halton sequence of `base`, in [0, 1)
double Halton(int i, int base) {
  double f = 1, r = 0;
  for (; i > 0; i /= base) {
    f /= base;
    r += f * (i % base);
  }
  return r;
}

}  // namespace

Kinematics::Kinematics(control::RobotModel* model, const MotionPlanner* planner) : model_(model), planner_(planner) {
  if (model_->dof() == 7) redundant_ = 2;
  why_not_ = ClosedFormMisfit();
  closed_form_ = why_not_.empty();
}

std::string Kinematics::ClosedFormMisfit() const {
  const int n = model_->dof();
  const std::vector<std::string>& names = model_->joint_names();
  if (n != 7) return "the chain has " + std::to_string(n) + " joints (the closed form is for 7)";
  for (int i = 0; i < n; ++i) {
    if (model_->model().jnt_type[model_->joint_ids()[i]] != mjJNT_HINGE) return "joint " + names[i] + " is not a hinge";
  }
  const Geometry g = ReadGeometry();
  // the shoulder: the axes of joints 1-3 meet; the wrist: the axes of joints 5-7 meet
  for (const int first : {0, 4}) {
    Eigen::Vector3d point;
    double gap;
    if (!Meet(g.r[first], g.w[first], g.r[first + 1], g.w[first + 1], &point, &gap) || gap > kMeet_m) {
      return "the axes of " + names[first] + " and " + names[first + 1] + " do not meet";
    }
    const double off = Across(g.w[first + 2], point - g.r[first + 2]).norm();
    if (off > kMeet_m) {
      return "the axis of " + names[first + 2] + " misses the point where those of " + names[first] + " and " +
             names[first + 1] + " meet by " + FormatNumber(off, "%.3g") + " m";
    }
  }
  if (g.w[5].cross(g.w[6]).norm() < 1e-3) return "the axes of " + names[5] + " and " + names[6] + " are parallel";
  // the elbow changes the shoulder-wrist distance
  const Eigen::Vector3d s = g.shoulder - g.r[3], p = g.wrist - g.r[3];
  if (Across(g.w[3], s).norm() < 1e-3 || Across(g.w[3], p).norm() < 1e-3) {
    return "the elbow " + names[3] + " does not change the shoulder-wrist distance";
  }
  return "";
}

Kinematics::Geometry Kinematics::ReadGeometry() const {
  const int n = model_->dof();
  Geometry g;
  g.tool0 = planner_->ToolPose(Eigen::VectorXd::Zero(n));  // (sets the model's state to zero joints)
  const mjData& d = model_->data();
  for (int i = 0; i < n; ++i) {
    const int id = model_->joint_ids()[i];
    g.w.push_back(Eigen::Map<const Eigen::Vector3d>(d.xaxis + 3 * id).normalized());
    g.r.push_back(Eigen::Map<const Eigen::Vector3d>(d.xanchor + 3 * id));
  }
  g.shoulder = g.wrist = Eigen::Vector3d::Zero();
  double gap;
  if (n == 7) {
    Meet(g.r[0], g.w[0], g.r[1], g.w[1], &g.shoulder, &gap);
    Meet(g.r[4], g.w[4], g.r[5], g.w[5], &g.wrist, &gap);
  }
  return g;
}

Frame Kinematics::Fk(const Eigen::VectorXd& q) const {
  const int n = model_->dof();
  if (q.size() != n) {
    throw std::invalid_argument("expected " + std::to_string(n) + " joint angles, got " + std::to_string(q.size()));
  }
  for (int i = 0; i < n; ++i) {
    const std::string& name = model_->joint_names()[i];
    if (!std::isfinite(q[i]))
      throw std::invalid_argument("joint " + name + " is " + FormatNumber(q[i]) + ", not a finite angle");
    const double lo = model_->lower_limits()[i], hi = model_->upper_limits()[i];
    if (q[i] < lo - kTol || q[i] > hi + kTol) throw std::invalid_argument(Beyond(name, q[i], lo, hi));
  }
  return planner_->ToolPose(q);
}

void Kinematics::CheckSeed(const Eigen::VectorXd& seed) const {
  if (seed.size() != model_->dof()) {
    throw std::invalid_argument("the seed has " + std::to_string(seed.size()) + " joint angles, the chain " +
                                std::to_string(model_->dof()));
  }
  for (int i = 0; i < seed.size(); ++i) {
    if (!std::isfinite(seed[i])) {
      throw std::invalid_argument("the seed's joint " + model_->joint_names()[i] + " is not a finite angle");
    }
  }
}

namespace {
void CheckGoal(const Frame& goal) {
  if (!goal.p.allFinite()) throw std::invalid_argument("the target position is not finite (a NaN or inf)");
  if (!goal.q.coeffs().allFinite()) throw std::invalid_argument("the target rotation is not finite (a NaN or inf)");
}
}  // namespace

std::vector<Eigen::VectorXd> Kinematics::ClosedForm(const Frame& goal_W, double held, Branches* out) const {
  const Geometry g = ReadGeometry();
  const Eigen::Matrix3d R0 = g.tool0.q.toRotationMatrix(), Rg = goal_W.q.normalized().toRotationMatrix();
  // the wrist centre is fixed in the tool frame: where the goal puts it
  const Eigen::Vector3d u = goal_W.p + Rg * (R0.transpose() * (g.wrist - g.tool0.p)) - g.shoulder;
  // elbow (subproblem 3): s·Rot(w, t4)·p = k, i.e. A cos t4 + B sin t4 = C
  const Eigen::Vector3d& we = g.w[3];
  const Eigen::Vector3d s = g.shoulder - g.r[3], p = g.wrist - g.r[3];
  const double k = (p.squaredNorm() + s.squaredNorm() - u.squaredNorm()) / 2;
  const double A = s.dot(Across(we, p)), B = s.dot(we.cross(p)), C = k - we.dot(s) * we.dot(p);
  const double rho = std::hypot(A, B);
  if (std::abs(C) > rho * (1 + 1e-12)) {
    const double base = p.squaredNorm() + s.squaredNorm() - 2 * we.dot(s) * we.dot(p);
    const double far = std::sqrt(base + 2 * rho), near = std::sqrt(std::max(0.0, base - 2 * rho));
    out->reach = "the wrist centre would be " + FormatNumber(u.norm(), "%.3f") + " m from the shoulder, " +
                 (C < 0 ? "the arm reaches " + FormatNumber(far, "%.3f") + " m"
                        : "the arm folds to no closer than " + FormatNumber(near, "%.3f") + " m");
    return {};
  }
  const double phi = std::atan2(B, A), delta = std::acos(std::clamp(C / rho, -1.0, 1.0));
  std::vector<Eigen::VectorXd> candidates;
  bool shoulder_free = false, wrist_free = false, shoulder_none = false;
  for (const double t4 : {phi + delta, phi - delta}) {
    // shoulder (subproblem 2): joints 1, 2 turn the wrist centre of (held, t4) onto u
    const Eigen::Vector3d v = Rot(g.w[2], held) * (g.r[3] + Rot(we, t4) * p - g.shoulder);
    const auto shoulder = TurnTwice(g.w[0], g.w[1], v, u, &shoulder_free);
    shoulder_none = shoulder_none || shoulder.empty();
    for (const auto& [t1, t2] : shoulder) {
      // wrist: Rot5·Rot6·Rot7 = M; joints 5, 6 point axis 7 (subproblem 2), joint 7 turns about it
      const Eigen::Matrix3d arm = Rot(g.w[0], t1) * Rot(g.w[1], t2) * Rot(g.w[2], held) * Rot(we, t4);
      const Eigen::Matrix3d M = arm.transpose() * Rg * R0.transpose();
      for (const auto& [t5, t6] : TurnTwice(g.w[4], g.w[5], g.w[6], M * g.w[6], &wrist_free)) {
        const Eigen::Matrix3d N = (Rot(g.w[4], t5) * Rot(g.w[5], t6)).transpose() * M;
        const Eigen::Vector3d x = Across(g.w[6], g.w[5]).normalized();
        bool unused = false;
        Eigen::VectorXd q(7);
        q << t1, t2, held, t4, t5, t6, TurnOnto(g.w[6], x, N * x, &unused);
        candidates.push_back(q);
      }
    }
  }
  if (candidates.empty() && shoulder_none) {
    out->other = "with " + model_->joint_names()[2] + " held at " + FormatNumber(held / kDeg) +
                 " deg the shoulder cannot turn the wrist centre there (another " + model_->joint_names()[2] + " may)";
  }
  if (!candidates.empty() && (shoulder_free || wrist_free)) out->singular = "singular";  // named once refined
  return candidates;
}

std::vector<Eigen::VectorXd> Kinematics::Seeds(double held) const {
  static const int kBases[] = {2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37};
  const int n = model_->dof();
  std::vector<Eigen::VectorXd> seeds;
  for (int i = 1; i <= kSeeds; ++i) {
    Eigen::VectorXd q(n);
    for (int j = 0; j < n; ++j) {
      double lo = model_->lower_limits()[j], hi = model_->upper_limits()[j];
      if (!std::isfinite(lo) || !std::isfinite(hi)) lo = -M_PI, hi = M_PI;
      q[j] = lo + Halton(i, kBases[j % 12]) * (hi - lo);
    }
    if (redundant_ >= 0) q[redundant_] = held;
    seeds.push_back(q);
  }
  return seeds;
}

bool Kinematics::Refine(const Frame& goal_W, int held, int iterations, Eigen::VectorXd* q) const {
  const Eigen::Quaterniond goal_q = goal_W.q.normalized();
  for (int it = 0;; ++it) {
    const Frame x = planner_->ToolPose(*q);  // (sets the model's state for the Jacobian)
    Eigen::Matrix<double, 6, 1> e;
    e.head<3>() = goal_W.p - x.p;
    e.tail<3>() = control::RotationVector((goal_q * x.q.conjugate()).toRotationMatrix());
    if (e.head<3>().norm() < kTol && e.tail<3>().norm() < kTol) return true;
    if (it == iterations || !e.allFinite()) return false;
    Eigen::MatrixXd J = model_->Jacobian();
    J.topRows(3) -= Skew(x.p - model_->TipPose().p_W) * J.bottomRows(3);  // the tool point
    if (held >= 0) J.col(held).setZero();
    const Eigen::Matrix<double, 6, 6> JJt =
        J * J.transpose() + kIkDamping * kIkDamping * Eigen::Matrix<double, 6, 6>::Identity();
    Eigen::VectorXd dq = J.transpose() * JJt.partialPivLu().solve(e);
    if (dq.norm() > kIkMaxStep_rad) dq *= kIkMaxStep_rad / dq.norm();
    *q += dq;
  }
}

void Kinematics::WithinLimits(const Eigen::VectorXd& q, Branches* out, std::vector<Eigen::VectorXd>* kept) const {
  // each joint's angles within its limits: q and the same angle a turn or more away
  const int n = static_cast<int>(q.size());
  std::vector<std::vector<double>> angles(n);
  for (int i = 0; i < n; ++i) {
    const double lo = model_->lower_limits()[i], hi = model_->upper_limits()[i];
    const double wrapped = std::remainder(q[i], 2 * M_PI);
    for (int turn = -3; turn <= 3; ++turn) {
      const double a = wrapped + turn * 2 * M_PI;
      if (a >= lo - kTol && a <= hi + kTol) angles[i].push_back(std::clamp(a, lo, hi));
    }
    if (angles[i].empty()) {
      if (out->limits.empty()) out->limits = Beyond(model_->joint_names()[i], wrapped, lo, hi);
      return;
    }
  }
  // every combination
  std::vector<int> pick(n, 0);
  for (;;) {
    Eigen::VectorXd s(n);
    for (int i = 0; i < n; ++i) s[i] = angles[i][pick[i]];
    kept->push_back(s);
    int i = 0;
    while (i < n && ++pick[i] == static_cast<int>(angles[i].size())) pick[i++] = 0;
    if (i == n) return;
  }
}

Kinematics::Branches Kinematics::Solve(const Frame& goal_W, const Eigen::VectorXd& seed) const {
  Branches b;
  const double held = redundant_ >= 0 ? seed[redundant_] : 0.0;
  const std::vector<Eigen::VectorXd> candidates = closed_form_ ? ClosedForm(goal_W, held, &b) : Seeds(held);
  std::vector<Eigen::VectorXd> refined;
  for (Eigen::VectorXd q : candidates) {
    if (Refine(goal_W, redundant_, closed_form_ ? 20 : 200, &q)) refined.push_back(q);
  }
  auto nearer = [&](const Eigen::VectorXd& a, const Eigen::VectorXd& c) {
    return (a - seed).norm() < (c - seed).norm();
  };
  std::sort(refined.begin(), refined.end(), nearer);
  if (!b.singular.empty()) {
    const std::string sing = refined.empty() ? "" : planner_->Singularity(refined.front());
    b.singular = "singular target: " + (sing.empty() ? std::string("a joint axis lines up with another") : sing) +
                 ": its solutions form a continuum";
  }
  std::vector<Eigen::VectorXd> kept;
  for (const Eigen::VectorXd& q : refined) WithinLimits(q, &b, &kept);
  std::sort(kept.begin(), kept.end(), nearer);
  for (const Eigen::VectorXd& q : kept) {
    const bool seen = std::any_of(b.q.begin(), b.q.end(),
                                  [&](const Eigen::VectorXd& o) { return (o - q).cwiseAbs().maxCoeff() < kSame_rad; });
    if (!seen) b.q.push_back(q);
  }
  if (b.q.empty() && b.reach.empty() && b.limits.empty() && b.other.empty()) {
    b.other = closed_form_ ? "no branch of the closed form converged to within 1e-9 m and 1e-9 rad"
                           : "Newton's method from " + std::to_string(kSeeds) +
                                 " seeds found no joints that put the tool there (within 1e-9 m and 1e-9 rad)";
  }
  return b;
}

namespace {
// the error of an empty branch search, most telling first
std::string NoSolution(const std::string& reach, const std::string& limits, const std::string& other,
                       const std::string& newton) {
  if (!reach.empty()) return "out of reach: " + reach;
  if (!limits.empty()) return "every solution found is beyond a joint limit; the nearest has " + limits;
  if (!newton.empty()) return newton;
  return other;
}
}  // namespace

Eigen::VectorXd Kinematics::Nearest(const Frame& goal_W, const Eigen::VectorXd& seed) const {
  CheckSeed(seed);
  CheckGoal(goal_W);
  std::string newton;
  try {
    Eigen::VectorXd q = planner_->Ik(seed, goal_W);
    // (the planner accepts 1e-8; polished to 1e-9, within the limits still)
    if (Refine(goal_W, -1, 20, &q)) {
      planner_->CheckLimits(q, "the IK's solution");
      return q;
    }
  } catch (const std::invalid_argument& e) {
    newton = e.what();
  }
  const Branches b = Solve(goal_W, seed);
  if (!b.q.empty()) return b.q.front();
  throw std::invalid_argument(NoSolution(b.reach, b.limits, b.other, newton));
}

std::vector<Eigen::VectorXd> Kinematics::All(const Frame& goal_W, const Eigen::VectorXd& seed) const {
  CheckSeed(seed);
  CheckGoal(goal_W);
  const Branches b = Solve(goal_W, seed);
  if (!b.singular.empty()) throw std::invalid_argument(b.singular);
  if (b.q.empty()) throw std::invalid_argument(NoSolution(b.reach, b.limits, b.other, ""));
  return b.q;
}

bool Kinematics::Reachable(const Frame& goal_W, const Eigen::VectorXd& seed) const {
  CheckSeed(seed);
  CheckGoal(goal_W);
  try {
    Nearest(goal_W, seed);
    return true;
  } catch (const std::invalid_argument&) {
    return false;
  }
}

}  // namespace vlab::task
