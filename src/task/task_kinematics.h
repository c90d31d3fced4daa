// Kinematics queries of a robot program's chain that never move it: forward
// kinematics, inverse kinematics (the nearest solution, or every branch with
// the redundant joint held) and reachability (the task language's fk, ik and
// reachable).
//
// Frames: every frame here is the tool frame in the world W (the planner's
// ToolPose: tip site composed with the planner's tool); the caller composes
// the script's base frame. Joints: chain order, rad.
//
// Closed form (7 hinges, S1 S2 S3 E1 E2 W1 W2 as on the PA10): with the third
// joint (S3) held, the chain is a spherical shoulder (the axes of joints 1-3
// meet in one point S), an elbow (joint 4) and a spherical wrist (the axes of
// joints 5-7 meet in one point W). In product-of-exponentials form, with the
// joint axes and points read from the model at zero joints:
//   elbow     |W − S| fixes joint 4: two values (Paden–Kahan subproblem 3)
//   shoulder  joints 1, 2 turn the upper arm so that the wrist centre lands
//             on W: two values (subproblem 2)
//   wrist     joints 5, 6 point the last axis, joint 7 turns about it: two
//             values (subproblem 2, then subproblem 1)
// so up to 8 branches, each refined by Newton steps (S3 held) to 1e-9 m and
// 1e-9 rad. A joint whose range spans more than a turn (the PA10's E2 and W2,
// ±255°) gives a branch once for each of its angles within the limits. The
// geometric assumptions are checked at construction (lines meeting within
// 1e-7 m); where they do not hold the branches come from Newton's method from
// a fixed set of 64 seeds (a Halton sequence over the joint ranges), the
// redundant joint held.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "control/robot_model.h"
#include "task/task_motion.h"
#include "task/task_values.h"

namespace vlab::task {

/// Inverse, forward kinematics and reachability of one chain. Uses the
/// model's scratch state (not thread-safe, like RobotModel).
class Kinematics {
 public:
  /// `model` and `planner` (on that model) outlive the instance. Reads the
  /// chain's geometry at zero joints and checks the closed form's assumptions
  /// (closed_form(), and why_not() when they fail). Never throws.
  Kinematics(control::RobotModel* model, const MotionPlanner* planner);

  /// Whether the closed form applies; when not, why (e.g. "the axes of S1 and
  /// S2 do not meet: 0.03 m apart").
  bool closed_form() const { return closed_form_; }
  const std::string& why_not() const { return why_not_; }
  /// The joint held in All() (the third of a 7-joint chain, else none: -1).
  int redundant() const { return redundant_; }

  /// Tool pose (world) at q. Throws std::invalid_argument: "expected 7 joint
  /// angles, got 6", "joint E1 is nan, not a finite angle", "joint E1 = 150
  /// deg is beyond its upper limit 137 deg".
  Frame Fk(const Eigen::VectorXd& q) const;

  /// The joints nearest `seed` that put the tool at `goal_W`: the planner's
  /// Newton IK from `seed`; when that fails (no convergence, or a solution
  /// beyond a limit), the nearest of the branches with the redundant joint at
  /// the seed's value. Throws std::invalid_argument saying why there is none:
  /// the target not finite, out of reach ("the wrist centre would be 1.021 m
  /// from the shoulder, the arm reaches 0.95 m"), or every solution found
  /// beyond a limit (naming the joint).
  Eigen::VectorXd Nearest(const Frame& goal_W, const Eigen::VectorXd& seed) const;

  /// Every solution with the redundant joint at the seed's value, within the
  /// limits, sorted by distance from `seed` (Euclidean, rad), duplicates
  /// (within 1e-6 rad) removed; never empty. Throws std::invalid_argument as
  /// Nearest does, and for a singular target, whose solutions form a
  /// continuum ("singular target: wrist singularity near W1 = 0 deg ...").
  std::vector<Eigen::VectorXd> All(const Frame& goal_W, const Eigen::VectorXd& seed) const;

  /// Whether Nearest() finds a solution (it does whenever All() would return
  /// one). Throws std::invalid_argument only for a non-finite target or a
  /// seed of the wrong size.
  bool Reachable(const Frame& goal_W, const Eigen::VectorXd& seed) const;

 private:
  // the chain at zero joints, world: axis directions w and points r on each axis
  struct Geometry {
    std::vector<Eigen::Vector3d> w, r;
    Eigen::Vector3d shoulder, wrist;  // S and W (zero joints)
    Frame tool0;                      // tool pose at zero joints
  };
  // the outcome of the branch search
  struct Branches {
    std::vector<Eigen::VectorXd> q;  // within limits, refined, sorted, unique
    std::string reach;               // non-empty: out of reach, why
    std::string limits;              // non-empty: a candidate beyond a limit (the nearest one's joint)
    std::string singular;            // non-empty: the target is singular (a continuum of solutions)
    std::string other;               // non-empty: no candidate at all, why
  };
  Geometry ReadGeometry() const;
  // why the closed form does not apply to the chain, or ""
  std::string ClosedFormMisfit() const;
  Branches Solve(const Frame& goal_W, const Eigen::VectorXd& seed) const;
  // the closed-form candidates (angles in (-pi, pi]), before refinement
  std::vector<Eigen::VectorXd> ClosedForm(const Frame& goal_W, double held, Branches* out) const;
  std::vector<Eigen::VectorXd> Seeds(double held) const;
  // Newton steps from q with joint `held` fixed (-1: none); true when within 1e-9 m and rad
  bool Refine(const Frame& goal_W, int held, int iterations, Eigen::VectorXd* q) const;
  // keeps the candidates' angles within limits (each turn of a joint with range > 360 deg)
  void WithinLimits(const Eigen::VectorXd& q, Branches* out, std::vector<Eigen::VectorXd>* kept) const;
  void CheckSeed(const Eigen::VectorXd& seed) const;

  control::RobotModel* model_;
  const MotionPlanner* planner_;
  bool closed_form_ = false;
  std::string why_not_;
  int redundant_ = -1;
};

}  // namespace vlab::task
