// Model validation of the mobile-manipulation models and scenes: they load without
// compiler warnings and simulate without MuJoCo warnings; masses equal the data sheet
// (DATASHEET 1.3, 2; the gripper's and the cube's README values) within 1 %; DOF counts;
// joint limits and drive limits; every joint, actuator, sensor, site and camera that the
// base and gripper devices (and the arm and JR3 devices) bind to exists; the PA10 stands on
// the XR4000's mount; nothing touches in the scenes' start poses.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include "mobile/mobile_scene.h"

namespace vlab::testing {
namespace {

constexpr double kDeg = kPi / 180;
const char* const kArmJoints[] = {"S1", "S2", "S3", "E1", "E2", "W1", "W2"};
// DATASHEET 1.3 (masses, kg) and 1.4 (limits, deg)
const double kArmLinkMass[] = {9.78, 8.41, 3.52, 4.31, 3.45, 1.46, 0.24};
const double kArmLimitDeg[] = {177, 94, 174, 137, 255, 165, 255};
constexpr double kPa10Mass = 34.21;                     // base + 7 links
constexpr double kJr3AndToolMass = 0.17 + 0.3416;       // mjcf/pa10/README.md
constexpr double kXr4000Mass = 30 + 4 * (2.72 + 5.2);   // DATASHEET 2: body + 4 casters
constexpr double kGripperMass = 1.4;                    // mjcf/gripper/README.md (PG 70)
constexpr double kCubeMass = 720 * 0.05 * 0.05 * 0.05;  // beech, 5 cm

double BodyMass(const mjModel* m, const char* name) {
  const int id = RequireId(m, mjOBJ_BODY, name);
  return id < 0 ? 0 : SubtreeMass(m, id);
}

void ExpectNamed(const mjModel* m, mjtObj type, const std::vector<std::string>& names) {
  for (const std::string& name : names) RequireId(m, type, name);
}

void ExpectRange(const mjtNum* range, int id, double lo, double hi, const std::string& what) {
  EXPECT_NEAR(range[2 * id], lo, 1e-9) << what;
  EXPECT_NEAR(range[2 * id + 1], hi, 1e-9) << what;
}

// the arm part of a scene: masses, joint ranges, devices' names
void ExpectPa10(const mjModel* m) {
  EXPECT_NEAR(BodyMass(m, "pa10_base"), kPa10Mass + kJr3AndToolMass, 1e-9);
  const char* const links[] = {"pa10_link1", "pa10_link2", "pa10_link3", "pa10_link4",
                               "pa10_link5", "pa10_link6", "pa10_link7"};
  for (int i = 0; i < 7; ++i) {
    const int body = RequireId(m, mjOBJ_BODY, links[i]);
    if (body >= 0) {
      EXPECT_NEAR(m->body_mass[body], kArmLinkMass[i], 0.01 * kArmLinkMass[i]) << links[i];
    }
    const int joint = RequireId(m, mjOBJ_JOINT, kArmJoints[i]);
    if (joint < 0) continue;
    EXPECT_TRUE(m->jnt_limited[joint]) << kArmJoints[i];
    ExpectRange(m->jnt_range, joint, -kArmLimitDeg[i] * kDeg, kArmLimitDeg[i] * kDeg, kArmJoints[i]);
    RequireId(m, mjOBJ_ACTUATOR, kArmJoints[i]);
    for (const char* suffix : {"_pos", "_vel", "_torque"}) {
      RequireId(m, mjOBJ_SENSOR, std::string(kArmJoints[i]) + suffix);
    }
  }
  ExpectNamed(m, mjOBJ_SENSOR, {"jr3_force", "jr3_torque"});
  ExpectNamed(m, mjOBJ_SITE, {"flange", "jr3", "tool"});
}

// the names the base device binds to (mjcf/nomad_xr4000/README.md "Device binding")
void ExpectXr4000(const mjModel* m) {
  const char* const joints[] = {"base_x", "base_y", "base_yaw"};
  const char* const actuators[] = {"base_x", "base_y", "base_yaw"};
  const double speed[] = {1.0, 1.0, 2.0}, force[] = {96.4, 96.4, 19.5}, kv[] = {5000, 5000, 325};
  for (int i = 0; i < 3; ++i) {
    const int joint = RequireId(m, mjOBJ_JOINT, joints[i]);
    if (joint >= 0) {
      EXPECT_FALSE(m->jnt_limited[joint]) << joints[i] << ": the floor does not end";
    }
    const int act = RequireId(m, mjOBJ_ACTUATOR, actuators[i]);
    if (act < 0) continue;
    EXPECT_EQ(m->actuator_trnid[2 * act], joint);
    EXPECT_TRUE(m->actuator_ctrllimited[act] && m->actuator_forcelimited[act]);
    ExpectRange(m->actuator_ctrlrange, act, -speed[i], speed[i], actuators[i]);
    ExpectRange(m->actuator_forcerange, act, -force[i], force[i], actuators[i]);
    // a velocity servo: force = kv ctrl - kv qvel
    EXPECT_EQ(m->actuator_gainprm[mjNGAIN * act], kv[i]);
    EXPECT_EQ(m->actuator_biasprm[mjNBIAS * act + 2], -kv[i]);
  }
  ExpectNamed(m, mjOBJ_SENSOR,
              {"base_x_pos", "base_y_pos", "base_yaw_pos", "base_x_vel", "base_y_vel", "base_yaw_vel", "base_x_force",
               "base_y_force", "base_yaw_torque"});
  ExpectNamed(m, mjOBJ_SITE, {"xr4000_center", "pa10_mount"});
}

// the names the gripper device binds to (mjcf/gripper/README.md "Device binding")
void ExpectGripper(const mjModel* m) {
  EXPECT_NEAR(BodyMass(m, "gripper"), kGripperMass, 0.01 * kGripperMass);
  for (const char* name : {"gripper_left", "gripper_right"}) {
    const int joint = RequireId(m, mjOBJ_JOINT, name);
    if (joint < 0) continue;
    EXPECT_EQ(m->jnt_type[joint], mjJNT_SLIDE);
    EXPECT_TRUE(m->jnt_limited[joint]);
    ExpectRange(m->jnt_range, joint, 0, 0.034, name);
  }
  const int servo = RequireId(m, mjOBJ_ACTUATOR, "gripper");
  if (servo >= 0) {
    ExpectRange(m->actuator_ctrlrange, servo, 0, 0.068, "gripper");
    ExpectRange(m->actuator_forcerange, servo, -200, 200, "gripper");
  }
  const int drive = RequireId(m, mjOBJ_ACTUATOR, "gripper_force");
  if (drive >= 0) ExpectRange(m->actuator_ctrlrange, drive, -200, 200, "gripper_force");
  ExpectNamed(m, mjOBJ_TENDON, {"gripper_opening"});
  ExpectNamed(m, mjOBJ_EQUALITY, {"gripper_sync", "gripper_mount"});
  ExpectNamed(m, mjOBJ_SENSOR,
              {"gripper_touch_left", "gripper_touch_right", "gripper_opening", "gripper_opening_vel",
               "gripper_left_pos", "gripper_right_pos", "gripper_servo_force", "gripper_drive_force"});
  ExpectNamed(m, mjOBJ_SITE, {"gripper_mount", "gripper_tcp", "gripper_pad_left", "gripper_pad_right"});
}

// 2 s of holding the arm's pose (joint PD + bias; nothing for a scene without an arm); a
// MuJoCo warning fails the test (the MuJoCo fixture)
void Hold(const mjModel* m, mjData* d) {
  if (mj_name2id(m, mjOBJ_SITE, "tool") < 0) {
    for (int k = 0; k < 2000; ++k) mj_step(m, d);
    return;
  }
  ArmServo servo(m, *d, "pa10_base", "tool", 10.0, 1.0);
  const Eigen::VectorXd q = servo.model().ChainPositions(*d);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(q.size());
  for (int k = 0; k < 2000; ++k) {
    servo.Command(d, q, zero, Eigen::VectorXd());
    mj_step(m, d);
  }
}

using MobileModels = vlab::test::MujocoTest;

TEST_F(MobileModels, Xr4000AloneMatchesTheDataSheet) {
  const mjModel* m = LoadModel("tests/mobile/data/xr4000_base.xml");
  EXPECT_EQ(m->nq, 3);
  EXPECT_EQ(m->nv, 3);
  EXPECT_EQ(m->nu, 3);
  EXPECT_NEAR(BodyMass(m, "xr4000"), kXr4000Mass, 1e-9);
  EXPECT_NEAR(BodyMass(m, "xr4000"), 61.68, 0.01 * 61.68);
  ExpectXr4000(m);
  mjData* data = MakeData(m);
  mj_forward(m, data);
  EXPECT_EQ(data->ncon, 0) << "the casters must clear the floor (planar joints carry the base)";
  Hold(m, data);
}

TEST_F(MobileModels, Pa10OnTheXr4000) {
  const mjModel* m = LoadModel("scenes/pa10_nomad.xml");
  EXPECT_EQ(m->nq, 10);
  EXPECT_EQ(m->nv, 10);
  EXPECT_EQ(m->nu, 10);
  EXPECT_NEAR(BodyMass(m, "xr4000"), kXr4000Mass + kPa10Mass + kJr3AndToolMass, 1e-9);
  ExpectPa10(m);
  ExpectXr4000(m);
  ExpectNamed(m, mjOBJ_CAMERA, {"overview"});
  ExpectNamed(m, mjOBJ_SITE, {"target"});
  EXPECT_EQ(m->vis.global.offwidth, 1280);
  EXPECT_EQ(m->vis.global.offheight, 960);
  // the qpos layout the scene documents: base_x, base_y, base_yaw, then S1..W2
  EXPECT_EQ(m->jnt_qposadr[mj_name2id(m, mjOBJ_JOINT, "base_yaw")], 2);
  EXPECT_EQ(m->jnt_qposadr[mj_name2id(m, mjOBJ_JOINT, "S1")], 3);

  for (int key = 0; key < m->nkey; ++key) {
    mjData* d = MakeData(m);  // one per keyframe: mj_resetData clears the warning counters
    mj_resetDataKeyframe(m, d, key);
    mj_forward(m, d);
    const int base = mj_name2id(m, mjOBJ_BODY, "pa10_base");
    const int mount = mj_name2id(m, mjOBJ_SITE, "pa10_mount");
    // the arm's base frame is the mount site's frame
    EXPECT_LT((Vec3(d->xpos + 3 * base) - Vec3(d->site_xpos + 3 * mount)).norm(), 1e-12);
    EXPECT_LT(AngleBetween(Mat3(d->xmat + 9 * base), Mat3(d->site_xmat + 9 * mount)), 1e-12);
    EXPECT_EQ(d->ncon, 0) << "keyframe " << mj_id2name(m, mjOBJ_KEY, key);
    Hold(m, d);
  }
  // mount height and the table: the docked base stops 5 cm short of the table edge
  mjData* d = MakeData(m);
  mj_resetDataKeyframe(m, d, mj_name2id(m, mjOBJ_KEY, "docked"));
  mj_forward(m, d);
  EXPECT_NEAR(d->site_xpos[3 * mj_name2id(m, mjOBJ_SITE, "pa10_mount") + 2], 0.85, 1e-12);
}

TEST_F(MobileModels, Pa10WithTheGripper) {
  const mjModel* m = LoadModel("scenes/pa10_gripper.xml");
  // arm 7, gripper free joint 7 (6 dof), jaws 2, cube free joint 7 (6 dof)
  EXPECT_EQ(m->nq, 7 + 7 + 2 + 7);
  EXPECT_EQ(m->nv, 7 + 6 + 2 + 6);
  EXPECT_EQ(m->nu, 7 + 2);
  ExpectPa10(m);
  ExpectGripper(m);
  EXPECT_NEAR(BodyMass(m, "cube"), kCubeMass, 0.01 * kCubeMass);
  ExpectNamed(m, mjOBJ_CAMERA, {"overview"});
  EXPECT_EQ(m->vis.global.offwidth, 1280);
  EXPECT_EQ(m->vis.global.offheight, 960);
  EXPECT_EQ(m->opt.cone, mjCONE_ELLIPTIC);

  mjData* d = MakeData(m);
  // forearm level, turned and rolled, the gripper at its welded place: only the cube rests on
  // the table
  const double pose[] = {0.3, 0, 0, 1.570796, 0, 0, 0.5};
  for (int i = 0; i < 7; ++i) d->qpos[i] = pose[i];
  PlaceWeldedBodies(m, d);
  const int cube = mj_name2id(m, mjOBJ_GEOM, "cube"), table = mj_name2id(m, mjOBJ_GEOM, "table_top");
  for (int c = 0; c < d->ncon; ++c) {
    const int g1 = d->contact[c].geom1, g2 = d->contact[c].geom2;
    EXPECT_TRUE((g1 == cube && g2 == table) || (g1 == table && g2 == cube))
        << mj_id2name(m, mjOBJ_GEOM, g1) << " touches " << mj_id2name(m, mjOBJ_GEOM, g2);
  }
  // the gripper sits on the pointer tip
  const int tool = mj_name2id(m, mjOBJ_SITE, "tool"), mount = mj_name2id(m, mjOBJ_SITE, "gripper_mount");
  EXPECT_LT((Vec3(d->site_xpos + 3 * tool) - Vec3(d->site_xpos + 3 * mount)).norm(), 1e-12);
  Hold(m, d);
}

// the keyframe home (docs/tasks.md's tutorial starts there): the gripper's free joint holds the
// welded place by its typed numbers (to their 9 decimals: 1e-8 m, 1e-8 rad), the tool points
// straight down, the pads are 0.14 m above the table, and only the cube touches the table
TEST_F(MobileModels, Pa10WithTheGripperHomeKeyframeHasTheGripperAtItsWeld) {
  const mjModel* m = LoadModel("scenes/pa10_gripper.xml");
  mjData* d = MakeData(m);
  const int home = mj_name2id(m, mjOBJ_KEY, "home");
  ASSERT_GE(home, 0);
  mj_resetDataKeyframe(m, d, home);
  mj_forward(m, d);
  const int tool = mj_name2id(m, mjOBJ_SITE, "tool"), mount = mj_name2id(m, mjOBJ_SITE, "gripper_mount");
  EXPECT_LT((Vec3(d->site_xpos + 3 * tool) - Vec3(d->site_xpos + 3 * mount)).norm(), 1e-8);
  EXPECT_LT(AngleBetween(Mat3(d->site_xmat + 9 * tool), Mat3(d->site_xmat + 9 * mount)), 1e-8);
  EXPECT_NEAR(d->site_xmat[9 * tool + 8], -1.0, 1e-12);  // the tool z is the world's -z
  const int tcp = mj_name2id(m, mjOBJ_SITE, "gripper_tcp");
  EXPECT_NEAR(d->site_xpos[3 * tcp + 2] - 0.40, 0.143, 0.001);  // the table top is at z = 0.40 m
  const int cube = mj_name2id(m, mjOBJ_GEOM, "cube"), table = mj_name2id(m, mjOBJ_GEOM, "table_top");
  for (int c = 0; c < d->ncon; ++c) {
    const int g1 = d->contact[c].geom1, g2 = d->contact[c].geom2;
    EXPECT_TRUE((g1 == cube && g2 == table) || (g1 == table && g2 == cube))
        << mj_id2name(m, mjOBJ_GEOM, g1) << " touches " << mj_id2name(m, mjOBJ_GEOM, g2);
  }
  Hold(m, d);
}

}  // namespace
}  // namespace vlab::testing
