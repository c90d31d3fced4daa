// An arm's start (device_arm.h, arm_welded.h): `initial_jitter` draws each joint uniform in
// initial +- jitter from the device's seed (the same seed the same start, another seed
// another, every joint within its bound), its errors; and with `initial` the gripper welded
// to the arm starts where its weld puts it: checked against the scene's own frames (the
// gripper's mounting site on the pointer's tool site, as scenes/pa10_gripper.xml's weld
// says), and by stepping: a gripper left at its place in the model would be snapped over a
// metre (0.99 m here) by the weld, one put there stays within 0.1 mm.
#include <cmath>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "arm_keys_error.h"
#include "core/core_errors.h"
#include "core/core_mujoco.h"
#include "lab/run/lab_runner.h"
#include "lab/scenario/lab_scenario.h"
#include "test_util.h"

namespace vlab::lab::arm_initial_test {
namespace {

using vlab::testing::TempDir;
using vlab::testing::WriteFile;

const std::string kScene = VLAB_SOURCE_DIR "/scenes/pa10_handover.xml";
const double kPark[7] = {0, -0.698132, 0, 1.919862, 0, 1.919862, 0};  // rad

// the two-arm scene, arm A with `initial` park and the given extra key lines (4 spaces),
// arm B at the model's zero pose
Scenario TwoArms(const std::string& a_keys, unsigned long long seed) {
  TempDir dir;
  WriteFile(dir / "s.yaml", "scene: " + kScene +
                                "\nduration: 0.1\ncontrol_period: 0.01\ndevices:\n"
                                "  - name: arm_a\n    kind: arm\n"
                                "    joints: [a_S1, a_S2, a_S3, a_E1, a_E2, a_W1, a_W2]\n"
                                "    initial: [0, -0.698132, 0, 1.919862, 0, 1.919862, 0]\n" +
                                a_keys +
                                "  - name: arm_b\n    kind: arm\n"
                                "    joints: [b_S1, b_S2, b_S3, b_E1, b_E2, b_W1, b_W2]\n");
  Scenario s = LoadScenario(dir / "s.yaml");
  s.seed = seed;
  return s;
}

// arm A's joints at the start of a lab made from `s`
Eigen::VectorXd StartOf(const Scenario& s) {
  const auto lab = Lab::Create(s);
  DataPtr d = MakeData(lab->model());
  lab->InitialState(d.get());
  Eigen::VectorXd q(7);
  for (int i = 0; i < 7; ++i) q[i] = d->qpos[i];  // a_S1..a_W2 are qpos 0-6 (the scene's comment)
  return q;
}

std::string CreateError(const Scenario& s) {
  try {
    Lab::Create(s);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(ArmInitialTest, JitterIsSeededAndWithinItsBound) {
  const Eigen::VectorXd one = StartOf(TwoArms("    initial_jitter: 0.05\n", 1));
  EXPECT_EQ(one, StartOf(TwoArms("    initial_jitter: 0.05\n", 1)));  // same seed, same start
  const Eigen::VectorXd two = StartOf(TwoArms("    initial_jitter: 0.05\n", 2));
  double largest = 0;
  for (int i = 0; i < 7; ++i) {
    EXPECT_LE(std::abs(one[i] - kPark[i]), 0.05) << i;
    EXPECT_LE(std::abs(two[i] - kPark[i]), 0.05) << i;
    EXPECT_NE(one[i], two[i]) << i;  // another seed moves every joint elsewhere
    largest = std::max(largest, std::abs(one[i] - kPark[i]));
  }
  EXPECT_GT(largest, 0.01);  // 7 draws uniform in +-0.05 rad: not all within 0.01 (p = 0.2^7)
  // one value per joint: a joint without jitter starts exactly at `initial`
  const Eigen::VectorXd per_joint = StartOf(TwoArms("    initial_jitter: [0, 0.1, 0, 0, 0, 0, 0]\n", 3));
  for (int i = 0; i < 7; ++i) {
    if (i == 1) {
      EXPECT_NE(per_joint[i], kPark[i]);
      EXPECT_LE(std::abs(per_joint[i] - kPark[i]), 0.1);
    } else {
      EXPECT_EQ(per_joint[i], kPark[i]) << i;
    }
  }
  // no jitter: `initial` as given
  const Eigen::VectorXd plain = StartOf(TwoArms("", 1));
  for (int i = 0; i < 7; ++i) EXPECT_EQ(plain[i], kPark[i]);
}

TEST(ArmInitialTest, JitterErrors) {
  EXPECT_NE(ArmKeysError("    initial_jitter: 0.1\n").find("initial_jitter: needs initial"), std::string::npos);
  EXPECT_NE(
      ArmKeysError("    initial: [0, 0]\n    initial_jitter: [0.1, 0.1, 0.1]\n").find("one value or one per joint (2)"),
      std::string::npos);
  EXPECT_NE(ArmKeysError("    initial: [0, 0]\n    initial_jitter: -0.1\n").find("values must be 0 to pi rad"),
            std::string::npos);
  EXPECT_NE(ArmKeysError("    initial: [0, 0]\n    initial_jitter: nan\n").find("initial_jitter"), std::string::npos);
  EXPECT_EQ(ArmKeysError("    initial: [0, 0]\n    initial_jitter: [0, 0.2]\n"), "");
  // park's S2 is -40 deg, 54 deg from its -94 deg limit: 1 rad (57 deg) could leave the range
  const std::string e = CreateError(TwoArms("    initial_jitter: [0, 1.0, 0, 0, 0, 0, 0]\n", 1));
  EXPECT_NE(e.find("device 'arm_a': initial_jitter: joint 'a_S2' could start outside its range"), std::string::npos)
      << e;
}

// the gripper's mounting frame on the tool site (the weld: relpose 0.165 m along tool_body's z,
// where the tool site is), position and rotation
void ExpectMounted(const mjModel* m, const mjData* d, const char* tool, const char* mount, double tol) {
  const int t = mj_name2id(m, mjOBJ_SITE, tool), g = mj_name2id(m, mjOBJ_SITE, mount);
  ASSERT_GE(t, 0);
  ASSERT_GE(g, 0);
  const Eigen::Vector3d p_t(d->site_xpos + 3 * t), p_g(d->site_xpos + 3 * g);
  EXPECT_LT((p_t - p_g).norm(), tol) << mount;
  const Eigen::Matrix3d R_t = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(d->site_xmat + 9 * t);
  const Eigen::Matrix3d R_g = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(d->site_xmat + 9 * g);
  EXPECT_LT(Eigen::AngleAxisd(R_t.transpose() * R_g).angle(), tol / 0.1) << mount;  // rad
}

TEST(ArmInitialTest, WeldedGripperStartsOnItsMount) {
  // arm A from park with jitter (its gripper placed), arm B from the model's zero pose (no
  // `initial`: its gripper is where the model puts it, on its mount too)
  const auto lab = Lab::Create(TwoArms("    initial_jitter: 0.05\n", 5));
  const mjModel* m = lab->model();
  DataPtr d = MakeData(m);
  lab->InitialState(d.get());
  ExpectMounted(m, d.get(), "a_tool", "a_gripper_mount", 1e-12);
  ExpectMounted(m, d.get(), "b_tool", "b_gripper_mount", 1e-12);
  // the model's own place of A's gripper (the zero pose's pointer tip, 1.535 m up) is far away
  const int body = mj_name2id(m, mjOBJ_BODY, "a_gripper");
  EXPECT_GT((Eigen::Vector3d(d->qpos + m->jnt_qposadr[m->body_jntadr[body]]) - Eigen::Vector3d(m->body_pos + 3 * body))
                .norm(),
            0.9);  // m: 0.99 here
  // 0.1 s with the arms passive: the weld holds the gripper where it was put (within 0.1 mm
  // of its mount: the arm sags under the gripper's weight meanwhile, the weld follows)
  for (int i = 0; i < 100; ++i) mj_step(m, d.get());
  ExpectMounted(m, d.get(), "a_tool", "a_gripper_mount", 1e-4);
}

}  // namespace
}  // namespace vlab::lab::arm_initial_test
