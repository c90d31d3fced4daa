// The cube scene (vision_scene.h): seeded placements that respect the table,
// the keep-out circle and each other; the committed scenes/pa10_cubes.xml
// loads cleanly with the cubes resting on the table; and its webcam sees the
// cubes: markers located in the world frame through the camera's pose agree
// with MuJoCo's cube poses.
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <opencv2/imgproc.hpp>

#include "core/core_errors.h"
#include "mujoco_fixture.h"
#include "render/renderer.h"
#include "vision/vision_locate.h"
#include "vision/vision_scene.h"

namespace vlab::vision::scene_test {
namespace {

TEST(CubeScene, PlacementsRespectTableKeepOutAndEachOther) {
  const CubeSetConfig cubes;
  CubeSceneConfig scene;
  const double radius = cubes.size_m * std::sqrt(0.5);
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    scene.seed = seed;
    const std::vector<CubePlacement> p = PlaceCubes(cubes, scene);
    ASSERT_EQ(p.size(), 6u);
    for (std::size_t i = 0; i < p.size(); ++i) {
      const Eigen::Vector3d& c = p[i].position;
      EXPECT_GE(c.x() - radius, scene.x_min);
      EXPECT_LE(c.x() + radius, scene.x_max);
      EXPECT_GE(c.y() - radius, scene.y_min);
      EXPECT_LE(c.y() + radius, scene.y_max);
      EXPECT_GE((c.head<2>() - scene.keep_out_xy).norm(), scene.keep_out_radius + radius);
      EXPECT_DOUBLE_EQ(c.z(), scene.table_top_z + cubes.size_m / 2 + scene.drop_m);
      EXPECT_LT(scene.drop_m, 0.001);
      // the face drawn to rest on the table points down; the cube is upright otherwise
      const Eigen::Vector3d down = p[i].orientation * CubeMarkerFrame(cubes, p[i].face_down).linear().col(2);
      EXPECT_TRUE(down.isApprox(-Eigen::Vector3d::UnitZ(), 1e-9)) << "seed " << seed << " cube " << i;
      EXPECT_GE(p[i].orientation.w(), 0.0);
      for (std::size_t j = 0; j < i; ++j) {
        EXPECT_GE((c.head<2>() - p[j].position.head<2>()).norm(), 2 * radius + scene.min_gap_m);
      }
    }
  }
}

TEST(CubeScene, SeededAndVaried) {
  const CubeSetConfig cubes;
  CubeSceneConfig scene;
  scene.seed = 7;
  const auto a = PlaceCubes(cubes, scene), b = PlaceCubes(cubes, scene);
  scene.seed = 8;
  const auto c = PlaceCubes(cubes, scene);
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].position, b[i].position);
    EXPECT_EQ(a[i].orientation.coeffs(), b[i].orientation.coeffs());
    EXPECT_NE(a[i].position, c[i].position);
  }
  // over many cubes every face comes down and yaws spread over the circle
  int faces[kCubeFaces] = {};
  double yaw_min = 360, yaw_max = 0;
  for (std::uint64_t seed = 1; seed <= 30; ++seed) {
    scene.seed = seed;
    for (const CubePlacement& p : PlaceCubes(cubes, scene)) {
      ++faces[p.face_down];
      yaw_min = std::min(yaw_min, p.yaw_deg);
      yaw_max = std::max(yaw_max, p.yaw_deg);
    }
  }
  for (int f = 0; f < kCubeFaces; ++f) EXPECT_GT(faces[f], 10) << f;
  EXPECT_LT(yaw_min, 20);
  EXPECT_GT(yaw_max, 340);
}

TEST(CubeScene, RefusesWhatDoesNotFit) {
  CubeSetConfig cubes;
  CubeSceneConfig scene;
  scene.count = 7;
  EXPECT_THROW(PlaceCubes(cubes, scene), vlab::InputError);
  cubes.size_m = 0.2;
  scene.count = 6;
  try {
    PlaceCubes(cubes, scene);
    FAIL();
  } catch (const vlab::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("do not fit the table's free area"), std::string::npos) << e.what();
  }
}

class CommittedCubeScene : public vlab::test::MujocoTest {
 protected:
  void SetUp() override {
    m_ = LoadModel("scenes/pa10_cubes.xml");
    d_ = MakeData(m_);
    mj_forward(m_, d_);
  }
  Eigen::Isometry3d BodyPose(const std::string& name) const {
    const int b = mj_name2id(m_, mjOBJ_BODY, name.c_str());
    EXPECT_GE(b, 0) << name;
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = Eigen::Quaterniond(d_->xquat[4 * b], d_->xquat[4 * b + 1], d_->xquat[4 * b + 2], d_->xquat[4 * b + 3])
                     .toRotationMatrix();
    X.translation() = Eigen::Vector3d(d_->xpos[3 * b], d_->xpos[3 * b + 1], d_->xpos[3 * b + 2]);
    return X;
  }

  CubeSetConfig cubes_;
  mjModel* m_ = nullptr;
  mjData* d_ = nullptr;
};

TEST_F(CommittedCubeScene, CubesSettleOnTheTableApart) {
  // 0.6 s to settle from their 0.1 mm drop into the soft contact (the arm,
  // straight up in its zero pose, balances without torque and stays clear)
  for (int i = 0; i < 600; ++i) mj_step(m_, d_);
  const int table = mj_name2id(m_, mjOBJ_GEOM, "table_top");
  int on_table = 0;
  for (int i = 0; i < d_->ncon; ++i) {
    const mjContact& c = d_->contact[i];
    const std::string a = mj_id2name(m_, mjOBJ_GEOM, c.geom1), b = mj_id2name(m_, mjOBJ_GEOM, c.geom2);
    const bool cube_a = a.rfind("cube_", 0) == 0, cube_b = b.rfind("cube_", 0) == 0;
    EXPECT_FALSE(cube_a && cube_b) << a << " touches " << b;
    if ((cube_a && c.geom2 == table) || (cube_b && c.geom1 == table)) {
      ++on_table;
      EXPECT_NEAR(c.dist, 0.0, 0.001);
    }
  }
  EXPECT_EQ(on_table, 6 * 4);  // each on a face: 4 contacts per cube
  // and at rest: the next 0.5 s moves none by more than 0.01 mm or 0.01 deg
  std::vector<Eigen::Isometry3d> before;
  for (int c = 0; c < 6; ++c) before.push_back(BodyPose(CubeName(cubes_, c)));
  for (int i = 0; i < 500; ++i) mj_step(m_, d_);
  for (int c = 0; c < 6; ++c) {
    const Eigen::Isometry3d now = BodyPose(CubeName(cubes_, c));
    EXPECT_LT((now.translation() - before[static_cast<std::size_t>(c)].translation()).norm(), 1e-5) << c;
    EXPECT_LT(RotationAngleDeg(now.linear(), before[static_cast<std::size_t>(c)].linear()), 0.01) << c;
  }
}

TEST_F(CommittedCubeScene, WebcamLocatesTheCubesInTheWorld) {
  const int cam = mj_name2id(m_, mjOBJ_CAMERA, "webcam");
  ASSERT_GE(cam, 0);
  render::Renderer::Options options;
  options.profile = render::Profile::kFast;
  options.log_renderer = false;
  auto renderer = render::Renderer::Create(m_, options);
  render::RgbImage rgb;
  renderer->Render(d_, cam, &rgb);
  cv::Mat grey;
  cv::cvtColor(cv::Mat(rgb.height, rgb.width, CV_8UC3, rgb.pixels.data()), grey, cv::COLOR_RGB2GRAY);

  const render::Intrinsics k = render::CameraIntrinsics(m_, cam, 640, 480);
  const CameraModel camera{640, 480, k.fx, k.fy, k.cx, k.cy, {}};
  Eigen::Isometry3d X_world_camera = Eigen::Isometry3d::Identity();
  Eigen::Matrix3d R;
  for (int i = 0; i < 9; ++i) R(i / 3, i % 3) = d_->cam_xmat[9 * cam + i];
  X_world_camera.linear() = R * Eigen::Vector3d(1, -1, -1).asDiagonal();  // MuJoCo -> OpenCV camera axes
  X_world_camera.translation() =
      Eigen::Vector3d(d_->cam_xpos[3 * cam], d_->cam_xpos[3 * cam + 1], d_->cam_xpos[3 * cam + 2]);

  MarkerTable table;
  std::vector<bridge::MarkerDescriptionMsg> all;
  for (int id = 0; id < 36; ++id) all.push_back({0, id, CubeMarkerSide(cubes_)});
  ASSERT_TRUE(table.Apply(all));
  bridge::MarkersStateMsg state;
  std::vector<MarkerPose> poses;
  LocateMarkers(grey, camera, X_world_camera, table, MarkerDetector(), &state, &poses);

  int valid = 0;
  bool seen[6] = {};
  for (std::size_t i = 0; i < state.markers.size(); ++i) {
    const bridge::MarkerRecordMsg& r = state.markers[i];
    ASSERT_TRUE(r.world_valid);
    if (!r.valid) continue;
    ++valid;
    const int cube = r.id / kCubeFaces, face = r.id % kCubeFaces;
    seen[cube] = true;
    const Eigen::Isometry3d truth = BodyPose(CubeName(cubes_, cube)) * CubeMarkerFrame(cubes_, face);
    Eigen::Matrix4d T;
    for (int j = 0; j < 16; ++j) T(j / 4, j % 4) = r.T_world[j];
    // 0.6-0.8 m away: a few mm and a degree at most
    EXPECT_LT((T.block<3, 1>(0, 3) - truth.translation()).norm(), 0.003) << "marker " << r.id;
    EXPECT_LT(RotationAngleDeg(T.block<3, 3>(0, 0), truth.linear()), 1.0) << "marker " << r.id;
  }
  std::printf("webcam at t = 0: %zu markers of the cubes located, %d valid\n", state.markers.size(), valid);
  for (int cube = 0; cube < 6; ++cube) EXPECT_TRUE(seen[cube]) << "no valid marker of " << CubeName(cubes_, cube);
}

}  // namespace
}  // namespace vlab::vision::scene_test
