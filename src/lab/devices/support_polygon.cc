#include "lab/devices/support_polygon.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vlab::lab {

namespace {

// z of (a - o) x (b - o): > 0 when o, a, b turn counter-clockwise
double Turn(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

// distance of p to the segment a-b (a point when a == b)
double SegmentDistance(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& p) {
  const Eigen::Vector2d ab = b - a;
  const double length2 = ab.squaredNorm();
  const double s = length2 > 0 ? std::clamp((p - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
  return (a + s * ab - p).norm();
}

}  // namespace

void ConvexHull(std::vector<Eigen::Vector2d>& points, std::vector<Eigen::Vector2d>* hull) {
  std::sort(points.begin(), points.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  const auto end = std::unique(points.begin(), points.end());
  const std::size_t n = static_cast<std::size_t>(end - points.begin());
  hull->clear();
  if (n < 3) {
    hull->assign(points.begin(), end);
    return;
  }
  // lower hull left to right, then upper hull right to left; a turn that is
  // not strictly counter-clockwise drops the middle point (collinear too)
  hull->resize(2 * n);
  std::vector<Eigen::Vector2d>& h = *hull;
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    while (k >= 2 && Turn(h[k - 2], h[k - 1], points[i]) <= 0) --k;
    h[k++] = points[i];
  }
  for (std::size_t i = n - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && Turn(h[k - 2], h[k - 1], points[i]) <= 0) --k;
    h[k++] = points[i];
  }
  hull->resize(k - 1);  // the last point repeats the first
}

double SignedDistanceToHull(const std::vector<Eigen::Vector2d>& hull, const Eigen::Vector2d& p) {
  const std::size_t n = hull.size();
  if (n == 0) return std::numeric_limits<double>::quiet_NaN();
  if (n == 1) return -(p - hull[0]).norm();
  if (n == 2) return -SegmentDistance(hull[0], hull[1], p);
  // inside: left of every counter-clockwise edge; the nearest edge line is
  // then the nearest edge
  double inside = std::numeric_limits<double>::infinity();
  double outside = std::numeric_limits<double>::infinity();
  bool is_inside = true;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d& a = hull[i];
    const Eigen::Vector2d& b = hull[(i + 1) % n];
    const Eigen::Vector2d edge = (b - a).normalized();
    const double left = edge.x() * (p.y() - a.y()) - edge.y() * (p.x() - a.x());
    is_inside = is_inside && left >= 0;
    inside = std::min(inside, left);
    outside = std::min(outside, SegmentDistance(a, b, p));
  }
  return is_inside ? inside : -outside;
}

}  // namespace vlab::lab
