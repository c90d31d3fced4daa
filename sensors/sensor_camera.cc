#include "sensors/sensor_camera.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include <Eigen/LU>
#include <opencv2/imgproc.hpp>

namespace vlab::sensors {

namespace {

constexpr double kTolerance_s = 1e-9;  // a stamp this close to a boundary counts as on it

void Check(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("camera model: " + what);
}

struct Lens {
  double k1, k2, p1, p2;
  // forward model on normalized coordinates, and its Jacobian
  Eigen::Vector2d Distort(const Eigen::Vector2d& p, Eigen::Matrix2d* jacobian = nullptr) const {
    const double x = p.x(), y = p.y();
    const double r2 = x * x + y * y;
    const double g = 1 + k1 * r2 + k2 * r2 * r2;
    const Eigen::Vector2d d(x * g + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
                            y * g + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y);
    if (jacobian) {
      const double dg = 2 * k1 + 4 * k2 * r2;  // dg/dx = dg * x, dg/dy = dg * y
      (*jacobian) << g + dg * x * x + 2 * p1 * y + 6 * p2 * x, dg * x * y + 2 * p1 * x + 2 * p2 * y,
          dg * x * y + 2 * p1 * x + 2 * p2 * y, g + dg * y * y + 6 * p1 * y + 2 * p2 * x;
    }
    return d;
  }
  // the normalized point whose image is `target`; Newton's method from the target
  bool Undistort(const Eigen::Vector2d& target, Eigen::Vector2d* p) const {
    Eigen::Vector2d x = target;
    Eigen::Matrix2d J;
    for (int i = 0; i < 50; ++i) {
      const Eigen::Vector2d residual = Distort(x, &J) - target;
      const double det = J.determinant();
      // a fold of the model (strong distortion far out): no physical inverse
      if (!(det > 1e-6)) return false;
      const Eigen::Vector2d step = J.inverse() * residual;
      x -= step;
      if (step.norm() < 1e-14) break;
    }
    Distort(x, &J);
    if (!((Distort(x) - target).norm() < 1e-11) || !(J.determinant() > 1e-6)) return false;
    *p = x;
    return true;
  }
};

Lens LensOf(const CameraModelConfig& c) { return {c.distortion[0], c.distortion[1], c.distortion[2], c.distortion[3]}; }

// frames with a time f(i) = i / fps + offset <= t (+ tolerance)
std::int64_t CountUpTo(double t, double fps, double offset) {
  const double x = (t + kTolerance_s - offset) * fps;
  return x < 0 ? 0 : static_cast<std::int64_t>(std::floor(x)) + 1;
}

}  // namespace

PinholeIntrinsics IntrinsicsFromFovy(double fovy_rad, int width, int height) {
  PinholeIntrinsics k;
  k.width = width;
  k.height = height;
  k.fx = k.fy = 0.5 * height / std::tan(0.5 * fovy_rad);
  k.cx = 0.5 * width - 0.5;
  k.cy = 0.5 * height - 0.5;
  return k;
}

double FovyFromHfov(double hfov_rad, int width, int height) {
  return 2.0 * std::atan(std::tan(0.5 * hfov_rad) * height / width);
}

CameraModel::CameraModel(const CameraModelConfig& config) : config_(config) {}
CameraModel::~CameraModel() = default;

std::unique_ptr<CameraModel> CameraModel::Create(const CameraModelConfig& c) {
  Check(c.width >= 1 && c.width <= 8192, "width must be 1 to 8192 pixels");
  Check(c.height >= 1 && c.height <= 8192, "height must be 1 to 8192 pixels");
  Check(c.fps > 0 && c.fps <= 1000, "fps must be > 0 and <= 1000 Hz");
  Check(c.fovy_rad > 0 && c.fovy_rad < 3.14159265358979323846, "fovy must be > 0 and < 180 deg");
  Check(c.exposure_s >= 0 && c.exposure_s < 1 / c.fps, "exposure must be >= 0 s and shorter than a frame");
  Check(c.latency_s >= 0 && c.latency_s <= 1, "latency must be 0 to 1 s");
  for (double k : c.distortion) {
    Check(std::isfinite(k) && std::abs(k) <= 100, "distortion coefficients must be finite, |k| <= 100");
  }
  Check(c.noise >= 0 && c.noise <= 64, "noise must be 0 to 64 grey levels");
  const PinholeIntrinsics& i = c.ideal;
  if (i.width != 0) {
    Check(i.width >= 1 && i.width <= 16384 && i.height >= 1 && i.height <= 16384,
          "ideal image size must be 1 to 16384 pixels");
    Check(i.fx > 0 && i.fy > 0 && std::isfinite(i.fx) && std::isfinite(i.fy) && std::isfinite(i.cx) &&
              std::isfinite(i.cy),
          "ideal intrinsics must be finite with fx, fy > 0");
  }
  std::unique_ptr<CameraModel> m(new CameraModel(c));
  m->intrinsics_ = IntrinsicsFromFovy(c.fovy_rad, c.width, c.height);
  m->ideal_is_output_ = i.width == 0;
  m->ideal_ = m->ideal_is_output_ ? m->intrinsics_ : i;
  m->distorts_ = std::any_of(c.distortion.begin(), c.distortion.end(), [](double k) { return k != 0; });
  m->BuildMap();
  m->BuildNoiseTable();
  return m;
}

void CameraModel::BuildNoiseTable() {
  if (config_.noise <= 0) return;
  // P(round(sigma Z) = k) for |k| <= K, renormalized
  const double sigma = config_.noise;
  const int K = static_cast<int>(std::ceil(6 * sigma)) + 1;
  const int n = 2 * K + 1;
  std::vector<double> p(static_cast<std::size_t>(n));
  double total = 0;
  for (int i = 0; i < n; ++i) {
    const double k = i - K;
    const auto phi = [&](double x) { return 0.5 * std::erfc(-x / (sigma * std::sqrt(2.0))); };
    p[i] = phi(k + 0.5) - phi(k - 0.5);
    total += p[i];
  }
  // Vose: split scaled probabilities into those below and above the mean
  std::vector<double> q(p.size());
  std::vector<int> small, large;
  for (int i = 0; i < n; ++i) {
    q[i] = p[i] / total * n;
    (q[i] < 1 ? small : large).push_back(i);
  }
  // a column no other fills (left over when the lists run out) keeps itself
  noise_threshold_.assign(p.size(), std::uint64_t{1} << 32);
  noise_alias_.resize(p.size());
  for (int i = 0; i < n; ++i) noise_alias_[i] = i;
  while (!small.empty() && !large.empty()) {
    const int s = small.back(), l = large.back();
    small.pop_back();
    noise_threshold_[s] = static_cast<std::uint64_t>(std::llround(q[s] * 4294967296.0));
    noise_alias_[s] = l;
    q[l] -= 1 - q[s];
    if (q[l] < 1) {
      large.pop_back();
      small.push_back(l);
    }
  }
  noise_offset_ = K;
}

void CameraModel::BuildMap() {
  // always computed (CoveringIdeal needs the extent); used when resampling is needed
  const PinholeIntrinsics& out = intrinsics_;
  const Lens lens = LensOf(config_);
  map_x_.resize(static_cast<std::size_t>(out.width) * out.height);
  map_y_.resize(map_x_.size());
  map_min_x_ = map_min_y_ = HUGE_VAL;
  map_max_x_ = map_max_y_ = -HUGE_VAL;
  for (int v = 0; v < out.height; ++v) {
    for (int u = 0; u < out.width; ++u) {
      const std::size_t at = static_cast<std::size_t>(v) * out.width + u;
      Eigen::Vector2d p;
      if (!lens.Undistort(Eigen::Vector2d((u - out.cx) / out.fx, (v - out.cy) / out.fy), &p)) {
        map_x_[at] = map_y_[at] = -1e6f;  // no source: black
        continue;
      }
      // the extent in output focal lengths (for CoveringIdeal)
      map_min_x_ = std::min(map_min_x_, p.x() * out.fx);
      map_max_x_ = std::max(map_max_x_, p.x() * out.fx);
      map_min_y_ = std::min(map_min_y_, p.y() * out.fy);
      map_max_y_ = std::max(map_max_y_, p.y() * out.fy);
      map_x_[at] = static_cast<float>(ideal_.fx * p.x() + ideal_.cx);
      map_y_[at] = static_cast<float>(ideal_.fy * p.y() + ideal_.cy);
    }
  }
}

double CameraModel::ExposureStart(std::int64_t i) const { return static_cast<double>(i) / config_.fps; }

double CameraModel::Stamp(std::int64_t i) const { return ExposureStart(i) + 0.5 * config_.exposure_s; }

double CameraModel::Delivery(std::int64_t i) const { return Stamp(i) + config_.latency_s; }

FrameRange CameraModel::DueForRender(double t_prev, double t) const {
  const double offset = 0.5 * config_.exposure_s;
  return {CountUpTo(t_prev, config_.fps, offset), CountUpTo(t, config_.fps, offset)};
}

FrameRange CameraModel::DueForDelivery(double t_prev, double t) const {
  const double offset = 0.5 * config_.exposure_s + config_.latency_s;
  return {CountUpTo(t_prev, config_.fps, offset), CountUpTo(t, config_.fps, offset)};
}

int CameraModel::FramesInFlight() const {
  // stamps in (t - latency, t]
  return static_cast<int>(std::ceil(config_.latency_s * config_.fps)) + 1;
}

Eigen::Vector2d CameraModel::DistortPixel(const Eigen::Vector2d& ideal_px) const {
  const Eigen::Vector2d p((ideal_px.x() - ideal_.cx) / ideal_.fx, (ideal_px.y() - ideal_.cy) / ideal_.fy);
  const Eigen::Vector2d d = LensOf(config_).Distort(p);
  return {intrinsics_.fx * d.x() + intrinsics_.cx, intrinsics_.fy * d.y() + intrinsics_.cy};
}

bool CameraModel::UndistortPixel(const Eigen::Vector2d& out_px, Eigen::Vector2d* ideal_px) const {
  Eigen::Vector2d p;
  const Eigen::Vector2d d((out_px.x() - intrinsics_.cx) / intrinsics_.fx,
                          (out_px.y() - intrinsics_.cy) / intrinsics_.fy);
  if (!LensOf(config_).Undistort(d, &p)) return false;
  *ideal_px = Eigen::Vector2d(ideal_.fx * p.x() + ideal_.cx, ideal_.fy * p.y() + ideal_.cy);
  return true;
}

PinholeIntrinsics CameraModel::CoveringIdeal() const {
  // centred on the optical axis (as MuJoCo renders), 1 pixel beyond the extent
  const double half_x = std::max({-map_min_x_, map_max_x_, intrinsics_.cx}) + 1.0;
  const double half_y = std::max({-map_min_y_, map_max_y_, intrinsics_.cy}) + 1.0;
  PinholeIntrinsics k;
  k.width = 2 * static_cast<int>(std::ceil(half_x + 0.5));
  k.height = 2 * static_cast<int>(std::ceil(half_y + 0.5));
  k.fx = intrinsics_.fx;
  k.fy = intrinsics_.fy;
  k.cx = 0.5 * k.width - 0.5;
  k.cy = 0.5 * k.height - 0.5;
  return k;
}

void CameraModel::Apply(const std::uint8_t* ideal_rgb, std::uint8_t* out_rgb, CameraNoiseState* state) const {
  const int w = intrinsics_.width, h = intrinsics_.height;
  const std::size_t n = 3u * static_cast<std::size_t>(w) * h;
  if (distorts_ || !ideal_is_output_) {
    const cv::Mat src(ideal_.height, ideal_.width, CV_8UC3, const_cast<std::uint8_t*>(ideal_rgb));
    cv::Mat dst(h, w, CV_8UC3, out_rgb);
    const cv::Mat map_x(h, w, CV_32FC1, const_cast<float*>(map_x_.data()));
    const cv::Mat map_y(h, w, CV_32FC1, const_cast<float*>(map_y_.data()));
    cv::remap(src, dst, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0, 0, 0));
  } else {
    std::memcpy(out_rgb, ideal_rgb, n);
  }
  if (noise_threshold_.empty() || state == nullptr) return;
  const std::uint64_t count = noise_threshold_.size();
  for (std::size_t i = 0; i < n; ++i) {
    // alias method: the high 32 bits pick a column, the low 32 bits pick it or its alias
    const std::uint64_t u = state->rng();
    const std::size_t column = static_cast<std::size_t>(((u >> 32) * count) >> 32);
    const int value = (u & 0xffffffffu) < noise_threshold_[column] ? static_cast<int>(column) : noise_alias_[column];
    out_rgb[i] = static_cast<std::uint8_t>(std::clamp(out_rgb[i] + value - noise_offset_, 0, 255));
  }
}

}  // namespace vlab::sensors
