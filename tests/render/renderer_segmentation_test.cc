// Segmentation: each pixel holds the model geom id drawn there (-1: none);
// the ids agree with where the geoms are (projection, RGB colour) and map to
// their bodies.
#include <map>

#include <gtest/gtest.h>

#include "render/renderer.h"
#include "render_test_scene.h"

namespace vlab::render {
namespace {

using vlab::testing::Project;
using vlab::testing::RenderScene;

class SegmentationTest : public RenderScene {
 protected:
  void SetUp() override {
    RenderScene::SetUp();
    Place("ball", 0.2, 0.1, 0.5);
    Place("block", -0.3, -0.2, 0.3);
  }
  std::int32_t At(const SegmentationImage& seg, double u, double v) const {
    return seg.geom[static_cast<std::size_t>(std::lround(v)) * seg.width + std::lround(u)];
  }
};

TEST_F(SegmentationTest, IdsAreTheGeomsAtTheirProjections) {
  const int cam = CameraId(m_, "down");
  const int ball = Id(mjOBJ_GEOM, "ball"), block = Id(mjOBJ_GEOM, "block"), floor = Id(mjOBJ_GEOM, "floor");
  for (Profile profile : {Profile::kFast, Profile::kQuality}) {
    Renderer::Options options;
    options.profile = profile;
    options.log_renderer = false;
    auto r = Renderer::Create(m_, options);
    SegmentationImage seg;
    r->RenderSegmentation(d_, cam, &seg);
    ASSERT_EQ(seg.width, 640);
    ASSERT_EQ(seg.geom.size(), 640u * 480u);
    const Intrinsics k = CameraIntrinsics(m_, cam, 640, 480);
    double u = 0, v = 0;
    Project(d_, cam, k, d_->geom_xpos + 3 * ball, &u, &v);
    EXPECT_EQ(At(seg, u, v), ball);
    Project(d_, cam, k, d_->geom_xpos + 3 * block, &u, &v);
    EXPECT_EQ(At(seg, u, v), block);
    EXPECT_EQ(At(seg, 5, 5), floor);
    // only these three geoms are in view, and all of them are
    std::map<int, long> count;
    for (std::int32_t g : seg.geom) ++count[g];
    EXPECT_EQ(count.size(), 3u);
    EXPECT_GT(count[ball], 100);
    EXPECT_GT(count[block], 100);
    EXPECT_GT(count[floor], 300000);
  }
}

TEST_F(SegmentationTest, AgreesWithTheColourImage) {
  const int cam = CameraId(m_, "down");
  const int ball = Id(mjOBJ_GEOM, "ball"), block = Id(mjOBJ_GEOM, "block");
  Renderer::Options options;
  options.log_renderer = false;
  auto r = Renderer::Create(m_, options);
  RgbImage rgb;
  SegmentationImage seg;
  r->Render(d_, cam, &rgb);
  r->RenderSegmentation(d_, cam, &seg);
  // fast profile (no multisampling): the same pixel centres are covered in both passes
  long red = 0, blue = 0, red_ball = 0, blue_block = 0;
  for (std::size_t i = 0; i < seg.geom.size(); ++i) {
    const std::uint8_t* p = rgb.pixels.data() + 3 * i;
    const bool is_red = p[0] > 128 && p[1] < 64 && p[2] < 64;
    const bool is_blue = p[2] > 128 && p[0] < 64 && p[1] < 64;
    red += is_red;
    blue += is_blue;
    red_ball += is_red && seg.geom[i] == ball;
    blue_block += is_blue && seg.geom[i] == block;
  }
  ASSERT_GT(red, 100);
  ASSERT_GT(blue, 100);
  EXPECT_EQ(red_ball, red);
  EXPECT_EQ(blue_block, blue);
}

TEST_F(SegmentationTest, NothingDrawnIsMinusOneAndBodiesFollowGeoms) {
  const int cam = CameraId(m_, "tilted");  // sees past the floor's far edge
  Renderer::Options options;
  options.log_renderer = false;
  auto r = Renderer::Create(m_, options);
  SegmentationImage seg;
  r->RenderSegmentation(d_, cam, &seg);
  EXPECT_EQ(seg.geom[5], -1);  // top-left corner: beyond the floor
  std::vector<std::int32_t> bodies;
  GeomsToBodies(m_, seg, &bodies);
  ASSERT_EQ(bodies.size(), seg.geom.size());
  const int cart_geom = Id(mjOBJ_GEOM, "cart"), cart_body = Id(mjOBJ_BODY, "cart");
  long cart = 0;
  for (std::size_t i = 0; i < seg.geom.size(); ++i) {
    EXPECT_EQ(bodies[i], seg.geom[i] < 0 ? -1 : m_->geom_bodyid[seg.geom[i]]);
    cart += seg.geom[i] == cart_geom;
    if (seg.geom[i] == cart_geom) {
      ASSERT_EQ(bodies[i], cart_body);
    }
  }
  EXPECT_GT(cart, 0) << "the cart should be in the tilted camera's view";
}

}  // namespace
}  // namespace vlab::render
