#include "models/support_polygon.h"

#include <algorithm>
#include <limits>

namespace vlab::models::testing {

namespace {

// z of (a - o) x (b - o): > 0 when o, a, b turn counter-clockwise
double Turn(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

}  // namespace

std::vector<Eigen::Vector2d> ConvexHull(std::vector<Eigen::Vector2d> points) {
  std::sort(points.begin(), points.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  if (points.size() < 3) return points;
  // Andrew's monotone chain: lower hull left to right, then upper hull right to left
  std::vector<Eigen::Vector2d> hull(2 * points.size());
  size_t k = 0;
  for (const auto& p : points) {
    while (k >= 2 && Turn(hull[k - 2], hull[k - 1], p) <= 0) --k;
    hull[k++] = p;
  }
  for (size_t i = points.size() - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && Turn(hull[k - 2], hull[k - 1], points[i]) <= 0) --k;
    hull[k++] = points[i];
  }
  hull.resize(k - 1);  // the last point repeats the first
  return hull;
}

double InsideMargin(const std::vector<Eigen::Vector2d>& hull, const Eigen::Vector2d& p) {
  double margin = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < hull.size(); ++i) {
    const Eigen::Vector2d& a = hull[i];
    const Eigen::Vector2d edge = (hull[(i + 1) % hull.size()] - a).normalized();
    // left of a counter-clockwise edge is inside
    margin = std::min(margin, edge.x() * (p.y() - a.y()) - edge.y() * (p.x() - a.x()));
  }
  return margin;
}

Eigen::Vector2d CentreOfPressure(const std::vector<Eigen::Vector2d>& points, const std::vector<double>& forces) {
  Eigen::Vector2d moment = Eigen::Vector2d::Zero();
  double total = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    moment += forces[i] * points[i];
    total += forces[i];
  }
  return total > 0 ? Eigen::Vector2d(moment / total) : Eigen::Vector2d::Zero();
}

}  // namespace vlab::models::testing
