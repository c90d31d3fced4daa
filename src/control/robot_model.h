// Robot-model quantities of one kinematic chain of a MuJoCo model.
//
// A chain is the ordered list of hinge and slide joints on the path from a base
// body (exclusive) to the body that carries a tip site. MuJoCo computes every
// quantity (mj_kinematics, mj_comPos, mj_comVel, mj_crb, mj_fullM, mj_jacSite,
// mj_rne); this class evaluates them on a scratch mjData of its own, so it never
// disturbs the simulation's state, and presents them per chain as Eigen types.
//
// Units and frames:
//   q    joint positions of the chain, rad (hinge) or m (slide), chain order
//   qd   joint velocities, rad/s or m/s
//   p    tip-site position in the world frame, m
//   R    tip-site orientation, rotation matrix world <- site
//   J    6×n geometric Jacobian of the tip site in the world frame: rows 0-2 map
//        qd to the site's linear velocity (m/s), rows 3-5 to its angular velocity
//        (rad/s), both expressed in world coordinates
//   H    n×n joint-space inertia matrix (kg·m² / kg), including joint armature
//   h    n-vector of bias forces C(q,qd)·qd + g(q), N·m or N
//   g    n-vector of gravity forces g(q), N·m or N
// The equation of motion of the chain, with every other joint of the model held
// still, reads H(q)·qdd + h(q,qd) = tau.
//
// Threading: an instance owns its scratch data and is not thread-safe; use one
// instance per thread.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace vlab::control {

/// Position (m) and orientation of a frame in the world.
struct Pose {
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R_W = Eigen::Matrix3d::Identity();
};

class RobotModel {
 public:
  struct Config {
    /// Body the chain starts from (its joints are not part of the chain).
    std::string base_body = "world";
    /// Site at the chain's tip; the chain ends at the body that carries it.
    std::string tip_site;
  };

  /// Builds the chain. `model` must outlive the instance. Throws
  /// std::invalid_argument naming the missing body or site, or saying why the
  /// path is not a chain (a free or ball joint on it, base not an ancestor).
  static std::unique_ptr<RobotModel> Create(const mjModel* model, const Config& config);

  ~RobotModel();
  RobotModel(const RobotModel&) = delete;
  RobotModel& operator=(const RobotModel&) = delete;

  /// Number of joints (= degrees of freedom) in the chain.
  int dof() const { return static_cast<int>(joint_ids_.size()); }
  /// MuJoCo joint ids, base to tip.
  const std::vector<int>& joint_ids() const { return joint_ids_; }
  /// Addresses into qpos of the chain's joints.
  const std::vector<int>& qpos_addresses() const { return qpos_addresses_; }
  /// Addresses into qvel / qfrc of the chain's joints.
  const std::vector<int>& dof_addresses() const { return dof_addresses_; }
  /// Joint names, base to tip.
  const std::vector<std::string>& joint_names() const { return joint_names_; }
  /// Joint position limits (rad or m); -inf / +inf for unlimited joints.
  const Eigen::VectorXd& lower_limits() const { return lower_; }
  const Eigen::VectorXd& upper_limits() const { return upper_; }
  int tip_site_id() const { return site_id_; }

  /// Extracts the chain's joint positions / velocities from a full state.
  Eigen::VectorXd ChainPositions(const mjData& data) const;
  Eigen::VectorXd ChainVelocities(const mjData& data) const;

  /// Sets the evaluation state: the whole model's qpos/qvel copied from `data`
  /// (so joints outside the chain, e.g. a mobile base, are respected), then the
  /// kinematics recomputed (inertia and velocity terms on first use).
  void SetState(const mjData& data);
  /// Sets the evaluation state from chain coordinates; joints outside the chain
  /// keep the positions of the last SetState(data) (qpos0 initially) and zero
  /// velocity. Sizes must equal dof().
  void SetState(const Eigen::VectorXd& q, const Eigen::VectorXd& qd);

  /// Quantities at the current evaluation state (see the file comment).
  Pose TipPose() const;
  Eigen::MatrixXd Jacobian() const;
  Eigen::MatrixXd MassMatrix() const;
  Eigen::VectorXd Bias() const;
  Eigen::VectorXd Gravity() const;
  /// The same, written into `out` (resized to dof(); no allocation when it
  /// already has that size): for control loops.
  void Bias(Eigen::VectorXd* out) const;
  void Gravity(Eigen::VectorXd* out) const;

  /// Scratch data holding the evaluation state (read-only view).
  const mjData& data() const { return *data_; }
  const mjModel& model() const { return *model_; }

 private:
  RobotModel(const mjModel* model, mjData* data);
  void Recompute();
  void EnsureInertia() const;   // mj_crb once per state
  void EnsureVelocity() const;  // mj_comVel once per state

  const mjModel* model_;
  mjData* data_;
  int site_id_ = -1;
  std::vector<int> joint_ids_;
  std::vector<int> qpos_addresses_;
  std::vector<int> dof_addresses_;
  std::vector<std::string> joint_names_;
  Eigen::VectorXd lower_, upper_;
  mutable bool inertia_ready_ = false;
  mutable bool velocity_ready_ = false;
  // scratch buffers sized at creation
  mutable std::vector<mjtNum> full_m_;
  mutable std::vector<mjtNum> rne_;
  mutable std::vector<mjtNum> jacp_, jacr_;
};

}  // namespace vlab::control
