#include "lab/run/lab_controller.h"

#include <algorithm>
#include <cmath>

#include "control/joint_pd.h"
#include "control/robot_model.h"
#include "control/task_space.h"
#include "control/trajectory.h"
#include "core/core_errors.h"

namespace vlab::lab {

namespace {

using control::RobotModel;

[[noreturn]] void Fail(const ControllerConfig& c, const std::string& what) {
  throw InputError(c.where + ": controller: " + what);
}

control::TimeScaling Timing(const ControllerConfig& c) {
  control::TimeScaling t;
  t.type = c.timing;
  return t;
}

// The chain the controller works on, and where each chain joint sits in the
// arm device's joint list.
struct BoundChain {
  std::unique_ptr<RobotModel> model;
  std::vector<int> arm_index;  // chain joint i is arm joint arm_index[i]
  int arm_dof = 0;
  Eigen::VectorXd q, qd;  // chain state of the current period (sized once)
};

BoundChain BindChain(const mjModel* m, const ControllerConfig& c, const std::vector<std::string>& joints) {
  BoundChain b;
  try {
    b.model = RobotModel::Create(m, {c.base_body, c.tip_site});
  } catch (const std::invalid_argument& e) {
    Fail(c, e.what());
  }
  for (const auto& name : b.model->joint_names()) {
    const auto it = std::find(joints.begin(), joints.end(), name);
    if (it == joints.end()) Fail(c, "chain joint '" + name + "' is not a joint of arm '" + c.arm + "'");
    b.arm_index.push_back(static_cast<int>(it - joints.begin()));
  }
  b.arm_dof = static_cast<int>(joints.size());
  b.q.setZero(b.model->dof());
  b.qd.setZero(b.model->dof());
  return b;
}

// the chain's joints out of the arm's state (no allocation)
void ToChain(BoundChain& b, const bridge::ArmState& state) {
  for (std::size_t i = 0; i < b.arm_index.size(); ++i) {
    b.q[i] = state.q[b.arm_index[i]];
    b.qd[i] = state.qd[b.arm_index[i]];
  }
}

void ToArm(const BoundChain& b, const Eigen::VectorXd& chain_values, Eigen::VectorXd* arm_values) {
  arm_values->setZero(b.arm_dof);
  for (std::size_t i = 0; i < b.arm_index.size(); ++i) (*arm_values)[b.arm_index[i]] = chain_values[i];
}

// ---------------------------------------------------------------------------
// task_space: Cartesian path, resolved-rate control, velocity commands
class TaskSpaceBuiltin final : public Controller {
 public:
  TaskSpaceBuiltin(const mjModel* m, const ControllerConfig& c, const std::vector<std::string>& joints,
                   const bridge::ArmState& initial)
      : chain_(BindChain(m, c, joints)), start_s_(c.start_s) {
    control::TaskSpaceConfig tc;
    tc.k_position = c.k_position;
    tc.k_orientation = c.k_orientation;
    tc.k_null = c.k_null;
    tc.damping = c.damping;
    RobotModel& model = *chain_.model;
    ToChain(chain_, initial);
    model.SetState(chain_.q, Eigen::VectorXd::Zero(chain_.q.size()));
    tc.q_rest = chain_.q;  // the null-space term keeps the arm near its start posture
    control::CartesianTrajectoryConfig path;
    path.waypoints.push_back(model.TipPose());
    for (const auto& w : c.cartesian) {
      control::Pose pose;
      pose.p_W = w.position_W;
      pose.R_W = w.orientation_W.toRotationMatrix();
      path.waypoints.push_back(pose);
      path.segments.push_back({w.duration_s, Timing(c)});
    }
    try {
      controller_ = control::TaskSpaceController::Create(tc, model);
      path_ = control::CartesianTrajectory::Create(path);
    } catch (const std::invalid_argument& e) {
      Fail(c, e.what());
    }
  }

  std::vector<std::string> Columns() const override {
    return {"controller.position_error",
            "controller.orientation_error",
            "controller.p_des.x",
            "controller.p_des.y",
            "controller.p_des.z",
            "controller.p.x",
            "controller.p.y",
            "controller.p.z"};
  }

  void Update(double t, const bridge::ArmState& state, bridge::ArmCommand* command, double* columns) override {
    RobotModel& model = *chain_.model;
    ToChain(chain_, state);
    model.SetState(chain_.q, chain_.qd);
    const control::CartesianSample desired = path_->Evaluate(std::max(0.0, t - start_s_));
    control::TaskSpaceTarget target;
    target.pose = desired.pose;
    target.v_W = desired.v_W;
    target.w_W = desired.w_W;
    const control::TaskSpaceOutput& out = controller_->Update(model, chain_.q, target);
    command->mode = bridge::ArmMode::kVelocity;
    ToArm(chain_, out.qd_cmd, &command->value);
    const control::Pose tip = model.TipPose();
    columns[0] = out.position_error_m;
    columns[1] = out.orientation_error_rad;
    for (int i = 0; i < 3; ++i) {
      columns[2 + i] = desired.pose.p_W[i];
      columns[5 + i] = tip.p_W[i];
    }
  }

 private:
  BoundChain chain_;
  double start_s_;
  std::unique_ptr<control::TaskSpaceController> controller_;
  std::unique_ptr<control::CartesianTrajectory> path_;
};

// ---------------------------------------------------------------------------
// joint_pd: joint path, PD + gravity compensation, torque commands
class JointPdBuiltin final : public Controller {
 public:
  JointPdBuiltin(const mjModel* m, const ControllerConfig& c, const std::vector<std::string>& joints,
                 const bridge::ArmState& initial)
      : chain_(BindChain(m, c, joints)), start_s_(c.start_s) {
    RobotModel& model = *chain_.model;
    const int n = model.dof();
    ToChain(chain_, initial);
    const Eigen::VectorXd q0 = chain_.q;
    model.SetState(q0, Eigen::VectorXd::Zero(n));
    zero_.setZero(n);
    // gains: given, or from the bandwidth rule on the start pose's inertia
    const Eigen::VectorXd inertia = model.MassMatrix().diagonal();
    const double w = 2.0 * M_PI * c.pd_bandwidth_hz;
    gains_.kp =
        c.kp.empty() ? Eigen::VectorXd(inertia * w * w) : Eigen::Map<const Eigen::VectorXd>(c.kp.data(), c.kp.size());
    gains_.kd =
        c.kd.empty() ? Eigen::VectorXd(2.0 * w * inertia) : Eigen::Map<const Eigen::VectorXd>(c.kd.data(), c.kd.size());
    if (gains_.kp.size() != n || gains_.kd.size() != n) {
      Fail(c, "gains.kp and gains.kd need one value per chain joint (" + std::to_string(n) + ")");
    }
    // torque limits of the motors driving the chain's joints (commands are clipped to them)
    tau_max_ = Eigen::VectorXd::Constant(n, INFINITY);
    for (int a = 0; a < m->nu; ++a) {
      for (int i = 0; i < n; ++i) {
        if (m->actuator_trntype[a] == mjTRN_JOINT && m->actuator_trnid[2 * a] == model.joint_ids()[i] &&
            m->actuator_ctrllimited[a]) {
          tau_max_[i] = std::min(std::abs(m->actuator_ctrlrange[2 * a]), std::abs(m->actuator_ctrlrange[2 * a + 1]));
        }
      }
    }
    control::JointTrajectoryConfig path;
    path.waypoints.push_back(q0);
    for (std::size_t i = 0; i < c.joint.size(); ++i) {
      const auto& wp = c.joint[i];
      if (static_cast<int>(wp.q.size()) != n) {
        Fail(c, "waypoints[" + std::to_string(i) + "].q needs " + std::to_string(n) + " values");
      }
      path.waypoints.push_back(Eigen::Map<const Eigen::VectorXd>(wp.q.data(), n));
      path.segments.push_back({wp.duration_s, Timing(c)});
    }
    try {
      path_ = control::JointTrajectory::Create(path);
    } catch (const std::invalid_argument& e) {
      Fail(c, e.what());
    }
  }

  std::vector<std::string> Columns() const override { return {"controller.joint_error"}; }

  void Update(double t, const bridge::ArmState& state, bridge::ArmCommand* command, double* columns) override {
    RobotModel& model = *chain_.model;
    ToChain(chain_, state);
    model.SetState(chain_.q, zero_);
    path_->Evaluate(std::max(0.0, t - start_s_), &desired_);
    model.Gravity(&g_);
    control::JointPdGravityTorque(gains_, chain_.q, chain_.qd, desired_.q, desired_.qd, g_, &tau_);
    tau_ = tau_.cwiseMax(-tau_max_).cwiseMin(tau_max_);
    command->mode = bridge::ArmMode::kTorque;
    ToArm(chain_, tau_, &command->value);
    columns[0] = (desired_.q - chain_.q).cwiseAbs().maxCoeff();
  }

 private:
  BoundChain chain_;
  double start_s_;
  control::JointPdGains gains_;
  Eigen::VectorXd tau_max_;
  std::unique_ptr<control::JointTrajectory> path_;
  // per-period buffers, sized once
  control::JointSample desired_;
  Eigen::VectorXd zero_, g_, tau_;
};

}  // namespace

std::unique_ptr<Controller> MakeController(const mjModel* m, const ControllerConfig& c,
                                           const std::vector<std::string>& joints, const bridge::ArmState& initial) {
  if (c.type == ControllerType::kTaskSpace) return std::make_unique<TaskSpaceBuiltin>(m, c, joints, initial);
  if (c.type == ControllerType::kJointPd) return std::make_unique<JointPdBuiltin>(m, c, joints, initial);
  Fail(c, std::string("no built-in controller of type '") + ControllerTypeName(c.type) + "'");
}

}  // namespace vlab::lab
