// HOAP-3 model (scenes/hoap3.xml, mjcf/hoap3/) against its sources: geometry, sensors,
// device bindings and postures.
//   - link geometry, sole outline, FSR layout, eye cameras and IMU of DATASHEET 3.3/3.5;
//   - every element the devices bind to exists: arm (28 joints + torque motors), feet
//     (8 FSRs), imu (gyro + accelerometer), two cameras;
//   - the SL joint signs give the SL default posture level, mirrored feet;
//   - the `stand` keyframe puts flat feet on the floor with the COM over them.
#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "models/hoap3_fixture.h"

namespace vlab::models::testing {
namespace {

TEST_F(Hoap3Model, LegGeometryIsTheDatasheets) {
  for (const double side : {-1.0, 1.0}) {
    const std::string s = side < 0 ? "r" : "l";
    SCOPED_TRACE(s);
    const Eigen::Vector3d hip(-kWaistToHipX, side * kHipLateral, -kWaistToHipZ);
    EXPECT_LT((BodyPos("hoap3_" + s + "_thigh") - hip).norm(), 1e-9);
    EXPECT_LT((BodyPos("hoap3_" + s + "_shank") - hip - Eigen::Vector3d(0, 0, -kThigh)).norm(), 1e-9);
    const Eigen::Vector3d ankle = hip - Eigen::Vector3d(0, 0, kThigh + kShank);
    EXPECT_LT((BodyPos("hoap3_" + s + "_foot") - ankle).norm(), 1e-9);
    // sole outline (right foot; the left is its mirror image), 10 mm thick
    const int sole = Id(m(), mjOBJ_GEOM, "hoap3_" + s + "_sole");
    ASSERT_GE(sole, 0);
    const Eigen::Vector3d centre = Vec3(d()->geom_xpos + 3 * sole) - pelvis_ - ankle;
    const Eigen::Vector3d half = Vec3(m()->geom_size + 3 * sole);
    EXPECT_NEAR(centre.x() - half.x(), kSoleBack, 1e-9);
    EXPECT_NEAR(centre.x() + half.x(), kSoleFront, 1e-9);
    // lateral edges, measured outward (towards -y for the right foot, +y for the left)
    EXPECT_NEAR(side * centre.y() + half.y(), kSoleOuter, 1e-9);
    EXPECT_NEAR(side * centre.y() - half.y(), -kSoleInner, 1e-9);
    EXPECT_NEAR(2 * half.z(), 0.010, 1e-9);
  }
}

// DATASHEET 3.5: the ZMP formula of hoap3_read_sensors puts a foot's right FSR column
// at +(LX - MX) and its left column at -MX on a lateral axis pointing right, the front
// row at +(LY - MY) and the back row at -MY on the forward axis, both from the ankle's
// projection on the sole (12.5-13 mm inside the sole outline on every side).
TEST_F(Hoap3Model, FsrPadsSitWhereTheZmpFormulaPutsThem) {
  for (const double side : {-1.0, 1.0}) {
    const std::string s = side < 0 ? "r" : "l";
    const double mx = (side < 0 ? kFsrMxRight : kFsrMxLeft) / 1000, lx = kFsrLx / 1000;
    const double front = (kFsrLy - kFsrMy) / 1000, back = -kFsrMy / 1000;
    const Eigen::Vector3d ankle = BodyPos("hoap3_" + s + "_foot");
    const std::map<std::string, Eigen::Vector2d> pads = {
        {"fr", {front, -(lx - mx)}}, {"fl", {front, mx}}, {"br", {back, -(lx - mx)}}, {"bl", {back, mx}}};
    for (const auto& [corner, xy] : pads) {
      const std::string name = "hoap3_" + s + "foot_" + corner;
      SCOPED_TRACE(name);
      const int geom = Id(m(), mjOBJ_GEOM, name);
      ASSERT_GE(geom, 0);
      const Eigen::Vector3d pad = Vec3(d()->geom_xpos + 3 * geom) - pelvis_ - ankle;
      EXPECT_NEAR(pad.x(), xy.x(), 1e-9);
      EXPECT_NEAR(pad.y(), xy.y(), 1e-9);
      // the pad's lowest point is the sole plane
      EXPECT_NEAR(pad.z() - m()->geom_size[3 * geom], -kAnkleToSole, 1e-9);
      const Eigen::Vector3d site = SitePos(name) - ankle;
      EXPECT_LT((site.head<2>() - xy).norm(), 1e-9) << "touch zone centred on the pad";
    }
  }
}

TEST_F(Hoap3Model, UpperBodyGeometryIsTheDatasheets) {
  for (const double side : {-1.0, 1.0}) {
    const std::string s = side < 0 ? "r" : "l";
    const Eigen::Vector3d shoulder(-0.035, side * kShoulderLateral, kChestHeight);
    EXPECT_LT((BodyPos("hoap3_" + s + "_shoulder") - shoulder).norm(), 1e-9) << s;
    EXPECT_LT((BodyPos("hoap3_" + s + "_forearm") - shoulder - Eigen::Vector3d(kUpperArm, 0, 0)).norm(), 1e-9) << s;
  }
  const Eigen::Vector3d neck(-0.035, 0, kChestHeight);
  EXPECT_LT((BodyPos("hoap3_neck") - neck).norm(), 1e-9);
  const Eigen::Vector3d head = neck + Eigen::Vector3d(kHeadOffset, 0, kNeck);
  EXPECT_LT((BodyPos("hoap3_head") - head).norm(), 1e-9);
  for (const double side : {-1.0, 1.0}) {
    const char* name = side < 0 ? "hoap3_right_eye" : "hoap3_left_eye";
    SCOPED_TRACE(name);
    const int cam = Id(m(), mjOBJ_CAMERA, name);
    ASSERT_GE(cam, 0);
    EXPECT_EQ(m()->cam_bodyid[cam], Id(m(), mjOBJ_BODY, "hoap3_head"));
    const Eigen::Vector3d eye = Vec3(d()->cam_xpos + 3 * cam) - pelvis_ - head;
    EXPECT_NEAR(eye.x(), kEyeForward, 1e-9);
    EXPECT_NEAR(eye.y(), side * kEyeLateral, 1e-9);
    EXPECT_LT(std::abs(eye.z()), 0.005);
    // looks forward (camera -z = +x), image up = +z
    const Eigen::Matrix3d r = Mat3(d()->cam_xmat + 9 * cam);
    EXPECT_LT((-r.col(2) - Eigen::Vector3d::UnitX()).norm(), 1e-9);
    EXPECT_LT((r.col(1) - Eigen::Vector3d::UnitZ()).norm(), 1e-9);
  }
  EXPECT_LT((SitePos("hoap3_imu") - V(kImuInPelvis)).norm(), 1e-9);
}

TEST_F(Hoap3Model, EveryElementTheDevicesBindToExists) {
  // arm: 28 joints in SL order with torque motors of the same names (gear 1, no bias)
  const char* arm[28] = {"RL_J1", "RL_J2", "RL_J3", "RL_J4", "RL_J5", "RL_J6", "RA_J1", "RA_J2", "RA_J3", "RA_J4",
                         "LL_J1", "LL_J2", "LL_J3", "LL_J4", "LL_J5", "LL_J6", "LA_J1", "LA_J2", "LA_J3", "LA_J4",
                         "B_J",   "H_J1",  "H_J2",  "H_J3",  "RA_J5", "RA_J6", "LA_J5", "LA_J6"};
  // DATASHEET 3.1 torque limits (larger value of each pair), N m
  const std::map<std::string, double> torque = {
      {"RL_J1", 3},   {"RL_J3", 3},   {"RL_J6", 3},   {"LL_J1", 3},    {"LL_J3", 3},   {"LL_J6", 3},
      {"RA_J1", 3},   {"RA_J2", 3},   {"RA_J3", 3},   {"RA_J4", 3},    {"LA_J1", 3},   {"LA_J2", 3},
      {"LA_J3", 3},   {"LA_J4", 3},   {"RL_J2", 4.5}, {"RL_J4", 4.5},  {"RL_J5", 4.5}, {"LL_J2", 4.5},
      {"LL_J4", 4.5}, {"LL_J5", 4.5}, {"B_J", 4.5},   {"RA_J5", 0.36}, {"LA_J5", 0.36}};
  ASSERT_EQ(m()->nu, 28);
  for (int i = 0; i < 28; ++i) {
    SCOPED_TRACE(arm[i]);
    const int a = Id(m(), mjOBJ_ACTUATOR, arm[i]);
    ASSERT_EQ(a, i) << "actuators in SL order";
    EXPECT_EQ(m()->actuator_trntype[a], mjTRN_JOINT);
    EXPECT_EQ(m()->actuator_trnid[2 * a], Id(m(), mjOBJ_JOINT, arm[i]));
    EXPECT_EQ(m()->actuator_gear[6 * a], 1.0);
    EXPECT_EQ(m()->actuator_gainprm[mjNGAIN * a], 1.0);
    EXPECT_EQ(m()->actuator_biastype[a], mjBIAS_NONE);
    EXPECT_TRUE(m()->actuator_ctrllimited[a] && m()->actuator_forcelimited[a]);
    const double limit = m()->actuator_forcerange[2 * a + 1];
    EXPECT_EQ(m()->actuator_forcerange[2 * a], -limit);
    EXPECT_EQ(m()->actuator_ctrlrange[2 * a + 1], limit);
    if (torque.count(arm[i])) {
      EXPECT_EQ(limit, torque.at(arm[i]));
    }
  }
  // feet: 8 FSR touch sensors on sites of the foot bodies
  for (const char* foot : {"r", "l"}) {
    for (const char* corner : {"fr", "fl", "br", "bl"}) {
      const std::string name = std::string("hoap3_") + foot + "foot_" + corner;
      const int s = Id(m(), mjOBJ_SENSOR, name);
      ASSERT_GE(s, 0) << name;
      EXPECT_EQ(m()->sensor_type[s], mjSENS_TOUCH) << name;
      EXPECT_EQ(m()->site_bodyid[m()->sensor_objid[s]], Id(m(), mjOBJ_BODY, std::string("hoap3_") + foot + "_foot"));
    }
  }
  // imu: gyro and accelerometer at the chest's IMU site
  const int imu = Id(m(), mjOBJ_SITE, "hoap3_imu");
  ASSERT_GE(imu, 0);
  EXPECT_EQ(m()->site_bodyid[imu], Id(m(), mjOBJ_BODY, "hoap3_chest"));
  for (const auto& [name, type] : {std::pair<const char*, int>{"hoap3_gyro", mjSENS_GYRO},
                                   std::pair<const char*, int>{"hoap3_accel", mjSENS_ACCELEROMETER}}) {
    const int s = Id(m(), mjOBJ_SENSOR, name);
    ASSERT_GE(s, 0) << name;
    EXPECT_EQ(m()->sensor_type[s], type) << name;
    EXPECT_EQ(m()->sensor_objid[s], imu) << name;
  }
  // two head cameras
  EXPECT_GE(Id(m(), mjOBJ_CAMERA, "hoap3_left_eye"), 0);
  EXPECT_GE(Id(m(), mjOBJ_CAMERA, "hoap3_right_eye"), 0);
  EXPECT_GE(Id(m(), mjOBJ_CAMERA, "hoap3_watch"), 0);
}

// The SL default posture (rokv/hoap-sl SensorOffset.cf "default" column; legs only) is a
// mirror-symmetric stance with level soles. That holds only with the SL joint signs.
TEST_F(Hoap3Model, SlDefaultPostureHasLevelMirroredFeet) {
  const std::map<std::string, double> posture = {{"RL_J2", -0.09}, {"RL_J3", 0.16}, {"RL_J4", 0.52},  {"RL_J5", -0.35},
                                                 {"RL_J6", -0.09}, {"LL_J2", 0.09}, {"LL_J3", -0.16}, {"LL_J4", -0.52},
                                                 {"LL_J5", 0.35},  {"LL_J6", 0.09}};
  for (const auto& [joint, q] : posture) d()->qpos[QposAdr(m(), joint)] = q;
  mj_kinematics(m(), d());
  const Eigen::Matrix3d mirror = Eigen::Vector3d(1, -1, 1).asDiagonal();
  const int right = Id(m(), mjOBJ_BODY, "hoap3_r_foot"), left = Id(m(), mjOBJ_BODY, "hoap3_l_foot");
  for (int foot : {right, left}) {
    // sole normal within 1 deg of vertical (the column sums to 0.01 rad of pitch)
    EXPECT_GT(Mat3(d()->xmat + 9 * foot)(2, 2), std::cos(1.0 * M_PI / 180)) << mj_id2name(m(), mjOBJ_BODY, foot);
  }
  EXPECT_LT((BodyPos("hoap3_l_foot") - mirror * BodyPos("hoap3_r_foot")).norm(), 1e-9);
  // and what the signs mean: right knee flexion swings the foot back, hip flexion forward
  ResetToKey(m(), d(), "zero");
  const Eigen::Vector3d foot0 = BodyPos("hoap3_r_foot");
  d()->qpos[QposAdr(m(), "RL_J4")] = 0.5;
  mj_kinematics(m(), d());
  EXPECT_LT(BodyPos("hoap3_r_foot").x(), foot0.x() - 0.04);
  d()->qpos[QposAdr(m(), "RL_J4")] = 0;
  d()->qpos[QposAdr(m(), "RL_J3")] = 0.5;
  d()->qpos[QposAdr(m(), "LL_J3")] = -0.5;
  mj_kinematics(m(), d());
  EXPECT_GT(BodyPos("hoap3_r_foot").x(), foot0.x() + 0.09);
  EXPECT_NEAR(BodyPos("hoap3_l_foot").x(), BodyPos("hoap3_r_foot").x(), 1e-9);
  // RA_J1 = +90 deg hangs the right arm down; positive B_J bows forward
  d()->qpos[QposAdr(m(), "RA_J1")] = M_PI / 2;
  d()->qpos[QposAdr(m(), "B_J")] = 0.3;
  mj_kinematics(m(), d());
  EXPECT_LT(SitePos("hoap3_r_hand").z(), BodyPos("hoap3_r_shoulder").z() - 0.2);
  EXPECT_GT(BodyPos("hoap3_head").x(), 0.0);
}

TEST_F(Hoap3Model, StandKeyframeHasFlatFeetOnTheFloorAndTheComOverThem) {
  ResetToKey(m(), d(), "stand");
  std::vector<double> pad_x;
  for (int g = 0; g < m()->ngeom; ++g) {
    const char* name = mj_id2name(m(), mjOBJ_GEOM, g);
    if (name == nullptr || std::string(name).find("foot_") == std::string::npos) continue;
    EXPECT_NEAR(d()->geom_xpos[3 * g + 2] - m()->geom_size[3 * g], 0.0, 1e-5) << name;
    pad_x.push_back(d()->geom_xpos[3 * g]);
  }
  EXPECT_EQ(pad_x.size(), 8u);
  for (const char* foot : {"hoap3_r_foot", "hoap3_l_foot"}) {
    const Eigen::Matrix3d r = Mat3(d()->xmat + 9 * Id(m(), mjOBJ_BODY, foot));
    EXPECT_LT((r - Eigen::Matrix3d::Identity()).norm(), 1e-6) << foot << " not flat";
  }
  // COM ahead of the heel pads and behind the toe pads, between the feet
  const double com_x = d()->subtree_com[3 * 1], com_y = d()->subtree_com[3 * 1 + 1];
  EXPECT_GT(com_x - *std::min_element(pad_x.begin(), pad_x.end()), 0.02);
  EXPECT_GT(*std::max_element(pad_x.begin(), pad_x.end()) - com_x, 0.02);
  EXPECT_LT(std::abs(com_y), 0.005);
  for (int i = 0; i < d()->ncon; ++i) {
    EXPECT_NE(std::string(mj_id2name(m(), mjOBJ_GEOM, d()->contact[i].geom2)).find("foot_"), std::string::npos)
        << "only the FSR pads touch";
  }
}
}  // namespace
}  // namespace vlab::models::testing
