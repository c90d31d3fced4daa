// The motion generator of one robot program: plans a whole move before it
// starts (so that a target out of reach or a joint limit on the way is an
// error before the arm moves), then hands out one joint reference per control
// period.
//
// Ports
//   input   the chain's joint reference at the start of a move (the previous
//           plan's end, or the measured joints before the first move)
//   output  q_ref (chain order, rad), one per period: the arm device's
//           position command; the planned tool pose of each sample
//   rate    one sample per control period `period_s`; sample i of a plan is
//           the reference for the end of the i-th period after its start
// Plans (all frames are the tool frame in the world W; the caller composes
// base and tool frames):
//   joint      straight line in joint space, trapezoidal speed (JointTrajectory)
//   linear     straight line of the tool point, orientation by SLERP
//              (CartesianTrajectory), trapezoidal speed along the path
//   arc        circular arc through a via point to a goal; orientation by
//              SLERP from start to goal
//   self       null-space motion: one joint driven by a quintic while the tool
//              pose is held (7-DOF arm: the elbow swings about the
//              shoulder-wrist line)
//   path       through a list of points at constant tool speed (movep): lines
//              joined by circular arcs tangent to both, each starting r before
//              its corner, or a cubic spline through every point (spline);
//              the path speed is a trapezoid over the whole length
//   blend      the next straight move entered from a blended one (movel's r):
//              a quadratic Bézier round the corner, then the line; the path
//              speed carries over (FromBlend)
// Inverse kinematics: each Cartesian sample is solved by Newton steps
// q += J⁺·e (damped least squares, λ = 1e-6) from the previous sample, to
// 1e-9 m and 1e-9 rad; a sample that does not converge, or a joint beyond its
// limits, fails the plan with std::invalid_argument saying where on the path.
// Joint speed and acceleration limits (task_rates.h): every plan's samples are
// differentiated at the period; a plan that needs more than a joint allows is
// planned again with its timing stretched by the factor that brings the worst
// joint within (the same path, slower), or refused (JointRateLimits::refuse)
// with a message naming the joint, what it needs and what it may.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "control/robot_model.h"
#include "task/task_rates.h"
#include "task/task_values.h"

namespace vlab::task {

/// Speeds and accelerations of moves (the script's speed()/accel() settings).
struct MotionLimits {
  double speed_mps = 0.1;            ///< tool linear speed, m/s
  double accel_mps2 = 0.5;           ///< tool linear acceleration, m/s²
  double rot_speed_rps = 0.7854;     ///< tool angular speed, rad/s (45°/s)
  double rot_accel_rps2 = 3.1416;    ///< tool angular acceleration, rad/s² (180°/s²)
  double joint_speed_rps = 0.5236;   ///< movej: speed of the fastest joint, rad/s (30°/s)
  double joint_accel_rps2 = 1.5708;  ///< movej: acceleration of the fastest joint, rad/s² (90°/s²)
};

/// A planned move: one joint reference per period.
struct Plan {
  std::vector<Eigen::VectorXd> q;  ///< chain joints, rad, sample i at (i + 1)·period after the start
  std::vector<Frame> tool_W;       ///< planned tool pose of each sample (world); empty for joint moves
  std::vector<double> speed_mps;   ///< planned tool path speed of each sample (Cartesian moves)
  double duration_s = 0;
};

/// Where a move with a blend radius is left for the next one (blending): the
/// sample of the running plan at which the tool came within the radius of
/// the corner (the running move's target).
struct BlendStart {
  Eigen::VectorXd q;                                  ///< chain joints of that sample
  Frame entry;                                        ///< its tool pose (world): P1, within the radius of the corner
  Eigen::Vector3d corner = Eigen::Vector3d::Zero();   ///< the running move's target point B (world)
  Eigen::Vector3d tangent = Eigen::Vector3d::Zero();  ///< unit direction of motion at P1 (a line: towards B)
  double speed_mps = 0;                               ///< the tool's path speed there
  Eigen::VectorXd q_before;                           ///< chain joints one period before q (empty: at rest at q)
};

class MotionPlanner {
 public:
  /// `model` is the robot's chain (owned by the caller, outlives the planner);
  /// `tool` the tip site -> tool transform.
  MotionPlanner(control::RobotModel* model, double period_s);

  void set_tool(const Frame& tip_T_tool) { tool_ = tip_T_tool; }
  /// The joint speed and acceleration limits every plan keeps (default:
  /// DefaultRateLimits); std::invalid_argument unless one positive value per joint.
  void set_rate_limits(const JointRateLimits& limits);
  const JointRateLimits& rate_limits() const { return rates_; }
  const Frame& tool() const { return tool_; }

  /// Tool pose (world) at chain joints q.
  Frame ToolPose(const Eigen::VectorXd& q) const;
  /// Joints that put the tool at `goal_W`, by Newton steps from q0. Throws
  /// std::invalid_argument ("out of reach: 12.3 mm and 2.1 deg away after
  /// 200 iterations", "joint S2 beyond its limits ...").
  Eigen::VectorXd Ik(const Eigen::VectorXd& q0, const Frame& goal_W) const;
  /// Ik for a pose one period away from the joints q0 (force mode's per-period
  /// command): the same Newton steps, but never throws. False, with *why saying
  /// what failed (the pose out of reach, a joint beyond its limits), when it
  /// does not converge to 1e-8 m and 1e-8 rad within its limits.
  bool Track(const Eigen::VectorXd& q0, const Frame& goal_W, Eigen::VectorXd* q, std::string* why) const;

  /// Plans; every function throws std::invalid_argument naming the problem.
  /// Every plan keeps rate_limits(): slowed down to them, or refused.
  /// Joint: a trapezoid of the fastest joint at limits.joint_speed_rps and
  /// joint_accel_rps2, each lowered (when not refusing) so that no joint
  /// exceeds its own limit: T = D/v + v/a (D the largest joint distance), or
  /// 2·sqrt(D/a) when D < v²/a; rounded up to whole periods.
  Plan Joint(const Eigen::VectorXd& q0, const Eigen::VectorXd& q1, const MotionLimits& limits,
             double duration_s = 0) const;
  Plan Linear(const Eigen::VectorXd& q0, const Frame& goal_W, const MotionLimits& limits, double duration_s = 0) const;
  Plan Arc(const Eigen::VectorXd& q0, const Eigen::Vector3d& via_W, const Frame& goal_W, const MotionLimits& limits,
           double duration_s = 0) const;
  /// The next straight move, entered from a blend: from P1 (b.entry, |B − P1|
  /// = d ≤ r) along the cubic Bézier P1, P1 + ⅔·d·t, P2 − ⅔·d·u, P2 (t the
  /// direction of motion at P1, P2 = B + d·u, u = (C − B)/|C − B|: tangent to
  /// the path at both ends; after a line, t points at B and the curve is the
  /// quadratic Bézier P1, B, P2, which passes B at 0.25·|2B − P1 − P2|, 0.354·d
  /// for a right angle) and on along the line P2 → C to rest at the goal C.
  /// The path speed starts at b.speed_mps (no stop) and follows a trapezoid
  /// to rest; orientation by SLERP from P1's to the goal's over the path.
  Plan FromBlend(const BlendStart& b, const Frame& goal_W, const MotionLimits& limits) const;
  /// Through `points` (world; the last is the goal) at constant tool speed:
  /// the polyline start, points[0], ..., points[n-1], each corner rounded by a
  /// circular arc tangent to both of its lines, which starts and ends
  /// l = min(r, half of either line) from the corner (radius l / tan(θ/2), θ
  /// the turn; the tool passes the corner at PathCornerGap(l, θ)).
  /// Orientation by SLERP from one point's to the next, each point's reached
  /// at the middle of its arc. One trapezoid of the path speed over the whole
  /// length: accelerate at limits.accel_mps2 to the cruise speed, hold it, stop at
  /// the goal. The cruise speed is limits.speed_mps, lowered so that no arc
  /// needs more than limits.accel_mps2 across the path (v²/R) and no piece
  /// turns the tool faster than limits.rot_speed_rps (then the rate limits, as
  /// every plan). r <= 0 with more than one point, a repeated point and a
  /// line shorter than 1e-6 m are refused.
  /// With `spline`: through every point exactly, on the natural cubic spline
  /// through the start and the points (chord-length parameter, curvature
  /// continuous), at constant speed along its arc length; `radius_m` unused;
  /// the cruise speed lowered to sqrt(accel / curvature) at the tightest bend.
  Plan Path(const Eigen::VectorXd& q0, const std::vector<Frame>& points, double radius_m, const MotionLimits& limits,
            bool spline = false) const;
  /// Moves chain joint `joint` by `delta` rad over `duration_s` with the tool held.
  Plan Self(const Eigen::VectorXd& q0, int joint, double delta, double duration_s) const;

  /// Throws unless every joint of q is within its limits ("at 40% of the
  /// path: joint E1 = 172.1 deg beyond its limit 170 deg").
  void CheckLimits(const Eigen::VectorXd& q, const std::string& where) const;

  /// The singularity the chain is in or near at q, or "" when none: two joint
  /// axes with joints between them line up (within 10 deg, their lines within
  /// 1 mm), e.g. "wrist singularity near W1 = 0.4 deg (the axes of E2 and W2
  /// line up)"; the joint named is the one between them closest to 0 or 180 deg.
  std::string Singularity(const Eigen::VectorXd& q) const;

 private:
  // the plan of replan(1), or of replan(k) with the smallest stretch k found that keeps
  // every joint within rate_limits() (from q_before, q_start: the two samples before it)
  template <class Replan>
  Plan Within(const Eigen::VectorXd& q_before, const Eigen::VectorXd& q_start, Replan replan) const;
  // samples of a Cartesian path: pose(s) for s of a trapezoid in time
  template <class PoseAt>
  Plan Cartesian(const Eigen::VectorXd& q0, double duration_s, double accel_fraction, double length_m,
                 PoseAt pose_at) const;
  // joints of each tool pose by Newton steps from the previous; throws where one fails
  Plan SolvePath(const Eigen::VectorXd& q0, const std::vector<Frame>& goals, const std::vector<double>& speeds) const;
  Eigen::VectorXd Solve(const Eigen::VectorXd& q_start, const Frame& goal_W, int* iterations, double* pos_err,
                        double* rot_err) const;
  // the message of a pose the IK did not reach: the final residual (m, deg), stated as
  // such, and the singularity the IK ended near, if any
  std::string Unreached(const Eigen::VectorXd& q_end, double pos_err, double rot_err, int iterations) const;
  // the failure of path sample i of n (IK at q_bad from q_good): the target's own reach
  // first (goal), then a singularity near q_good, else `what`
  std::string PathFailure(int i, int n, const Eigen::VectorXd& q_good, const Frame& goal,
                          const std::string& what) const;

  control::RobotModel* model_;
  double period_s_;
  Frame tool_;
  JointRateLimits rates_;
  Eigen::VectorXd zero_;  // joint velocities of every evaluation (kinematics only)
};

/// The distance (m) by which a path (MotionPlanner::Path) passes a corner it
/// rounds with an arc starting `l` before it, the lines turning by `theta`
/// rad: R / cos(θ/2) - R with R = l / tan(θ/2), which is l·tan(θ/4) (a right
/// angle: 0.414·l).
double PathCornerGap(double l, double theta);

/// Duration (s) and acceleration fraction of a trapezoidal speed profile over
/// distance `d` with peak speed v and acceleration a (a triangle when d <
/// v²/a): T = d/v + v/a, or 2·sqrt(d/a).
void TrapezoidTiming(double d, double v, double a, double* duration_s, double* accel_fraction);

}  // namespace vlab::task
