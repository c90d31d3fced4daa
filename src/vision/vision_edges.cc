#include "vision/vision_edges.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

namespace vlab::vision {

namespace {

constexpr double kStep = 0.25;         // px between profile samples along a normal
constexpr double kMaxMove = 1.5;       // px a corner may move
constexpr double kMinContrast = 20.0;  // grey levels across the profile: less is not an edge
constexpr int kIterations = 2;         // the second pass centres the profiles on the refined sides

// bilinear grey level at (x, y) in pixel-centre coordinates; NaN outside the image
double Sample(const cv::Mat& g, double x, double y) {
  if (!(x >= 0 && y >= 0 && x <= g.cols - 1 && y <= g.rows - 1)) return NAN;
  const int x0 = std::min(static_cast<int>(x), g.cols - 2), y0 = std::min(static_cast<int>(y), g.rows - 2);
  const double fx = x - x0, fy = y - y0;
  const std::uint8_t* r0 = g.ptr<std::uint8_t>(y0);
  const std::uint8_t* r1 = g.ptr<std::uint8_t>(y0 + 1);
  return (1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x0 + 1]) + fy * ((1 - fx) * r1[x0] + fx * r1[x0 + 1]);
}

struct Line {
  Eigen::Vector2d point, direction;
};

// the dark-to-light step along the outward normal n through p: the centroid
// of the positive intensity gradient (exact for an area-sampled step between
// two flat levels); offset along n, px
bool EdgeOffset(const cv::Mat& g, const Eigen::Vector2d& p, const Eigen::Vector2d& n, double reach, double* offset,
                double* strength) {
  constexpr int kMaxSamples = 32;
  const int count = std::min(kMaxSamples, static_cast<int>(std::lround(2 * reach / kStep)) + 1);
  double level[kMaxSamples];
  double lo = 255, hi = 0;
  for (int k = 0; k < count; ++k) {
    const double s = -reach + k * kStep;
    level[k] = Sample(g, p.x() + s * n.x(), p.y() + s * n.y());
    if (std::isnan(level[k])) return false;
    lo = std::min(lo, level[k]);
    hi = std::max(hi, level[k]);
  }
  if (hi - lo < kMinContrast) return false;
  double sum = 0, moment = 0;
  for (int k = 1; k + 1 < count; ++k) {
    const double gradient = (level[k + 1] - level[k - 1]) / (2 * kStep);
    if (gradient <= 0) continue;
    sum += gradient;
    moment += gradient * (-reach + k * kStep);
  }
  if (sum <= 0) return false;
  *offset = moment / sum;
  *strength = sum * kStep;
  return true;
}

// edge points spaced along one side (from a to b); a weighted least-squares line through them
bool FitSide(const cv::Mat& g, const Eigen::Vector2d& a, const Eigen::Vector2d& b, int cells, Line* line) {
  const double length = (b - a).norm();
  if (length < 8) return false;
  const Eigen::Vector2d d = (b - a) / length;
  const Eigen::Vector2d n(d.y(), -d.x());  // outward: the corners run clockwise in the image (y down)
  const double reach = std::clamp(0.4 * length / cells, 1.5, 3.0);
  constexpr int kMaxPoints = 64;
  const int samples = std::clamp(static_cast<int>(length / 1.5), 6, kMaxPoints);

  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  double total = 0;
  int used = 0;
  Eigen::Vector2d points[kMaxPoints];
  double weights[kMaxPoints];
  for (int i = 0; i < samples; ++i) {
    const Eigen::Vector2d p = a + (0.12 + 0.76 * i / (samples - 1)) * length * d;
    double offset = 0, strength = 0;
    if (!EdgeOffset(g, p, n, reach, &offset, &strength)) continue;
    points[used] = p + offset * n;
    weights[used] = strength;
    mean += strength * points[used];
    total += strength;
    ++used;
  }
  if (used < 4) return false;
  mean /= total;
  for (int i = 0; i < used; ++i) {
    const Eigen::Vector2d e = points[i] - mean;
    scatter += weights[i] * e * e.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(scatter);
  line->point = mean;
  line->direction = eigen.eigenvectors().col(1);  // the largest eigenvalue: along the side
  return true;
}

bool Intersect(const Line& u, const Line& v, Eigen::Vector2d* at) {
  // u.point + s u.direction = v.point + t v.direction
  Eigen::Matrix2d A;
  A << u.direction, -v.direction;
  if (std::abs(A.determinant()) < 1e-6) return false;
  const Eigen::Vector2d st = A.inverse() * (v.point - u.point);
  *at = u.point + st[0] * u.direction;
  return true;
}

}  // namespace

bool RefineMarkerEdges(const cv::Mat& grey, int cells, std::array<Eigen::Vector2d, 4>* corners) {
  if (grey.type() != CV_8UC1 || grey.cols < 2 || grey.rows < 2 || cells < 3) return false;
  std::array<Eigen::Vector2d, 4> refined = *corners;
  for (int iteration = 0; iteration < kIterations; ++iteration) {
    Line lines[4];
    for (std::size_t i = 0; i < 4; ++i) {
      if (!FitSide(grey, refined[i], refined[(i + 1) % 4], cells, &lines[i])) return false;
    }
    // corner i starts side i and ends side i - 1
    for (std::size_t i = 0; i < 4; ++i) {
      if (!Intersect(lines[(i + 3) % 4], lines[i], &refined[i])) return false;
    }
  }
  for (std::size_t i = 0; i < 4; ++i) {
    if ((refined[i] - (*corners)[i]).norm() > kMaxMove) return false;
  }
  *corners = refined;
  return true;
}

}  // namespace vlab::vision
