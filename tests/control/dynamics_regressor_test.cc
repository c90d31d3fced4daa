#include "control/dynamics_regressor.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "mujoco_fixture.h"

namespace vlab::control {
namespace {

const std::vector<std::string> kPa10Joints = {"S1", "S2", "S3", "E1", "E2", "W1", "W2"};

// A chain with what the PA10 lacks: a slide joint, a hinge whose anchor is off its body's
// origin and whose axis is oblique, a body welded below a link, a body with a joint of its
// own (held), and a free body before the chain (other qpos addresses).
constexpr char kMixedChainXml[] = R"(
<mujoco model="mixed">
  <compiler angle="radian"/>
  <option gravity="0.3 -0.2 -9.81"/>
  <default><geom contype="0" conaffinity="0"/><joint limited="true"/></default>
  <worldbody>
    <body name="box" pos="1 1 0.5"><freejoint name="box_free"/><geom type="box" size="0.05 0.05 0.05"/></body>
    <body name="base" pos="0 0 0.1" euler="0.1 0.2 0.3">
      <geom type="cylinder" size="0.06 0.05"/>
      <body name="l1" pos="0 0 0.05">
        <joint name="j1" axis="0 0 1" range="-3 3"/>
        <inertial pos="0.02 0.01 0.1" mass="2" diaginertia="0.03 0.02 0.01" euler="0.2 0.1 0"/>
        <body name="l2" pos="0.05 0 0.2" euler="0 0.4 0">
          <joint name="j2" type="slide" axis="1 0 0" range="-0.3 0.3"/>
          <inertial pos="0.1 0 0.02" mass="1.5" diaginertia="0.01 0.02 0.015"/>
          <body name="l3" pos="0.2 0 0">
            <joint name="j3" axis="0.3 1 0.2" pos="0.01 -0.02 0.03" range="-2 2"/>
            <inertial pos="0 0.03 0.15" mass="1.2" diaginertia="0.02 0.025 0.005" euler="0.5 0 0.3"/>
            <body name="welded" pos="0 0 0.3" euler="0.3 0 0">
              <inertial pos="0.01 0 0.02" mass="0.4" diaginertia="0.001 0.002 0.0015"/>
            </body>
            <body name="finger" pos="0 0.05 0.3">
              <joint name="finger" type="slide" axis="0 1 0" range="-0.02 0.02"/>
              <inertial pos="0 0.01 0.01" mass="0.1" diaginertia="0.0001 0.0001 0.0001"/>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
)";

class DynamicsRegressorTest : public vlab::test::MujocoTest {
 protected:
  // torques of the chain by MuJoCo's own inverse dynamics (mj_rne with accelerations): the
  // rest of the model at the reference pose, at rest
  Eigen::VectorXd Rne(const mjModel* m, const DynamicsRegressor& r, const std::vector<double>& qpos,
                      const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd) {
    mjData* d = MakeData(m);
    std::copy(qpos.begin(), qpos.end(), d->qpos);
    for (int i = 0; i < r.dof(); ++i) {
      const int joint = mj_name2id(m, mjOBJ_JOINT, r.joint_names()[i].c_str());
      d->qpos[m->jnt_qposadr[joint]] = q[i];
      d->qvel[m->jnt_dofadr[joint]] = qd[i];
      d->qacc[m->jnt_dofadr[joint]] = qdd[i];
    }
    mj_kinematics(m, d);
    mj_comPos(m, d);
    mj_comVel(m, d);
    std::vector<mjtNum> tau(m->nv);
    mj_rne(m, d, 1, tau.data());
    Eigen::VectorXd out(r.dof());
    for (int i = 0; i < r.dof(); ++i) {
      out[i] = tau[m->jnt_dofadr[mj_name2id(m, mjOBJ_JOINT, r.joint_names()[i].c_str())]];
    }
    return out;
  }

  // a random state within the joints' ranges
  void RandomState(std::mt19937_64* rng, const DynamicsRegressor& r, Eigen::VectorXd* q, Eigen::VectorXd* qd,
                   Eigen::VectorXd* qdd) {
    std::uniform_real_distribution<double> u(-1, 1);
    const int n = r.dof();
    q->resize(n), qd->resize(n), qdd->resize(n);
    for (int i = 0; i < n; ++i) {
      (*q)[i] = 0.5 * (r.lower_limits()[i] + r.upper_limits()[i]) +
                0.45 * (r.upper_limits()[i] - r.lower_limits()[i]) * u(*rng);
      (*qd)[i] = 2 * u(*rng);
      (*qdd)[i] = 5 * u(*rng);
    }
  }

  // Y·pi against mj_rne at 20 random states; returns the worst relative difference
  double WorstAgainstRne(const mjModel* m, DynamicsRegressor& r, const std::vector<double>& qpos) {
    std::mt19937_64 rng(11);
    Eigen::VectorXd pi = r.Parameters(*m);
    // the joint parameters are outside mj_rne
    pi.tail(DynamicsRegressor::kJointParameters * r.dof()).setZero();
    Eigen::MatrixXd Y;
    Eigen::VectorXd q, qd, qdd;
    double worst = 0;
    for (int k = 0; k < 20; ++k) {
      RandomState(&rng, r, &q, &qd, &qdd);
      r.Compute(q, qd, qdd, &Y);
      const Eigen::VectorXd rne = Rne(m, r, qpos, q, qd, qdd);
      worst = std::max(worst, (Y * pi - rne).cwiseAbs().maxCoeff() / std::max(1.0, rne.cwiseAbs().maxCoeff()));
    }
    return worst;
  }
};

TEST_F(DynamicsRegressorTest, Pa10NominalParametersGiveMujocosInverseDynamics) {
  const mjModel* m = LoadModel("scenes/pa10.xml");
  auto r = DynamicsRegressor::Create(m, kPa10Joints);
  EXPECT_EQ(r->parameters(), 91);
  EXPECT_EQ(r->names()[0], "pa10_link1.m");
  EXPECT_EQ(r->names()[69], "pa10_link7.Iyz");
  EXPECT_EQ(r->names()[70], "S1.damping");
  EXPECT_EQ(r->names()[90], "W2.armature");
  const Eigen::VectorXd pi = r->Parameters(*m);
  // link 7 carries the flange, the JR3 and the tool (welded): their masses summed
  double mass7 = 0;
  for (const char* body : {"pa10_link7", "jr3_body", "jr3_tool_side", "tool_body"}) {
    mass7 += m->body_mass[mj_name2id(m, mjOBJ_BODY, body)];
  }
  EXPECT_NEAR(pi[60], mass7, 1e-12);
  EXPECT_DOUBLE_EQ(pi[90], 0.00575);  // W2's armature (mjcf/pa10)
  EXPECT_LT(WorstAgainstRne(m, *r, std::vector<double>(m->qpos0, m->qpos0 + m->nq)), 1e-9);
}

TEST_F(DynamicsRegressorTest, EveryInertialColumnIsRightOnPerturbedModels) {
  // tau is linear in pi: Y, computed once per state, must give mj_rne of any model of the
  // same kinematics; ten random models (masses, centres, inertias and their axes) span the
  // ten parameters of each link
  const mjModel* nominal = LoadModel("scenes/pa10.xml");
  auto r = DynamicsRegressor::Create(nominal, kPa10Joints);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 10; ++trial) {
    mjModel* m = mj_copyModel(nullptr, nominal);
    for (int b = 1; b < m->nbody; ++b) {
      m->body_mass[b] *= 1 + 0.5 * u(rng);
      for (int k = 0; k < 3; ++k) m->body_ipos[3 * b + k] += 0.05 * u(rng);
      for (int k = 0; k < 3; ++k) m->body_inertia[3 * b + k] = 0.01 + 0.05 * (1 + u(rng));
      Eigen::Quaterniond qt(1, 0.5 * u(rng), 0.5 * u(rng), 0.5 * u(rng));
      qt.normalize();
      m->body_iquat[4 * b] = qt.w(), m->body_iquat[4 * b + 1] = qt.x();
      m->body_iquat[4 * b + 2] = qt.y(), m->body_iquat[4 * b + 3] = qt.z();
    }
    EXPECT_LT(WorstAgainstRne(m, *r, std::vector<double>(m->qpos0, m->qpos0 + m->nq)), 1e-9) << "trial " << trial;
    mj_deleteModel(m);
  }
}

TEST_F(DynamicsRegressorTest, SlideJointsOffsetAnchorsAndHeldBodies) {
  const mjModel* m = LoadModelFromString("mixed.xml", kMixedChainXml);
  std::vector<double> qpos(m->qpos0, m->qpos0 + m->nq);
  qpos[m->jnt_qposadr[mj_name2id(m, mjOBJ_JOINT, "finger")]] = 0.013;  // held there
  auto r = DynamicsRegressor::Create(m, {"j1", "j2", "j3"}, qpos);
  EXPECT_LT(WorstAgainstRne(m, *r, qpos), 1e-9);
}

TEST_F(DynamicsRegressorTest, DampingAndArmatureAsMujocosInverse) {
  // mj_inverse: M(q)·qdd (armature in M) + bias − passive (damping); no contacts, no
  // friction loss (a constraint in MuJoCo, not the Coulomb column)
  mjModel* m = mj_copyModel(nullptr, LoadModel("scenes/pa10.xml"));
  m->opt.disableflags |= mjDSBL_CONTACT;
  for (int i = 0; i < 7; ++i) m->dof_damping[i] = 1.5 + i;
  auto r = DynamicsRegressor::Create(m, kPa10Joints);
  Eigen::VectorXd pi = r->Parameters(*m);
  EXPECT_DOUBLE_EQ(pi[70 + 3], 4.5);
  std::mt19937_64 rng(3);
  Eigen::MatrixXd Y;
  Eigen::VectorXd q, qd, qdd;
  for (int k = 0; k < 10; ++k) {
    RandomState(&rng, *r, &q, &qd, &qdd);
    r->Compute(q, qd, qdd, &Y);
    mjData* d = MakeData(m);
    for (int i = 0; i < 7; ++i) d->qpos[i] = q[i], d->qvel[i] = qd[i], d->qacc[i] = qdd[i];
    mj_inverse(m, d);
    const Eigen::VectorXd tau = Eigen::Map<const Eigen::VectorXd>(d->qfrc_inverse, 7);
    EXPECT_LT((Y * pi - tau).cwiseAbs().maxCoeff(), 1e-9 * std::max(1.0, tau.cwiseAbs().maxCoeff()));
  }
  // the Coulomb column: sign(qd) per joint
  qd.setZero();
  qd[2] = -0.1;
  r->Compute(q, qd, qdd, &Y);
  EXPECT_EQ(Y(2, 77 + 2), -1);
  EXPECT_EQ(Y(1, 77 + 1), 0);
  mj_deleteModel(m);
}

TEST_F(DynamicsRegressorTest, BaseParametersOfThePa10) {
  const mjModel* m = LoadModel("scenes/pa10.xml");
  auto r = DynamicsRegressor::Create(m, kPa10Joints);
  std::mt19937_64 rng(17);
  Eigen::MatrixXd W(7 * 100, r->parameters()), Y;
  Eigen::VectorXd q, qd, qdd;
  for (int k = 0; k < 100; ++k) {
    RandomState(&rng, *r, &q, &qd, &qdd);
    r->Compute(q, qd, qdd, &Y);
    W.middleRows(7 * k, 7) = Y;
  }
  const BaseParameters base = FindBaseParameters(W);
  const int rank = static_cast<int>(base.independent.size());
  EXPECT_EQ(rank + base.dependent.size(), 91u);
  EXPECT_LT(rank, 91);
  // the dropped columns are combinations of the kept ones: W·pi = W_base·pi_base
  Eigen::MatrixXd W_ind(W.rows(), rank), W_dep(W.rows(), base.dependent.size());
  for (int k = 0; k < rank; ++k) W_ind.col(k) = W.col(base.independent[k]);
  for (std::size_t k = 0; k < base.dependent.size(); ++k) W_dep.col(k) = W.col(base.dependent[k]);
  EXPECT_LT((W_dep - W_ind * base.K).cwiseAbs().maxCoeff(), 1e-8 * W.cwiseAbs().maxCoeff());
  EXPECT_LT(ConditionNumber(W_ind), 1e8);
  EXPECT_TRUE(std::isinf(ConditionNumber(W)) || ConditionNumber(W) > 1e12);
  // S1 turns its link about the vertical: nothing but its inertia about z moves it, so the
  // link's mass and first moments cannot be identified (their columns are zero)
  const auto dropped = [&](const std::string& name) {
    const int col = static_cast<int>(std::find(r->names().begin(), r->names().end(), name) - r->names().begin());
    return std::find(base.dependent.begin(), base.dependent.end(), col) != base.dependent.end();
  };
  EXPECT_TRUE(dropped("pa10_link1.m"));
  EXPECT_TRUE(dropped("pa10_link1.mx"));
  EXPECT_TRUE(dropped("pa10_link1.Ixx"));
  EXPECT_FALSE(dropped("S1.frictionloss"));
}

TEST_F(DynamicsRegressorTest, RefusesWhatIsNotAChain) {
  const mjModel* m = LoadModelFromString("mixed.xml", kMixedChainXml);
  const auto message = [&](const std::vector<std::string>& joints) {
    try {
      DynamicsRegressor::Create(m, joints);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message({"j1", "nope"}).find("no joint 'nope'"), std::string::npos);
  EXPECT_NE(message({"j2", "j1"}).find("joint 'j1' is not below joint 'j2'"), std::string::npos);
  EXPECT_NE(message({}).find("no joints"), std::string::npos);
  EXPECT_NE(message({"box_free"}).find("joint 'box_free' is not a hinge or slide"), std::string::npos);
}

}  // namespace
}  // namespace vlab::control
