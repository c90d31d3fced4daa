// Depth: metres along the optical axis, equal to the analytic distance to the
// plane z = 0 within 1 mm at every pixel that sees it (camera facing it, and
// camera tilted 45 degrees), +infinity where nothing was drawn.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "render/renderer.h"
#include "render_test_scene.h"

namespace vlab::render {
namespace {

using vlab::testing::RenderScene;

constexpr double kTolerance_m = 1e-3;

class DepthTest : public RenderScene {
 protected:
  void SetUp() override {
    RenderScene::SetUp();
    Place("ball", 0, 0, -1);  // under the floor slab: out of sight
    Place("block", 0.1, 0, -1);
  }

  // z (optical axis) of the point where the ray through pixel (u, v) meets the plane z_W = 0; NaN if it does not
  double PlaneDepth(int cam, const Intrinsics& k, int u, int v) const {
    const double* pos = d_->cam_xpos + 3 * cam;
    const double* R = d_->cam_xmat + 9 * cam;
    const double x = (u - k.cx) / k.fx, y = (v - k.cy) / k.fy;  // ray (x, y, 1) in the OpenCV camera frame
    // world direction: camera x * x - camera y(up) * y - camera z(back) * 1
    const double dz_W = R[6] * x - R[7] * y - R[8];
    if (dz_W >= 0) return std::nan("");
    return -pos[2] / dz_W;
  }
};

TEST_F(DepthTest, FrontoParallelPlaneAtTwoMetres) {
  for (Profile profile : {Profile::kFast, Profile::kQuality}) {
    Renderer::Options options;
    options.profile = profile;
    options.log_renderer = false;
    auto r = Renderer::Create(m_, options);
    RgbImage rgb;
    DepthImage depth;
    r->Render(d_, CameraId(m_, "down"), &rgb, &depth);
    ASSERT_EQ(depth.width, 640);
    ASSERT_EQ(depth.height, 480);
    ASSERT_EQ(depth.metres.size(), 640u * 480u);
    double worst = 0;
    for (float z : depth.metres) worst = std::max(worst, std::abs(z - 2.0));
    EXPECT_LT(worst, kTolerance_m) << ProfileName(profile);
  }
}

TEST_F(DepthTest, TiltedPlaneMatchesTheRayIntersection) {
  const int cam = CameraId(m_, "tilted");
  const int floor = Id(mjOBJ_GEOM, "floor");
  for (Profile profile : {Profile::kFast, Profile::kQuality}) {
    Renderer::Options options;
    options.profile = profile;
    options.log_renderer = false;
    auto r = Renderer::Create(m_, options);
    for (auto [w, h] : {std::pair{640, 480}, std::pair{320, 240}}) {
      RgbImage rgb;
      rgb.width = w;
      rgb.height = h;
      DepthImage depth;
      SegmentationImage seg;
      seg.width = w;
      seg.height = h;
      r->Render(d_, cam, &rgb, &depth);
      r->RenderSegmentation(d_, cam, &seg);
      ASSERT_EQ(depth.width, w);
      const Intrinsics k = CameraIntrinsics(m_, cam, w, h);
      const int width = w;  // (a lambda captures a structured binding only from C++20)
      auto at = [&seg, width](int u, int v) { return seg.geom[static_cast<std::size_t>(v) * width + u]; };
      long checked = 0, sky = 0;
      double worst = 0;
      for (int v = 1; v < h - 1; ++v) {
        for (int u = 1; u < w - 1; ++u) {
          const float z = depth.metres[static_cast<std::size_t>(v) * w + u];
          // multisampled depth is resolved from one sample of a pixel, the segmentation from its
          // centre: with multisampling, compare away from outlines (3 x 3 neighbourhood alike)
          bool alike = true;
          for (int dv = -1; dv <= 1; ++dv) {
            for (int du = -1; du <= 1; ++du) alike = alike && at(u + du, v + dv) == at(u, v);
          }
          if (profile == Profile::kQuality && !alike) continue;
          if (at(u, v) == -1) {
            EXPECT_TRUE(std::isinf(z)) << ProfileName(profile) << " " << w << "x" << h << " at " << u << ", " << v;
            ++sky;
            continue;
          }
          if (at(u, v) != floor) continue;
          const double expected = PlaneDepth(cam, k, u, v);
          ASSERT_FALSE(std::isnan(expected)) << u << ", " << v;
          worst = std::max(worst, std::abs(z - expected));
          ++checked;
        }
      }
      EXPECT_LT(worst, kTolerance_m) << ProfileName(profile) << " " << w << "x" << h;
      EXPECT_GT(checked, w * h / 2) << "the floor should fill most of the view";
      EXPECT_GT(sky, 0) << "the view should reach beyond the floor's far edge";
    }
  }
}

TEST_F(DepthTest, NearerObjectsAreNearer) {
  // the blue box's top face at z = 0.63 under the "down" camera: 1.37 m away
  Place("block", 0.0, 0.0, 0.6);
  Renderer::Options options;
  options.log_renderer = false;
  auto r = Renderer::Create(m_, options);
  RgbImage rgb;
  DepthImage depth;
  r->Render(d_, CameraId(m_, "down"), &rgb, &depth);
  EXPECT_NEAR(depth.metres[240 * 640 + 320], 2.0 - 0.63, kTolerance_m);
}

}  // namespace
}  // namespace vlab::render
