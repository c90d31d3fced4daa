// The arm servo's own model (arm_servo_model.h): it equals the world's arm where
// it knows every body (chain folding, slide joints, refs, rotated frames), it
// leaves out what it is not told (J^T F of the bodies it does not know), and bad
// servo and payload keys are InputErrors naming the device or key.
#include "lab/devices/arm_servo_model.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "arm_keys_error.h"
#include "arm_servo_forces.h"
#include "core/core_errors.h"
#include "lab/devices/arm_servo_rne.h"
#include "lab/devices/device_arm.h"
#include "lab/scenario/lab_scenario.h"
#include "mujoco_fixture.h"
#include "test_util.h"

namespace vlab::lab::arm_servo_model_test {
namespace {

// three jointed bodies (hinge, hinge with ref, slide), an unjointed spacer
// between the first two (rotated, off-axis inertia) and a load on the last
constexpr const char* kChain = R"(
<mujoco>
  <option gravity="0.5 -0.3 -9.81" timestep="0.001"/>
  <worldbody>
    <body name="base" pos="0.1 0.2 0.3" quat="0.9659258 0 0.258819 0">
      <body name="l1" pos="0.05 0 0.1" quat="0.9238795 0 0 0.3826834">
        <joint name="a" axis="0 0 1" pos="0.01 0 0" armature="0.3"/>
        <inertial pos="0 0.01 0.05" mass="2" diaginertia="0.02 0.02 0.01"/>
        <body name="spacer" pos="0.05 0.02 0.1" quat="0.9238795 0.3826834 0 0">
          <inertial pos="0.01 0.02 0.03" quat="0.7071068 0 0.7071068 0" mass="0.7" diaginertia="0.003 0.002 0.0015"/>
          <body name="l2" pos="0 0 0.1">
            <joint name="b" axis="0 1 0" ref="0.3" armature="0.1"/>
            <inertial pos="0 0 0.15" mass="1.5" diaginertia="0.01 0.01 0.002"/>
            <body name="l3" pos="0 0 0.3" quat="0.9659258 0 0 0.258819">
              <joint name="c" type="slide" axis="0.6 0.8 0" armature="0.05"/>
              <inertial pos="0.02 0 0.05" mass="0.8" diaginertia="0.004 0.003 0.002"/>
              <body name="load" pos="0 0.03 0.1" quat="0.9238795 0 0.3826834 0">
                <inertial pos="0 0.01 0.02" quat="0.8660254 0.5 0 0" mass="0.5" diaginertia="0.001 0.002 0.0025"/>
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>)";

class ServoModelTest : public test::MujocoTest {
 protected:
  std::vector<int> Joints(const mjModel* m, const std::vector<std::string>& names) {
    std::vector<int> ids;
    for (const auto& n : names) ids.push_back(mj_name2id(m, mjOBJ_JOINT, n.c_str()));
    return ids;
  }
  // At 20 random states of the world: the servo model (placed at the world's
  // base) gives the world's bias and inertia diagonal, less the bias of the
  // bodies `unknown` (their weight through J^T: the test's own closed form).
  void Compare(const mjModel* m, const std::vector<int>& joints, const std::vector<std::string>& bodies,
               const std::vector<std::string>& unknown, const Payload& payload = {}) {
    mjData* d = MakeData(m);
    auto servo = ArmServoModel::Create(*m, joints, bodies);
    ASSERT_TRUE(servo->SetPayload(payload));
    mj_forward(m, d);
    servo->Place(*d);
    std::mt19937 random(7);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    const int n = static_cast<int>(joints.size());
    std::vector<double> bias(n), inertia(n);
    for (int trial = 0; trial < 20; ++trial) {
      // velocities too where the servo knows every body (Coriolis); at rest where it does not
      for (int j : joints) {
        d->qpos[m->jnt_qposadr[j]] = m->qpos0[m->jnt_qposadr[j]] + uniform(random);
        d->qvel[m->jnt_dofadr[j]] = unknown.empty() ? 2.0 * uniform(random) : 0.0;
      }
      mj_forward(m, d);
      servo->Bias(*d, bias.data());
      servo->InertiaDiagonal(*d, inertia.data());
      const std::vector<double> missing = WeightBias(m, d, joints, unknown);
      for (int i = 0; i < n; ++i) {
        const int dof = m->jnt_dofadr[joints[i]];
        const double world = d->qfrc_bias[dof];
        EXPECT_NEAR(bias[i] + missing[i], world, 1e-9 * (1 + std::abs(world))) << "joint " << i << " trial " << trial;
        if (unknown.empty()) {
          EXPECT_NEAR(inertia[i], d->qM[m->dof_Madr[dof]], 1e-9) << "joint " << i;
        }
      }
    }
  }
};

TEST_F(ServoModelTest, EqualsTheWorldWhereItKnowsEveryBody) {
  const mjModel* m = LoadModelFromString(kChain);
  Compare(m, Joints(m, {"a", "b", "c"}), {"spacer", "load"}, {});
}

TEST_F(ServoModelTest, FoldsAnUnnamedBodyIntoTheChainAndMissesItsWeight) {
  const mjModel* m = LoadModelFromString(kChain);
  Compare(m, Joints(m, {"a", "b", "c"}), {}, {"spacer", "load"});
}

// The body "load" of kChain as a payload of l3: mass, centre of mass and full
// inertia tensor in l3's frame (the test's own composition of the MJCF numbers).
Payload LoadAsPayload(const mjModel* m) {
  const int b = mj_name2id(m, mjOBJ_BODY, "load");
  Payload p;
  p.mass_kg = m->body_mass[b];
  double com[3], quat[4], rotation[9];
  mju_rotVecQuat(com, m->body_ipos + 3 * b, m->body_quat + 4 * b);
  mju_addTo3(com, m->body_pos + 3 * b);
  p.com_m = Eigen::Vector3d(com[0], com[1], com[2]);
  mju_mulQuat(quat, m->body_quat + 4 * b, m->body_iquat + 4 * b);
  mju_quat2Mat(rotation, quat);
  const Eigen::Matrix3d r = Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(rotation);
  const Eigen::Matrix3d inertia =
      r * Eigen::Map<const Eigen::Vector3d>(m->body_inertia + 3 * b).asDiagonal() * r.transpose();
  p.inertia_kgm2 = {inertia(0, 0), inertia(1, 1), inertia(2, 2), inertia(0, 1), inertia(0, 2), inertia(1, 2)};
  return p;
}

TEST_F(ServoModelTest, APayloadEqualToTheLoadIsTheLoad) {
  const mjModel* m = LoadModelFromString(kChain);
  const Payload load = LoadAsPayload(m);
  EXPECT_GT(std::abs(load.inertia_kgm2[3]) + std::abs(load.inertia_kgm2[4]) + std::abs(load.inertia_kgm2[5]), 1e-4);
  Compare(m, Joints(m, {"a", "b", "c"}), {"spacer"}, {}, load);
}

TEST_F(ServoModelTest, EqualsThePa10WithItsToolNamed) {
  const mjModel* m = LoadModel("scenes/pa10.xml");
  Compare(m, Joints(m, {"S1", "S2", "S3", "E1", "E2", "W1", "W2"}), {"jr3_body", "jr3_tool_side", "tool_body"}, {});
}

// The PA10's chain (one hinge per body, at its origin) takes the pass in the bodies' frames;
// at 20 random states it gives the general pass's torques to rounding. kChain (a slide, a
// joint off its body's origin) cannot, and takes the general pass.
TEST_F(ServoModelTest, TheLocalPassEqualsTheGeneralOne) {
  const mjModel* pa10 = LoadModel("scenes/pa10.xml");
  const std::unique_ptr<ArmServoModel> servo = ArmServoModel::Create(
      *pa10, Joints(pa10, {"S1", "S2", "S3", "E1", "E2", "W1", "W2"}), {"jr3_body", "jr3_tool_side", "tool_body"});
  const mjModel& s = servo->model();
  ChainRne rne(s);
  ASSERT_TRUE(rne.local());
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> angle(-2.0, 2.0), rate(-3.0, 3.0);
  std::vector<double> qpos(s.nq), qvel(s.nv), local(s.nv), general(s.nv);
  double worst = 0.0, largest = 0.0;
  for (int trial = 0; trial < 20; ++trial) {
    for (int i = 0; i < s.nq; ++i) qpos[i] = angle(rng);
    for (int i = 0; i < s.nv; ++i) qvel[i] = rate(rng);
    rne.Bias(s, qpos.data(), qvel.data(), local.data());
    rne.BiasWorld(s, qpos.data(), qvel.data(), general.data());
    for (int i = 0; i < s.nv; ++i) {
      worst = std::max(worst, std::abs(local[i] - general[i]));
      largest = std::max(largest, std::abs(general[i]));
    }
  }
  EXPECT_LE(worst, 1e-12 * largest) << "largest torque " << largest;
  EXPECT_GT(largest, 1.0);
  EXPECT_FALSE(ChainRne(*LoadModelFromString(kChain)).local());
}

TEST_F(ServoModelTest, RefusesBodiesItCannotUse) {
  const mjModel* m = LoadModelFromString(kChain);
  auto error = [&](const std::vector<std::string>& joints, const std::vector<std::string>& bodies) {
    try {
      ArmServoModel::Create(*m, Joints(m, joints), bodies);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error({"a", "b", "c"}, {"gripper"}).find("servo.bodies: no body 'gripper'"), std::string::npos);
  EXPECT_NE(error({"b", "c"}, {"l1"}).find("servo.bodies: body 'l1' is not moved by the arm's joints"),
            std::string::npos);
  // a joint of the chain that is not the arm's: the chain is not rigid between its bodies
  EXPECT_NE(error({"a", "c"}, {}).find("body 'l2' between the arm's bodies 'l1' and 'l3' has joint 'b'"),
            std::string::npos)
      << error({"a", "c"}, {});
}

TEST(PayloadTest, ChecksRigidBodies) {
  std::string field, reason;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Payload p;
  p.mass_kg = 1.0;
  p.inertia_kgm2 = {0.01, 0.02, 0.025, 0.001, 0, 0};
  EXPECT_TRUE(CheckPayload(p, &field, &reason)) << reason;
  auto refused = [&](Payload bad) {
    field.clear();
    EXPECT_FALSE(CheckPayload(bad, &field, &reason));
    return field;
  };
  Payload bad = p;
  bad.mass_kg = -0.1;
  EXPECT_EQ(refused(bad), "mass");
  bad = p;
  bad.mass_kg = nan;
  EXPECT_EQ(refused(bad), "mass");
  bad = p;
  bad.com_m[1] = nan;
  EXPECT_EQ(refused(bad), "com");
  bad = p;
  bad.inertia_kgm2 = {0.01, 0.01, 0.01, 0.02, 0, 0};  // eigenvalues -0.01, 0.01, 0.03
  EXPECT_EQ(refused(bad), "inertia");
  EXPECT_NE(reason.find("positive semi-definite"), std::string::npos);
  bad.inertia_kgm2 = {0.01, 0.01, 0.03, 0, 0, 0};  // 0.03 > 0.01 + 0.01
  EXPECT_EQ(refused(bad), "inertia");
  EXPECT_NE(reason.find("triangle"), std::string::npos);
  bad.inertia_kgm2 = {0.01, 0.01, nan, 0, 0, 0};
  EXPECT_EQ(refused(bad), "inertia");
}

TEST(ArmServoKeysTest, BadKeysNameTheField) {
  EXPECT_EQ(ArmKeysError("    servo: {feedforward: model, bodies: [x]}\n    payload: {mass: 1, com: [0, 0, 0.1], "
                         "inertia: [0.01, 0.01, 0.01, 0, 0, 0]}\n"),
            "");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"    servo: {feedforward: exact}\n", "devices[0].servo.feedforward: must be world or model, got 'exact'"},
      {"    payload: {mass: -1}\n", "devices[0].payload.mass: must be a finite number >= 0 kg"},
      {"    payload: {mass: .nan}\n", "devices[0].payload.mass: expected a finite number"},
      {"    payload: {com: [0, 0, 0]}\n", "devices[0].payload.mass"},
      {"    payload: {mass: 1, com: [0, 0]}\n", "devices[0].payload.com: needs 3 numbers"},
      {"    payload: {mass: 1, inertia: [0.01, 0.01, 0.01, 0.02, 0, 0]}\n",
       "devices[0].payload.inertia: is not positive semi-definite"},
      {"    payload: {mass: 1, inertia: [0.01, 0.01, 0.03]}\n", "devices[0].payload.inertia: principal moments"},
      {"    payload: {mass: 1, inertai: [0.01, 0.01, 0.01]}\n", "devices[0].payload.inertai: unknown key"},
  };
  for (const auto& [keys, expected] : cases) {
    const std::string e = ArmKeysError(keys);
    EXPECT_NE(e.find(expected), std::string::npos) << keys << " -> " << e;
    EXPECT_NE(e.find("s.yaml:"), std::string::npos) << e;
  }
}

TEST_F(ServoModelTest, SimArmNamesTheDeviceForBadBodiesAndPayloads) {
  const mjModel* m = LoadModel("scenes/pa10.xml");
  auto error = [&](const std::vector<std::string>& bodies, double mass) {
    DeviceConfig c;
    c.name = "pa10";
    c.where = "arm.yaml:9";
    auto& p = c.EditParams<ArmParams>();
    p.joints = p.actuators = {"S1", "S2", "S3", "E1", "E2", "W1", "W2"};
    p.servo.bodies = bodies;
    p.payload.mass_kg = mass;
    try {
      SimArm::Create({m, 0.002, 1, "pa10.xml"}, c);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(error({"tool_body"}, 0.5), "");
  EXPECT_EQ(error({"gripper"}, 0), "arm.yaml:9: device 'pa10': servo.bodies: no body 'gripper' in the scene");
  EXPECT_EQ(error({}, std::numeric_limits<double>::quiet_NaN()),
            "arm.yaml:9: device 'pa10': payload.mass: must be a finite number >= 0 kg");
}

}  // namespace
}  // namespace vlab::lab::arm_servo_model_test
