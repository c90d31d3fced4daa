// SimArm's feed-forward from its own model (servo.feedforward: model) on the
// PA10: a load the servo does not know deflects each joint by the closed form
// K^-1 tau_load (K = diag(kp), tau_load = J^T F from the joint axes); the world's
// feed-forward hides it; a declared payload takes the deflection away, a wrong
// one gives the predicted error.
#include "lab/devices/device_arm.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "arm_servo_forces.h"
#include "mujoco_fixture.h"

namespace vlab::lab::arm_servo_test {
namespace {

using Feedforward = ServoConfig::Feedforward;

constexpr double kPeriod = 0.002;
const std::vector<std::string> kJoints = {"S1", "S2", "S3", "E1", "E2", "W1", "W2"};
// what pa10.xml welds beyond the flange: JR3 (two halves) and the pointer
const std::vector<std::string> kTool = {"jr3_body", "jr3_tool_side", "tool_body"};
// tilted poses, leaning away from the table (no contact)
const std::vector<std::vector<double>> kPoses = {
    {0, -0.5, 0, -1.0, 0, -0.8, 0},
    {0.4, -0.3, 0.6, -1.4, -0.7, 1.1, 0.5},
    {-1.2, 0.6, -0.4, 1.0, 1.0, -1.3, -0.6},
};

class ArmServoTest : public test::MujocoTest {
 protected:
  void SetUp() override {
    model_ = LoadModel("scenes/pa10.xml");
    for (const auto& j : kJoints) joints_.push_back(mj_name2id(model_, mjOBJ_JOINT, j.c_str()));
  }
  // a fresh arm holding `pose`, started as the lab starts it
  void Start(const std::vector<double>& pose, Feedforward feedforward, const Payload& payload = {},
             const std::vector<std::string>& bodies = {}) {
    DeviceConfig c;
    c.name = "pa10";
    c.where = "arm.yaml:9";
    auto& p = c.EditParams<ArmParams>();
    p.joints = p.actuators = kJoints;
    p.initial = pose;
    p.servo.feedforward = feedforward;
    p.servo.bodies = bodies;
    p.payload = payload;
    arm_ = SimArm::Create({model_, kPeriod, 1, "pa10.xml"}, c);
    data_ = MakeData(model_);
    arm_->SetInitialState(*data_);
    mj_forward(model_, data_);
    arm_->Start(*data_);
    pose_ = Eigen::Map<const Eigen::VectorXd>(pose.data(), 7);
  }
  // holds for `seconds`, then returns the deflection q_ref - q (rad)
  Eigen::VectorXd Hold(double seconds) {
    for (long k = 0; k < std::lround(seconds / model_->opt.timestep); ++k) {
      mj_step1(model_, data_);
      arm_->Actuate(*data_, model_->opt.timestep);
      mj_step2(model_, data_);
    }
    EXPECT_EQ(data_->ncon, 0) << "the arm touches something";
    mj_forward(model_, data_);
    Eigen::VectorXd q(7);
    for (int i = 0; i < 7; ++i) q[i] = data_->qpos[model_->jnt_qposadr[joints_[i]]];
    return pose_ - q;
  }
  // K^-1 tau: the deflection a bias torque the servo does not feed forward gives
  Eigen::VectorXd Deflection(const std::vector<double>& tau) const {
    return Eigen::Map<const Eigen::VectorXd>(tau.data(), 7).cwiseQuotient(arm_->kp());
  }
  // the tool as a payload: mass, centre of mass and inertia in the flange body's frame
  Payload ToolPayload() const {
    const int flange = mj_name2id(model_, mjOBJ_BODY, "pa10_link7");
    using Rotation = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
    const Rotation r_wf = Eigen::Map<const Rotation>(data_->xmat + 9 * flange);
    const Eigen::Vector3d p_wf = Eigen::Map<const Eigen::Vector3d>(data_->xpos + 3 * flange);
    Payload p;
    Eigen::Vector3d moment = Eigen::Vector3d::Zero();
    for (const auto& name : kTool) {
      const int b = mj_name2id(model_, mjOBJ_BODY, name.c_str());
      p.mass_kg += model_->body_mass[b];
      moment +=
          model_->body_mass[b] * r_wf.transpose() * (Eigen::Map<const Eigen::Vector3d>(data_->xipos + 3 * b) - p_wf);
    }
    p.com_m = moment / p.mass_kg;
    Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
    for (const auto& name : kTool) {
      const int b = mj_name2id(model_, mjOBJ_BODY, name.c_str());
      const Rotation r_fb = r_wf.transpose() * Eigen::Map<const Rotation>(data_->ximat + 9 * b);
      const Eigen::Vector3d diag = Eigen::Map<const Eigen::Vector3d>(model_->body_inertia + 3 * b);
      const Eigen::Vector3d r =
          r_wf.transpose() * (Eigen::Map<const Eigen::Vector3d>(data_->xipos + 3 * b) - p_wf) - p.com_m;
      inertia += r_fb * diag.asDiagonal() * r_fb.transpose() +
                 model_->body_mass[b] * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
    }
    p.inertia_kgm2 = {inertia(0, 0), inertia(1, 1), inertia(2, 2), inertia(0, 1), inertia(0, 2), inertia(1, 2)};
    return p;
  }

  mjModel* model_ = nullptr;
  mjData* data_ = nullptr;
  std::vector<int> joints_;
  std::unique_ptr<SimArm> arm_;
  Eigen::VectorXd pose_;
};

// |a - b| within 2 % of |b| (largest joint), and b not negligible
void ExpectClose(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const std::string& what) {
  EXPECT_GT(b.cwiseAbs().maxCoeff(), 1e-3) << what << ": the load must deflect the arm";
  EXPECT_LE((a - b).cwiseAbs().maxCoeff(), 0.02 * b.cwiseAbs().maxCoeff())
      << what << "\n deflection " << a.transpose() << "\n closed form " << b.transpose();
}

TEST_F(ArmServoTest, AnUnknownWeldedToolDeflectsByTheClosedForm) {
  Start(kPoses[0], Feedforward::kModel);
  const Eigen::VectorXd deflection = Hold(1.5);
  ExpectClose(deflection, Deflection(WeightBias(model_, data_, joints_, kTool)), "model feed-forward");
  // the world's feed-forward knows the tool: no deflection at all
  Start(kPoses[0], Feedforward::kWorld);
  EXPECT_LT(Hold(1.5).cwiseAbs().maxCoeff(), 1e-9);
}

TEST_F(ArmServoTest, AnExternalPushDeflectsByJTransposeF) {
  // the servo knows the tool (servo.bodies): only the push is unknown
  Start(kPoses[1], Feedforward::kModel, {}, kTool);
  const int tool = mj_name2id(model_, mjOBJ_BODY, "tool_body");
  const double push_N[3] = {3.0, -2.0, 4.0};
  for (int k = 0; k < 3; ++k) data_->xfrc_applied[6 * tool + k] = push_N[k];
  const Eigen::VectorXd deflection = Hold(1.5);
  std::vector<double> tau = JointForces(model_, data_, joints_, tool, push_N);
  for (double& t : tau) t = -t;  // the push helps the servo by J^T F: the joints give way along it
  ExpectClose(deflection, Deflection(tau), "push");
}

TEST_F(ArmServoTest, KnowingEveryBodyTheGainsAreTheWorlds) {
  Start(kPoses[2], Feedforward::kWorld);
  const Eigen::VectorXd kp_world = arm_->kp();
  Start(kPoses[2], Feedforward::kModel, {}, kTool);
  EXPECT_LT((arm_->kp() - kp_world).cwiseAbs().maxCoeff(), 1e-9 * kp_world.maxCoeff());
  // without the tool W1's inertia (the tool swings about it), and so its gain, is smaller
  Start(kPoses[2], Feedforward::kModel);
  EXPECT_LT(arm_->kp()[5], 0.9 * kp_world[5]);
}

TEST_F(ArmServoTest, PayloadStaticErrorAtThreePoses) {
  for (std::size_t pose = 0; pose < kPoses.size(); ++pose) {
    const std::string where = "pose " + std::to_string(pose);
    Start(kPoses[pose], Feedforward::kModel);
    const Payload tool = ToolPayload();
    // no payload: the tool's weight is unknown
    const Eigen::VectorXd none = Hold(1.5);
    ExpectClose(none, Deflection(WeightBias(model_, data_, joints_, kTool)), where + ", no payload");
    // the right payload: no error
    Start(kPoses[pose], Feedforward::kModel, tool);
    EXPECT_LT(Hold(1.5).cwiseAbs().maxCoeff(), 1e-4 * none.cwiseAbs().maxCoeff()) << where << ", right payload";
    // twice the mass: the servo lifts one tool too many, the error reverses
    Payload twice = tool;
    twice.mass_kg *= 2;
    Start(kPoses[pose], Feedforward::kModel, twice);
    const Eigen::VectorXd over = Hold(1.5);
    std::vector<double> tau = WeightBias(model_, data_, joints_, kTool);
    for (double& t : tau) t = -t;
    ExpectClose(over, Deflection(tau), where + ", twice the mass");
  }
}

TEST_F(ArmServoTest, SetPayloadTakesEffectAtTheNextStep) {
  Start(kPoses[1], Feedforward::kModel);
  const Eigen::VectorXd none = Hold(1.0);
  ASSERT_GT(none.cwiseAbs().maxCoeff(), 1e-3);
  Payload bad = ToolPayload();
  bad.mass_kg = -1;
  std::string why;
  EXPECT_FALSE(arm_->SetPayload(bad, &why));
  EXPECT_EQ(why, "mass: must be a finite number >= 0 kg");
  ASSERT_TRUE(arm_->SetPayload(ToolPayload()));
  EXPECT_DOUBLE_EQ(arm_->payload().mass_kg, ToolPayload().mass_kg);
  EXPECT_LT(Hold(1.5).cwiseAbs().maxCoeff(), 1e-4 * none.cwiseAbs().maxCoeff());
}

}  // namespace
}  // namespace vlab::lab::arm_servo_test
