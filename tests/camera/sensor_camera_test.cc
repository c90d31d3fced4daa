// Tests sensors/sensor_camera.cc: intrinsics from fovy, the frame schedule
// against control period boundaries, the lens against OpenCV's own projection
// (cv::projectPoints), and the pixel noise's statistics and seeding.
#include "sensors/sensor_camera.h"

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>

namespace vlab::sensors::sensor_camera_test {
namespace {

constexpr double kPi = 3.14159265358979323846;
double Deg(double rad) { return rad * 180 / kPi; }
double Rad(double deg) { return deg * kPi / 180; }

// DATASHEET section 7: a typical 640x480 webcam calibration (k1, k2, p1, p2)
constexpr std::array<double, 4> kExampleDistortion = {0.1097, -0.5567, -0.0019, 0.0002};

TEST(CameraIntrinsicsTest, FromFovyAsMujocoRenders) {
  const PinholeIntrinsics k = IntrinsicsFromFovy(Rad(45), 640, 480);
  EXPECT_NEAR(k.fx, 240 / std::tan(Rad(22.5)), 1e-12);
  EXPECT_NEAR(k.fx, 579.4112549695428, 1e-9);
  EXPECT_EQ(k.fy, k.fx);
  EXPECT_EQ(k.cx, 319.5);
  EXPECT_EQ(k.cy, 239.5);
  EXPECT_EQ(k.width, 640);
  EXPECT_EQ(k.height, 480);
}

TEST(CameraIntrinsicsTest, DefaultsAreTheQuickCamPro4000) {
  const CameraModelConfig c;
  EXPECT_EQ(c.width, 640);
  EXPECT_EQ(c.height, 480);
  EXPECT_EQ(c.fps, 30.0);
  for (double k : c.distortion) EXPECT_EQ(k, 0.0);
  const auto m = CameraModel::Create(c);
  // the horizontal field of view of the default is the data sheet's 45-50 deg (middle: 47.5)
  const double hfov = 2 * std::atan((c.width / 2.0) / m->intrinsics().fx);
  EXPECT_NEAR(Deg(hfov), kQuickCamHfovDeg, 1e-9);
  EXPECT_NEAR(Deg(c.fovy_rad), 36.527, 0.001);
  EXPECT_FALSE(m->distorts());
}

TEST(CameraScheduleTest, StampsAndDelivery) {
  CameraModelConfig c;
  c.fps = 25;
  c.exposure_s = 0.02;
  c.latency_s = 0.05;
  const auto m = CameraModel::Create(c);
  EXPECT_DOUBLE_EQ(m->ExposureStart(3), 0.12);
  EXPECT_DOUBLE_EQ(m->Stamp(3), 0.13);
  EXPECT_DOUBLE_EQ(m->Delivery(3), 0.18);
  EXPECT_EQ(m->FramesInFlight(), 3);  // ceil(0.05 * 25) + 1
}

// every frame is rendered exactly once, at the first boundary at or after its
// stamp, and delivered exactly once, at the first boundary at or after its delivery time
void CheckSchedule(double fps, double exposure_s, double latency_s, double period_s, double duration_s) {
  CameraModelConfig c;
  c.fps = fps;
  c.exposure_s = exposure_s;
  c.latency_s = latency_s;
  const auto m = CameraModel::Create(c);
  std::int64_t next_render = 0, next_delivery = 0;
  int max_in_flight = 0;
  double t_prev = -1;
  const long periods = std::lround(duration_s / period_s);
  for (long k = 0; k <= periods; ++k) {
    const double t = static_cast<double>(k) * period_s;
    const FrameRange render = m->DueForRender(t_prev, t);
    ASSERT_EQ(render.first, next_render) << "t = " << t;
    for (std::int64_t i = render.first; i < render.end; ++i) {
      EXPECT_LE(m->Stamp(i), t + 1e-9) << "frame " << i << " rendered before its stamp";
      EXPECT_GT(m->Stamp(i), t - period_s - 1e-9) << "frame " << i << " rendered late";
    }
    next_render = render.end;
    const FrameRange deliver = m->DueForDelivery(t_prev, t);
    ASSERT_EQ(deliver.first, next_delivery);
    for (std::int64_t i = deliver.first; i < deliver.end; ++i) {
      EXPECT_LT(i, next_render) << "frame " << i << " delivered before it was rendered";
      EXPECT_LE(m->Delivery(i), t + 1e-9);
      EXPECT_GT(m->Delivery(i), t - period_s - 1e-9);
    }
    next_delivery = deliver.end;
    max_in_flight = std::max(max_in_flight, static_cast<int>(next_render - next_delivery));
    t_prev = t;
  }
  // frames with a stamp in [0, duration]
  EXPECT_EQ(next_render, static_cast<std::int64_t>(std::floor((duration_s - exposure_s / 2) * fps + 1e-6)) + 1);
  EXPECT_LE(max_in_flight, m->FramesInFlight());
}

TEST(CameraScheduleTest, EveryFrameOnceAt500Hz) { CheckSchedule(30, 0, 0.03, 0.002, 10); }
TEST(CameraScheduleTest, EveryFrameOnceWithExposureAndAwkwardPeriod) { CheckSchedule(25, 0.013, 0.071, 1.0 / 333, 7); }
TEST(CameraScheduleTest, FasterCameraThanControl) { CheckSchedule(30, 0, 0.0, 0.1, 5); }  // several frames a period

TEST(CameraScheduleTest, FrameZeroIsDueAtTimeZero) {
  const auto m = CameraModel::Create({});
  const FrameRange r = m->DueForRender(-1, 0);
  EXPECT_EQ(r.first, 0);
  EXPECT_EQ(r.end, 1);
  // boundaries exactly on stamps: frame 3 at 0.1 s is due at t = 0.1 (whatever the rounding of 3 / 30)
  EXPECT_EQ(m->DueForRender(0.098, 0.1).first, 3);
  EXPECT_EQ(m->DueForRender(0.098, 0.1).end, 4);
}

struct Projection {
  std::vector<cv::Point3d> points;
  std::vector<cv::Point2d> ideal, distorted;
};

// random points in front of the camera, projected by OpenCV with and without distortion
Projection Project(const PinholeIntrinsics& k, const std::array<double, 4>& dist, int n, double spread) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-spread, spread), z(0.3, 2.0);
  Projection p;
  for (int i = 0; i < n; ++i) {
    const double depth = z(rng);
    p.points.emplace_back(u(rng) * depth, 0.75 * u(rng) * depth, depth);
  }
  const cv::Matx33d K(k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  const cv::Vec3d zero(0, 0, 0);
  cv::projectPoints(p.points, zero, zero, K, cv::Mat(), p.ideal);
  cv::projectPoints(p.points, zero, zero, K, std::vector<double>(dist.begin(), dist.end()), p.distorted);
  return p;
}

TEST(CameraLensTest, ForwardAndInverseAgreeWithProjectPoints) {
  CameraModelConfig c;
  c.fovy_rad = 2 * std::atan(240 / 726.0);  // fy of the data sheet's example calibration
  c.distortion = kExampleDistortion;
  const auto m = CameraModel::Create(c);
  ASSERT_TRUE(m->distorts());
  const Projection p = Project(m->intrinsics(), c.distortion, 500, 0.42);
  for (std::size_t i = 0; i < p.points.size(); ++i) {
    const Eigen::Vector2d ideal(p.ideal[i].x, p.ideal[i].y), distorted(p.distorted[i].x, p.distorted[i].y);
    EXPECT_LT((m->DistortPixel(ideal) - distorted).norm(), 1e-9) << i;
    Eigen::Vector2d back;
    ASSERT_TRUE(m->UndistortPixel(distorted, &back)) << i;
    EXPECT_LT((back - ideal).norm(), 1e-6) << i;
  }
}

// an ideal image with a small bright blob at each ideal projection: after the
// lens, each blob's centroid sits where cv::projectPoints puts the point
TEST(CameraLensTest, DistortedImageMatchesProjectPointsWithinATenthOfAPixel) {
  for (const auto& dist : {kExampleDistortion, std::array<double, 4>{-0.13, 0, 0, 0}}) {
    CameraModelConfig c;
    c.fovy_rad = 2 * std::atan(240 / 726.0);
    c.distortion = dist;
    const auto m = CameraModel::Create(c);
    const PinholeIntrinsics& k = m->intrinsics();
    Projection p = Project(k, dist, 400, 0.4);
    std::vector<std::uint8_t> ideal(3u * k.width * k.height, 0), out(ideal.size());
    // keep blobs well inside both images and apart from each other
    std::vector<int> used;
    for (std::size_t i = 0; i < p.points.size() && used.size() < 40; ++i) {
      const cv::Point2d a = p.ideal[i], b = p.distorted[i];
      const bool inside = a.x > 12 && a.x < k.width - 13 && a.y > 12 && a.y < k.height - 13 && b.x > 12 &&
                          b.x < k.width - 13 && b.y > 12 && b.y < k.height - 13;
      bool apart = true;
      for (int j : used) apart = apart && cv::norm(p.ideal[j] - a) > 30;
      if (inside && apart) used.push_back(static_cast<int>(i));
    }
    ASSERT_GE(used.size(), 20u);
    const double sigma = 1.5;
    for (int i : used) {
      const cv::Point2d a = p.ideal[i];
      for (int v = static_cast<int>(a.y) - 8; v <= static_cast<int>(a.y) + 8; ++v) {
        for (int u = static_cast<int>(a.x) - 8; u <= static_cast<int>(a.x) + 8; ++u) {
          const double r2 = (u - a.x) * (u - a.x) + (v - a.y) * (v - a.y);
          const double value = 250 * std::exp(-r2 / (2 * sigma * sigma));
          for (int ch = 0; ch < 3; ++ch) ideal[3u * (v * k.width + u) + ch] = static_cast<std::uint8_t>(value + 0.5);
        }
      }
    }
    m->Apply(ideal.data(), out.data(), nullptr);
    double worst = 0;
    for (int i : used) {
      const cv::Point2d b = p.distorted[i];
      double sum = 0, su = 0, sv = 0;
      for (int v = static_cast<int>(b.y) - 9; v <= static_cast<int>(b.y) + 9; ++v) {
        for (int u = static_cast<int>(b.x) - 9; u <= static_cast<int>(b.x) + 9; ++u) {
          const double w = out[3u * (v * k.width + u) + 1];
          sum += w;
          su += w * u;
          sv += w * v;
        }
      }
      ASSERT_GT(sum, 0);
      worst = std::max(worst, std::hypot(su / sum - b.x, sv / sum - b.y));
    }
    EXPECT_LT(worst, 0.1) << "k1 = " << dist[0];
    std::printf("lens k1=%g k2=%g: %zu blobs, worst centroid offset from cv::projectPoints %.4f px\n", dist[0], dist[1],
                used.size(), worst);
  }
}

TEST(CameraLensTest, NoDistortionIsAnExactCopy) {
  const auto m = CameraModel::Create({});
  std::vector<std::uint8_t> ideal(640 * 480 * 3), out(ideal.size());
  for (std::size_t i = 0; i < ideal.size(); ++i) ideal[i] = static_cast<std::uint8_t>(i * 13 + 5);
  m->Apply(ideal.data(), out.data(), nullptr);
  EXPECT_EQ(out, ideal);
}

TEST(CameraLensTest, CoveringIdealLeavesNoBlackBorder) {
  CameraModelConfig c;
  c.distortion = {-0.13, 0, 0, 0};  // the ARToolKit default's barrel (DATASHEET section 7)
  const auto plain = CameraModel::Create(c);
  const PinholeIntrinsics cover = plain->CoveringIdeal();
  EXPECT_GT(cover.width, 640);
  EXPECT_GT(cover.height, 480);
  EXPECT_EQ(cover.fx, plain->intrinsics().fx);
  EXPECT_EQ(cover.cx, cover.width / 2.0 - 0.5);
  std::vector<std::uint8_t> out(640 * 480 * 3);
  auto black = [&] {
    long n = 0;
    for (std::size_t i = 0; i < out.size(); i += 3) n += out[i] == 0;
    return n;
  };
  std::vector<std::uint8_t> white(640 * 480 * 3, 200);
  plain->Apply(white.data(), out.data(), nullptr);
  EXPECT_GT(black(), 100) << "barrel distortion of a same-size ideal image leaves black corners";
  c.ideal = cover;
  const auto covered = CameraModel::Create(c);
  std::vector<std::uint8_t> big(3u * cover.width * cover.height, 200);
  covered->Apply(big.data(), out.data(), nullptr);
  EXPECT_EQ(black(), 0);
  // and the lens is the same: a point lands at the same output pixel
  EXPECT_LT((covered->DistortPixel({cover.cx + 100, cover.cy - 80}) -
             plain->DistortPixel({plain->intrinsics().cx + 100, plain->intrinsics().cy - 80}))
                .norm(),
            1e-9);
}

TEST(CameraNoiseTest, GaussianWithTheGivenSigma) {
  CameraModelConfig c;
  c.noise = 4.0;
  const auto m = CameraModel::Create(c);
  std::vector<std::uint8_t> grey(640 * 480 * 3, 128), out(grey.size());
  CameraNoiseState state(42);
  m->Apply(grey.data(), out.data(), &state);
  double sum = 0, sum2 = 0;
  for (std::uint8_t v : out) {
    sum += v;
    sum2 += (v - 128.0) * (v - 128.0);
  }
  const double n = static_cast<double>(out.size());
  const double mean = sum / n, sd = std::sqrt(sum2 / n - (mean - 128) * (mean - 128));
  // each value's frequency is P(round(4 Z) = k), within 5 standard errors
  std::vector<long> count(256, 0);
  for (std::uint8_t v : out) ++count[v];
  const auto phi = [](double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); };
  for (int k = -12; k <= 12; ++k) {
    const double p = phi((k + 0.5) / 4) - phi((k - 0.5) / 4);
    const double f = count[128 + k] / n;
    EXPECT_NEAR(f, p, 5 * std::sqrt(p * (1 - p) / n) + 1e-7) << "k = " << k;
  }
  // rounding to whole grey levels adds 1/12 to the variance
  EXPECT_NEAR(mean, 128.0, 0.03);
  EXPECT_NEAR(sd, std::sqrt(16 + 1.0 / 12), 0.02);
  std::printf("noise sigma 4: mean %.4f, sd %.4f (expected %.4f)\n", mean, sd, std::sqrt(16 + 1.0 / 12));
}

TEST(CameraNoiseTest, SeededAndClamped) {
  CameraModelConfig c;
  c.noise = 10.0;
  const auto m = CameraModel::Create(c);
  std::vector<std::uint8_t> in(640 * 480 * 3), a(in.size()), b(in.size()), d(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) in[i] = i % 2 ? 0 : 255;  // noise must clamp at both ends
  CameraNoiseState s1(7), s2(7), s3(8);
  m->Apply(in.data(), a.data(), &s1);
  m->Apply(in.data(), b.data(), &s2);
  m->Apply(in.data(), d.data(), &s3);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, d);
  // the next frame of the same state differs (the generator moves on)
  m->Apply(in.data(), b.data(), &s2);
  EXPECT_NE(a, b);
  double dark = 0, bright = 0;
  for (std::size_t i = 0; i < a.size(); ++i) (i % 2 ? dark : bright) += a[i];
  // E[max(0, N(0, 10))] = 10 / sqrt(2 pi) = 3.99 (plus rounding)
  EXPECT_NEAR(dark / (a.size() / 2), 3.99, 0.1);
  EXPECT_NEAR(bright / (a.size() / 2), 255 - 3.99, 0.1);
}

TEST(CameraModelTest, BadConfigurationNamesTheField) {
  auto message = [](CameraModelConfig c) {
    try {
      CameraModel::Create(c);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CameraModelConfig c;
  c.fps = 0;
  EXPECT_NE(message(c).find("fps"), std::string::npos);
  c = {};
  c.exposure_s = 0.05;  // longer than a 30 Hz frame
  EXPECT_NE(message(c).find("exposure"), std::string::npos);
  c = {};
  c.width = 0;
  EXPECT_NE(message(c).find("width"), std::string::npos);
  c = {};
  c.noise = -1;
  EXPECT_NE(message(c).find("noise"), std::string::npos);
  c = {};
  c.distortion[1] = std::nan("");
  EXPECT_NE(message(c).find("distortion"), std::string::npos);
  c = {};
  c.latency_s = 2;
  EXPECT_NE(message(c).find("latency"), std::string::npos);
  c = {};
  c.fovy_rad = 0;
  EXPECT_NE(message(c).find("fovy"), std::string::npos);
}

}  // namespace
}  // namespace vlab::sensors::sensor_camera_test
