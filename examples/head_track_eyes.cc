#include "head_track_eyes.h"

#include <algorithm>
#include <cmath>

namespace head_track {

Blob FindBall(const std::uint8_t* rgb, int width, int height, int min_pixels) {
  // a hand-written colour threshold: strongly red, little green or blue
  double sum_u = 0, sum_v = 0;
  int count = 0;
  for (int v = 0; v < height; ++v) {
    const std::uint8_t* row = rgb + static_cast<std::size_t>(v) * width * 3;
    for (int u = 0; u < width; ++u) {
      const int r = row[3 * u], g = row[3 * u + 1], b = row[3 * u + 2];
      if (r >= 60 && r >= 2 * std::max(g, b) + 20) {
        sum_u += u;
        sum_v += v;
        ++count;
      }
    }
  }
  Blob blob;
  blob.pixels = count;
  blob.found = count >= min_pixels;
  if (blob.found) {
    blob.u = sum_u / count;
    blob.v = sum_v / count;
  }
  return blob;
}

EyeAngles FixateAngles(double u, double v, const Intrinsics& k, double pan, double tilt) {
  // the pixel's ray in the eye frame (x forward, y left, z up) from the
  // OpenCV camera frame (x right, y down, z forward)
  const double ex = 1.0, ey = -(u - k.cx) / k.fx, ez = -(v - k.cy) / k.fy;
  // into the tilt frame: the pan turns the eye about -z by pan
  const double c = std::cos(pan), s = std::sin(pan);
  const double dx = c * ex + s * ey, dy = -s * ex + c * ey, dz = ez;
  // into the head frame: the tilt turns about +y by tilt
  const double ct = std::cos(tilt), st = std::sin(tilt);
  const double hx = ct * dx + st * dz, hy = dy, hz = -st * dx + ct * dz;
  // the gimbal pointing along h: (cos p cos t, -sin p, -cos p sin t)
  EyeAngles a;
  a.pan = std::atan2(-hy, std::hypot(hx, hz));
  a.tilt = std::atan2(-hz, hx);
  return a;
}

std::int64_t NewestSentFrame(double t_s, const FrameSchedule& s) {
  const double x = t_s - s.latency_s - s.control_period_s - 0.5 * s.exposure_s - 1e-6;
  if (x < 0) return -1;
  return static_cast<std::int64_t>(std::floor(x * s.fps));
}

void AngleFilter::Update(double t_s, double angle) {
  const double dt = t_s - t_;
  if (!valid_ || dt > gap_s_ || dt <= 0) {
    angle_ = angle;
    rate_ = 0;
  } else {
    const double residual = angle - (angle_ + rate_ * dt);
    angle_ += rate_ * dt + alpha_ * residual;
    rate_ += beta_ * residual / dt;
  }
  t_ = t_s;
  valid_ = true;
}

double AngleFilter::Angle(double t_s) const { return angle_ + Rate(t_s) * (t_s - t_); }

double AngleFilter::Rate(double t_s) const { return t_s - t_ <= gap_s_ ? rate_ : 0.0; }

}  // namespace head_track
