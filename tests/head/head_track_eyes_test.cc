// Tests examples/head_track_eyes.cc: the ball's centroid in a drawn image, the
// eye angles that fixate a pixel against an independent forward model of the
// eye gimbal (Eigen rotations), the frame schedule against hand-computed
// frame numbers, and the gaze filter on a ramp.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "head_track_eyes.h"

namespace head_track {
namespace {

// A grey image with a dark bar and a red disc of radius r centred at (cu, cv).
std::vector<std::uint8_t> Picture(int w, int h, double cu, double cv, double r) {
  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(w) * h * 3);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      std::uint8_t* p = &rgb[3 * (static_cast<std::size_t>(v) * w + u)];
      const bool disc = (u - cu) * (u - cu) + (v - cv) * (v - cv) <= r * r;
      const bool bar = u >= 10 && u < 14;
      p[0] = disc ? 170 : bar ? 40 : 120;  // a red ball, a dark post, a grey wall
      p[1] = disc ? 12 : bar ? 40 : 125;
      p[2] = disc ? 10 : bar ? 45 : 130;
    }
  }
  return rgb;
}

TEST(HeadTrackEyesTest, BallCentroidIsTheDiscCentre) {
  // a disc symmetric about its centre (whole or half pixel): the centroid is the centre
  for (auto [cu, cv] : {std::pair{100.0, 60.0}, std::pair{200.5, 31.5}, std::pair{17.0, 200.5}}) {
    const std::vector<std::uint8_t> rgb = Picture(320, 240, cu, cv, 9.3);
    const Blob b = FindBall(rgb.data(), 320, 240);
    ASSERT_TRUE(b.found);
    EXPECT_NEAR(b.u, cu, 1e-9);
    EXPECT_NEAR(b.v, cv, 1e-9);
    EXPECT_GT(b.pixels, 250);  // pi 9.3^2 = 272
  }
  const std::vector<std::uint8_t> none = Picture(320, 240, -50, -50, 9.3);
  EXPECT_FALSE(FindBall(none.data(), 320, 240).found);
}

// The pixel of a direction d (head frame: x forward, y left, z up) in the eye
// camera with the eye at (pan, tilt): the eye's rotation is Ry(tilt) Rz(-pan),
// its camera looks along the eye's x with image x = -y, image y = -z.
Eigen::Vector2d PixelOf(const Eigen::Vector3d& d_head, double pan, double tilt, const Intrinsics& k) {
  const Eigen::Matrix3d r =
      (Eigen::AngleAxisd(tilt, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(-pan, Eigen::Vector3d::UnitZ()))
          .toRotationMatrix();
  const Eigen::Vector3d e = r.transpose() * d_head;
  return {k.cx + k.fx * (-e.y() / e.x()), k.cy + k.fy * (-e.z() / e.x())};
}

TEST(HeadTrackEyesTest, FixateAnglesInvertTheEyeGimbal) {
  const Intrinsics k{289.7, 289.7, 159.5, 119.5};
  // the principal point: the angles stay as they are
  const EyeAngles same = FixateAngles(159.5, 119.5, k, 0.2, -0.1);
  EXPECT_NEAR(same.pan, 0.2, 1e-12);
  EXPECT_NEAR(same.tilt, -0.1, 1e-12);
  // a pixel straight to the right of the centre, eye at rest: pan by atan((u - cx) / fx)
  EXPECT_NEAR(FixateAngles(159.5 + 50, 119.5, k, 0, 0).pan, std::atan(50 / 289.7), 1e-12);
  EXPECT_NEAR(FixateAngles(159.5, 119.5 + 40, k, 0, 0).tilt, std::atan(40 / 289.7), 1e-12);
  // any target direction seen from any eye pose: its gimbal angles come back
  for (double pan0 : {-0.3, 0.0, 0.25}) {
    for (double tilt0 : {-0.2, 0.1}) {
      for (auto [pan, tilt] : {std::pair{0.1, 0.05}, std::pair{-0.35, 0.3}, std::pair{0.4, -0.25}}) {
        const Eigen::Vector3d d(std::cos(pan) * std::cos(tilt), -std::sin(pan), -std::cos(pan) * std::sin(tilt));
        const Eigen::Vector2d px = PixelOf(d, pan0, tilt0, k);
        const EyeAngles a = FixateAngles(px.x(), px.y(), k, pan0, tilt0);
        EXPECT_NEAR(a.pan, pan, 1e-12) << pan0 << " " << tilt0;
        EXPECT_NEAR(a.tilt, tilt, 1e-12) << pan0 << " " << tilt0;
      }
    }
  }
}

TEST(HeadTrackEyesTest, NewestSentFrameFollowsTheWebcamSchedule) {
  // 30 fps, 30 ms latency, 2 ms periods: frame i is exposed at i / 30 s, rendered at the
  // period end at or after it, sent 30 ms later; certainly sent by i / 30 + 0.032
  FrameSchedule s{30.0, 0.0, 0.03, 0.002};
  EXPECT_EQ(NewestSentFrame(0.0, s), -1);
  EXPECT_EQ(NewestSentFrame(0.030, s), -1);
  EXPECT_EQ(NewestSentFrame(0.032, s), -1);  // 1 us short of certain
  EXPECT_EQ(NewestSentFrame(0.0322, s), 0);
  EXPECT_EQ(NewestSentFrame(1.0 / 30 + 0.032 - 1e-5, s), 0);
  EXPECT_EQ(NewestSentFrame(1.0 / 30 + 0.032 + 1e-5, s), 1);
  EXPECT_EQ(NewestSentFrame(10.0, s), 299);  // (10 - 0.032) 30 = 299.04
  s.exposure_s = 0.01;                       // stamps move by half the exposure
  EXPECT_EQ(NewestSentFrame(0.036, s), -1);
  EXPECT_EQ(NewestSentFrame(0.038, s), 0);
}

TEST(HeadTrackEyesTest, AngleFilterSettlesOnARampAndHoldsAfterAGap) {
  AngleFilter f(0.7, 0.3, 0.5);
  EXPECT_FALSE(f.valid());
  f.Update(1.0, 0.2);  // the first measurement: that angle, rate 0
  EXPECT_TRUE(f.valid());
  EXPECT_EQ(f.Angle(1.1), 0.2);
  EXPECT_EQ(f.Rate(1.1), 0.0);
  // a ramp of 0.4 rad/s sampled at 30 Hz: the error shrinks by sqrt(1 - alpha) per sample
  // (the error dynamics' poles have modulus sqrt(0.3)), below 1e-12 after 60 samples
  double t = 1.0;
  for (int i = 1; i <= 60; ++i) {
    t = 1.0 + i / 30.0;
    f.Update(t, 0.2 + 0.4 * (t - 1.0));
  }
  EXPECT_NEAR(f.Rate(t), 0.4, 1e-10);
  EXPECT_NEAR(f.Angle(t + 0.05), 0.2 + 0.4 * (t + 0.05 - 1.0), 1e-10);  // predicted
  // no measurement for longer than the gap: the last angle, no rate; then a restart
  EXPECT_NEAR(f.Angle(t + 0.6), 0.2 + 0.4 * (t - 1.0), 1e-10);
  EXPECT_EQ(f.Rate(t + 0.6), 0.0);
  f.Update(t + 0.6, -0.1);
  EXPECT_EQ(f.Angle(t + 0.6), -0.1);
  EXPECT_EQ(f.Rate(t + 0.6), 0.0);
}

}  // namespace
}  // namespace head_track
