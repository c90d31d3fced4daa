// scenes/pa10_cubes_gripper.xml and scenes/pa10_blocks_gripper.xml (the same lab,
// scenes/cubes_lab/, with the lettered cubes or the alphabet blocks): the numbers their comments state. The keyframe's gripper sits
// at the weld's pose (else the weld snaps it on the first steps); the slots are 70 mm apart on
// the table in the reading frame; the webcam sees the slots in reading order and the whole
// placement area, and not the gripper of the parked arm.
#include <algorithm>
#include <cmath>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "mujoco_fixture.h"

namespace vlab::test {
namespace {

constexpr double kTableTop = 0.20;   // m, the scene's table
constexpr double kHalfEdge = 0.025;  // m, 50 mm cubes
constexpr double kPitch = 0.07;      // m, between slots

class CubesSceneTest : public MujocoTest, public ::testing::WithParamInterface<const char*> {
 protected:
  void SetUp() override {
    m_ = LoadModel(GetParam());
    d_ = MakeData(m_);
    const int key = mj_name2id(m_, mjOBJ_KEY, "park");
    ASSERT_GE(key, 0);
    mj_resetDataKeyframe(m_, d_, key);
    mj_forward(m_, d_);
  }
  int Id(mjtObj type, const char* name) {
    const int id = mj_name2id(m_, type, name);
    EXPECT_GE(id, 0) << name;
    return id;
  }
  // image coordinates in [-1, 1] (x right, y up) of a world point through the webcam;
  // false when it lies behind the camera
  bool Project(const Eigen::Vector3d& p_W, Eigen::Vector2d* uv) {
    const int cam = Id(mjOBJ_CAMERA, "webcam");
    const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> R_WC(d_->cam_xmat + 9 * cam);
    const Eigen::Vector3d p_C = R_WC.transpose() * (p_W - Eigen::Vector3d(d_->cam_xpos + 3 * cam));
    if (p_C.z() >= 0) return false;  // MuJoCo cameras look along their -z
    const double tan_v = std::tan(m_->cam_fovy[cam] * M_PI / 360), tan_h = tan_v * 640.0 / 480.0;
    *uv = Eigen::Vector2d(p_C.x() / -p_C.z() / tan_h, p_C.y() / -p_C.z() / tan_v);
    return true;
  }
  mjModel* m_ = nullptr;
  mjData* d_ = nullptr;
};

TEST_P(CubesSceneTest, KeyframeGripperSitsAtTheWeld) {
  // gripper frame = tool site frame (equality gripper_mount, relpose 0 0 0.165 from tool_body)
  const int tool = Id(mjOBJ_SITE, "tool");
  const int gripper = Id(mjOBJ_BODY, "gripper");
  const Eigen::Vector3d p_tool(d_->site_xpos + 3 * tool), p_gripper(d_->xpos + 3 * gripper);
  EXPECT_LT((p_tool - p_gripper).norm(), 1e-6);  // the keyframe's numbers carry 6 decimals
  const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> R_tool(d_->site_xmat + 9 * tool);
  const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> R_gripper(d_->xmat + 9 * gripper);
  EXPECT_LT((R_tool - R_gripper).norm(), 1e-6);
  // tool straight down, jaws open 68 mm
  EXPECT_NEAR(R_tool(2, 2), -1, 1e-9);
  EXPECT_NEAR(d_->qpos[14] + d_->qpos[15], 0.068, 1e-12);
}

TEST_P(CubesSceneTest, SlotsSpellAlongTheReadingFrame) {
  for (int k = 1; k <= 4; ++k) {
    const int slot = Id(mjOBJ_SITE, ("slot_" + std::to_string(k)).c_str());
    const Eigen::Vector3d p(d_->site_xpos + 3 * slot);
    const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> R(d_->site_xmat + 9 * slot);
    EXPECT_NEAR(p.z(), kTableTop + kHalfEdge, 1e-9);                 // a resting cube's centre
    EXPECT_NEAR(p.y(), (k - 2.5) * kPitch, 1e-9);                    // 70 mm apart, centred on y = 0
    EXPECT_LT((R.col(0) - Eigen::Vector3d(0, 1, 0)).norm(), 1e-6);   // reading direction: world +y
    EXPECT_LT((R.col(1) - Eigen::Vector3d(-1, 0, 0)).norm(), 1e-6);  // the letter's up: toward the arm
  }
}

TEST_P(CubesSceneTest, WebcamReadsTheWordLeftToRightAndUpright) {
  double previous_u = -2;
  for (int k = 1; k <= 4; ++k) {
    const int slot = Id(mjOBJ_SITE, ("slot_" + std::to_string(k)).c_str());
    const Eigen::Vector3d p(d_->site_xpos + 3 * slot);
    const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> R(d_->site_xmat + 9 * slot);
    Eigen::Vector2d uv, up_uv;
    ASSERT_TRUE(Project(p, &uv));
    ASSERT_TRUE(Project(p + 0.02 * R.col(1), &up_uv));
    EXPECT_LT(uv.cwiseAbs().maxCoeff(), 1.0) << "slot " << k << " outside the image";
    EXPECT_GT(uv.x(), previous_u);  // slot k right of slot k - 1
    EXPECT_GT(up_uv.y(), uv.y());   // the letter's up points up in the image
    previous_u = uv.x();
  }
  // a placement area that holds cases/cubes' (stage1.yaml: x 0.45 .. 0.80, y -0.33 .. 0.33):
  // region x 0.40 .. 0.80, y -0.35 .. 0.35, centres a footprint (35.4 mm) inside it and within
  // 0.78 m of the base axis: the top faces' outer edges at the extreme centres are in the picture
  // (in the picture, not necessarily with a valid marker: see cases/cubes/stage1.yaml)
  const double inset = kHalfEdge * std::sqrt(2.0);
  for (const Eigen::Vector2d& centre : {Eigen::Vector2d(0.40 + inset, 0.35 - inset),
                                        Eigen::Vector2d(0.70, 0.35 - inset), Eigen::Vector2d(0.765, 0.15)}) {
    ASSERT_LE(centre.norm(), 0.78);
    for (const double side : {-1.0, 1.0}) {
      for (const Eigen::Vector2d& edge : {Eigen::Vector2d(0, side * kHalfEdge), Eigen::Vector2d(kHalfEdge, 0)}) {
        const Eigen::Vector2d xy(centre.x() + edge.x(), side * centre.y() + edge.y());
        Eigen::Vector2d uv;
        ASSERT_TRUE(Project(Eigen::Vector3d(xy.x(), xy.y(), kTableTop + 2 * kHalfEdge), &uv));
        EXPECT_LT(uv.cwiseAbs().maxCoeff(), 1.0) << xy.transpose() << " outside the image";
      }
    }
  }
}

TEST_P(CubesSceneTest, ParkedGripperIsOutOfThePicture) {
  // every corner of every gripper geom's bounding box (the jaws' tips included)
  const int gripper = Id(mjOBJ_BODY, "gripper");
  int checked = 0;
  for (int g = 0; g < m_->ngeom; ++g) {
    int b = m_->geom_bodyid[g];
    while (b != 0 && b != gripper) b = m_->body_parentid[b];
    if (b != gripper) continue;
    const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> R(d_->geom_xmat + 9 * g);
    const Eigen::Vector3d size(m_->geom_size + 3 * g);
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3d c((corner & 1 ? 1 : -1) * size.x(), (corner & 2 ? 1 : -1) * size.y(),
                              (corner & 4 ? 1 : -1) * size.z());
      Eigen::Vector2d uv;
      if (Project(Eigen::Vector3d(d_->geom_xpos + 3 * g) + R * c, &uv)) {
        EXPECT_GT(uv.cwiseAbs().maxCoeff(), 1.0) << "geom " << mj_id2name(m_, mjOBJ_GEOM, g) << " in the picture";
      }
      ++checked;
    }
  }
  EXPECT_GT(checked, 8);
}

INSTANTIATE_TEST_SUITE_P(Scenes, CubesSceneTest,
                         ::testing::Values("scenes/pa10_cubes_gripper.xml", "scenes/pa10_blocks_gripper.xml"));

// the blocks scene: six alphabet blocks, each naming its six face letters for the word device
// (mjcf/cubes/blocks/README.md), every letter A-Z and 0-9 once
class BlocksSceneTest : public MujocoTest {};

TEST_F(BlocksSceneTest, EveryBlockNamesItsFaceLetters) {
  const mjModel* m = LoadModel("scenes/pa10_blocks_gripper.xml");
  std::string all;
  for (const char* block : {"AGMSY4", "BHNTZ5", "CIOU06", "DJPV17", "EKQW28", "FLRX39"}) {
    const std::string body = std::string("cube_") + block;
    EXPECT_GE(mj_name2id(m, mjOBJ_BODY, body.c_str()), 0) << body;
    const int text = mj_name2id(m, mjOBJ_TEXT, (body + ".faces").c_str());
    ASSERT_GE(text, 0) << body;
    EXPECT_EQ(std::string(m->text_data + m->text_adr[text]), block);
    all += block;
  }
  std::sort(all.begin(), all.end());
  EXPECT_EQ(all, "0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZ");
}

}  // namespace
}  // namespace vlab::test
