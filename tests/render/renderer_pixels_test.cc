// Pixel facts: a small red ball appears where the pinhole projection with
// CameraIntrinsics puts it (centroid within 1 px), for a fixed camera, a
// camera carried by a moving body, every profile and two image sizes. The
// draft profile draws no sky, and spheres with 16 slices instead of 28.
#include <cmath>

#include <gtest/gtest.h>

#include "render/renderer.h"
#include "render_test_scene.h"

namespace vlab::render {
namespace {

using vlab::testing::Project;
using vlab::testing::RenderScene;

struct Centroid {
  double u = 0, v = 0;
  int pixels = 0;
};

// centroid of the saturated red pixels (the emissive ball)
Centroid RedCentroid(const RgbImage& img) {
  Centroid c;
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      const std::uint8_t* p = img.pixels.data() + 3 * (static_cast<std::size_t>(y) * img.width + x);
      if (p[0] > 128 && p[1] < 64 && p[2] < 64) {
        c.u += x;
        c.v += y;
        ++c.pixels;
      }
    }
  }
  if (c.pixels) {
    c.u /= c.pixels;
    c.v /= c.pixels;
  }
  return c;
}

class PixelTest : public RenderScene {
 protected:
  // renders `camera` and checks the ball's centroid against its projection
  void ExpectBallAtProjection(Renderer& r, const char* camera, int width, int height) {
    const int cam = CameraId(m_, camera);
    RgbImage img;
    img.width = width;
    img.height = height;
    r.Render(d_, cam, &img);
    ASSERT_EQ(img.width, width);
    ASSERT_EQ(img.pixels.size(), static_cast<std::size_t>(width) * height * 3);
    const Intrinsics k = CameraIntrinsics(m_, cam, width, height);
    double u = 0, v = 0;
    Project(d_, cam, k, d_->xpos + 3 * Id(mjOBJ_BODY, "ball"), &u, &v);
    const Centroid c = RedCentroid(img);
    ASSERT_GT(c.pixels, 10) << camera << ": ball not visible; projected at " << u << ", " << v;
    EXPECT_NEAR(c.u, u, 1.0) << camera << " " << width << "x" << height;
    EXPECT_NEAR(c.v, v, 1.0) << camera << " " << width << "x" << height;
  }
};

TEST_F(PixelTest, IntrinsicsFollowFovy) {
  const Intrinsics k = CameraIntrinsics(m_, CameraId(m_, "tilted"), 640, 480);
  EXPECT_NEAR(k.fy, 240 / std::tan(30 * M_PI / 180), 1e-9);
  EXPECT_EQ(k.fx, k.fy);
  EXPECT_EQ(k.cx, 319.5);
  EXPECT_EQ(k.cy, 239.5);
}

TEST_F(PixelTest, BallAtItsProjectionInAFixedCamera) {
  for (Profile profile : {Profile::kDraft, Profile::kFast, Profile::kQuality}) {
    Renderer::Options options;
    options.profile = profile;
    options.log_renderer = false;
    auto r = Renderer::Create(m_, options);
    // centre, off-centre in each quadrant, near a corner
    const double places[][3] = {{0, 0, 0.5}, {0.2, 0.1, 0.5}, {-0.35, 0.2, 0.3}, {0.3, -0.25, 0.8}, {0.55, 0.4, 0.2}};
    for (const auto& p : places) {
      Place("ball", p[0], p[1], p[2]);
      ExpectBallAtProjection(*r, "down", 640, 480);
      ExpectBallAtProjection(*r, "down", 320, 240);
      ExpectBallAtProjection(*r, "tilted", 640, 480);
    }
  }
}

TEST_F(PixelTest, BallAtItsProjectionInACarriedCamera) {
  Renderer::Options options;
  options.log_renderer = false;
  auto r = Renderer::Create(m_, options);
  const int x = m_->jnt_qposadr[Id(mjOBJ_JOINT, "cart_x")];
  const int yaw = m_->jnt_qposadr[Id(mjOBJ_JOINT, "cart_yaw")];
  Place("ball", 0.1, 0.2, 0.5);
  double u_first = 0;
  for (int i = 0; i < 5; ++i) {
    // the cart moves and turns: the camera's pose changes, so does the image
    d_->qpos[x] = -0.2 + 0.1 * i;
    d_->qpos[yaw] = 0.15 - 0.075 * i;  // both motions move the ball the same way in the image
    mj_forward(m_, d_);
    ExpectBallAtProjection(*r, "carried", 640, 480);
    RgbImage img;
    r->Render(d_, CameraId(m_, "carried"), &img);
    const double u = RedCentroid(img).u;
    if (i == 0) u_first = u;
    if (i == 4) {
      EXPECT_GT(std::abs(u - u_first), 50) << "the carried camera did not move";
    }
  }
}

TEST_F(PixelTest, ImagesAreTopDownRgb) {
  // the ball placed towards the top of the "down" image (+y world = up in the image)
  Place("ball", 0, 0.5, 0.3);
  Renderer::Options options;
  options.log_renderer = false;
  auto r = Renderer::Create(m_, options);
  RgbImage img;
  r->Render(d_, CameraId(m_, "down"), &img);
  const Centroid c = RedCentroid(img);
  ASSERT_GT(c.pixels, 10);
  EXPECT_LT(c.v, 240 - 100);  // top half
  // and it is red (channel order R, G, B), not blue
  const std::uint8_t* p = img.pixels.data() + 3 * (static_cast<std::size_t>(std::lround(c.v)) * 640 + std::lround(c.u));
  EXPECT_GT(p[0], 200);
  EXPECT_LT(p[2], 50);
}

TEST_F(PixelTest, DraftDrawsNoSkyAndSpheresOfFewerSlices) {
  Renderer::Options options;
  options.log_renderer = false;
  options.profile = Profile::kDraft;
  auto draft = Renderer::Create(m_, options);
  // the model's own settings are what the next renderer reads: unchanged
  EXPECT_EQ(m_->vis.quality.numslices, 28);
  EXPECT_EQ(m_->vis.quality.numstacks, 16);
  options.profile = Profile::kFast;
  auto fast = Renderer::Create(m_, options);

  // "tilted" sees the floor slab and the sky beyond it: the sky is black in draft,
  // and everything else (flat faces, one light, no haze: no infinite plane) is the
  // same bytes as in fast
  const int tilted = CameraId(m_, "tilted");
  RgbImage a, b;
  SegmentationImage seg;
  fast->Render(d_, tilted, &a);
  draft->Render(d_, tilted, &b);
  fast->RenderSegmentation(d_, tilted, &seg);
  const int ball = Id(mjOBJ_GEOM, "ball");
  int sky = 0, same = 0, near_ball = 0;
  for (int y = 0; y < a.height; ++y) {
    for (int x = 0; x < a.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * a.width + x;
      const std::uint8_t* pa = a.pixels.data() + 3 * i;
      const std::uint8_t* pb = b.pixels.data() + 3 * i;
      if (seg.geom[i] < 0) {
        ++sky;
        ASSERT_TRUE(pb[0] == 0 && pb[1] == 0 && pb[2] == 0) << "draft sky at " << x << ", " << y;
        ASSERT_GT(pa[0] + pa[1] + pa[2], 100) << "fast sky at " << x << ", " << y;
        continue;
      }
      // the ball's outline (and its anti-aliasing-free edge pixels) differ by the slices
      bool by_ball = false;
      for (int dy = -2; dy <= 2 && !by_ball; ++dy) {
        for (int dx = -2; dx <= 2 && !by_ball; ++dx) {
          const int u = x + dx, v = y + dy;
          by_ball = u >= 0 && v >= 0 && u < a.width && v < a.height &&
                    seg.geom[static_cast<std::size_t>(v) * a.width + u] == ball;
        }
      }
      if (by_ball) {
        ++near_ball;
        continue;
      }
      ASSERT_TRUE(pa[0] == pb[0] && pa[1] == pb[1] && pa[2] == pb[2]) << "at " << x << ", " << y;
      ++same;
    }
  }
  EXPECT_GT(sky, a.width * a.height / 20);
  EXPECT_GT(same, a.width * a.height / 2);

  // a sphere seen along its axis from close by: its outline is the equator's polygon,
  // of area (n/2) sin(2 pi / n) r^2 for n slices; 16 against 28: 0.98272 of the area
  Place("ball", 0, 0, 1.7);  // 0.3 m below "down": radius 0.02 m is about 39 px
  const int down = CameraId(m_, "down");
  fast->Render(d_, down, &a);
  draft->Render(d_, down, &b);
  const auto polygon = [](int n) { return 0.5 * n * std::sin(2 * M_PI / n); };
  const double expected = polygon(kDraftSlices) / polygon(28);
  const Centroid ca = RedCentroid(a), cb = RedCentroid(b);
  ASSERT_GT(ca.pixels, 3000);
  EXPECT_NEAR(static_cast<double>(cb.pixels) / ca.pixels, expected, 0.005)
      << cb.pixels << " red pixels in draft, " << ca.pixels << " in fast";
}

TEST_F(PixelTest, RenderingLeavesTheStateUnchanged) {
  Renderer::Options options;
  options.profile = Profile::kQuality;
  options.log_renderer = false;
  auto r = Renderer::Create(m_, options);
  d_->qpos[0] = 0.1;
  mj_forward(m_, d_);
  mjData* copy = MakeData(m_);
  mj_copyData(copy, m_, d_);
  RgbImage img;
  DepthImage depth;
  SegmentationImage seg;
  r->Render(d_, CameraId(m_, "carried"), &img, &depth);
  r->RenderSegmentation(d_, CameraId(m_, "down"), &seg);
  for (int i = 0; i < m_->nq; ++i) EXPECT_EQ(copy->qpos[i], d_->qpos[i]);
  for (int i = 0; i < 3 * m_->nbody; ++i) EXPECT_EQ(copy->xpos[i], d_->xpos[i]);
  for (int i = 0; i < mjNWARNING; ++i) EXPECT_EQ(copy->warning[i].number, d_->warning[i].number);
  EXPECT_EQ(copy->time, d_->time);
}

}  // namespace
}  // namespace vlab::render
