// The joint torques of an arm chain as a linear function of its dynamic
// parameters: tau = Y(q, qd, qdd) · pi (the rigid-body dynamics are linear in
// each link's 10 inertial parameters; Atkeson, An and Hollerbach 1986; Khalil
// and Dombre, "Modeling, Identification and Control of Robots", ch. 12).
//
// Chain: the named joints of a MuJoCo model (an arm device's joints), base to
// tip, each a hinge or slide and the only joint of its body, each body below
// the previous joint's. The body the first joint's body hangs from is taken at
// rest (a mobile base is held). Link i is joint i's body with every body below
// it that no later chain joint moves; a body there with joints of its own (a
// gripper's fingers) is held at the reference pose (Create), lumped in rigidly.
//
// Parameters pi (SI units), in this order:
//   per link i, in the frame of joint i's body, about its origin:
//     m, m·cx, m·cy, m·cz (kg, kg m), Ixx, Iyy, Izz, Ixy, Ixz, Iyz (kg m²)
//   per joint j: damping (N m s/rad, N s/m: tau = d·qd), friction loss (N m or
//   N: tau = f·sign(qd), Coulomb), armature (kg m² or kg: tau = a·qdd)
// so Y has n rows and 13·n columns. MuJoCo's damping and armature enter its
// dynamics exactly so; its friction loss is a soft constraint, which the
// Coulomb column models at speed (not at rest).
//
// Gravity is the model's (opt.gravity). Evaluation allocates nothing once the
// output matrix has its size; an instance owns scratch mjData and is not
// thread-safe (one per thread).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>
#include <Eigen/Core>

namespace vlab::control {

class DynamicsRegressor {
 public:
  /// Inertial parameters per link, then the three joint parameters.
  static constexpr int kLinkParameters = 10;
  static constexpr int kJointParameters = 3;

  /// Builds the regressor of `joints` (MJCF joint names, base to tip) of
  /// `model`, which must outlive it. `reference_qpos` (nq values; empty:
  /// qpos0) holds the joints outside the chain. Throws std::invalid_argument
  /// naming the joint that is missing, not a hinge or slide, shares its body,
  /// or is not below the previous one.
  static std::unique_ptr<DynamicsRegressor> Create(const mjModel* model, const std::vector<std::string>& joints,
                                                   const std::vector<double>& reference_qpos = {});
  ~DynamicsRegressor();
  DynamicsRegressor(const DynamicsRegressor&) = delete;
  DynamicsRegressor& operator=(const DynamicsRegressor&) = delete;

  int dof() const { return static_cast<int>(joints_.size()); }
  /// Columns of Y: 13·dof().
  int parameters() const { return dof() * (kLinkParameters + kJointParameters); }
  /// The parameters' names: BODY.m, BODY.mx, BODY.my, BODY.mz, BODY.Ixx, ...,
  /// BODY.Iyz per link (BODY its first body), then JOINT.damping per joint,
  /// JOINT.frictionloss per joint, JOINT.armature per joint.
  const std::vector<std::string>& names() const { return names_; }
  /// Joint names, base to tip; their qpos addresses.
  const std::vector<std::string>& joint_names() const { return joint_names_; }
  const std::vector<int>& qpos_addresses() const { return qpos_adr_; }
  /// Joint ranges (rad or m; -inf / +inf when unlimited).
  const Eigen::VectorXd& lower_limits() const { return lower_; }
  const Eigen::VectorXd& upper_limits() const { return upper_; }

  /// The parameters of `model` (the one given at Create, or a copy of it with
  /// other masses, inertias, damping...), with the held joints at the
  /// reference pose: what Y multiplies to give its torques.
  Eigen::VectorXd Parameters(const mjModel& model) const;

  /// Y at chain positions q, velocities qd, accelerations qdd (rad, rad/s,
  /// rad/s²), written into `Y` (resized to dof() x parameters()).
  void Compute(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd, Eigen::MatrixXd* Y);

 private:
  struct Joint {
    int id = -1, body = -1, qpos_adr = -1, dof_adr = -1;
    bool hinge = true;
  };
  DynamicsRegressor(const mjModel* model, mjData* data);

  const mjModel* model_;
  mjData* data_;
  std::vector<double> reference_qpos_;
  std::vector<Joint> joints_;
  std::vector<int> link_of_body_;  // chain link of each body (-1: none)
  std::vector<std::string> names_, joint_names_;
  std::vector<int> qpos_adr_;
  Eigen::VectorXd lower_, upper_;
};

/// The base parameters of a regressor (Gautier 1991's numerical method): the
/// columns of Y that the data can tell apart. QR with column pivoting of a Y
/// stacked over many samples; columns past the numerical rank are zero or
/// combinations of the kept ones: pi_base = pi[independent] + K · pi[dependent].
struct BaseParameters {
  std::vector<int> independent;  ///< kept columns, in Y's order
  std::vector<int> dependent;    ///< dropped columns, in Y's order
  Eigen::MatrixXd K;             ///< independent.size() x dependent.size()
};

/// Base parameters of `W` (samples·dof x parameters): the rank is the number
/// of pivots larger than `relative_tolerance` times the largest.
BaseParameters FindBaseParameters(const Eigen::MatrixXd& W, double relative_tolerance = 1e-9);

/// 2-norm condition number of A (largest over smallest singular value; inf
/// when the smallest is 0).
double ConditionNumber(const Eigen::MatrixXd& A);

}  // namespace vlab::control
