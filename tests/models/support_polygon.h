// Support polygon and centre of pressure from point contact forces (test helper).
#pragma once

#include <vector>

#include <Eigen/Core>

namespace vlab::models::testing {

/// Convex hull of planar points, counter-clockwise, without collinear points.
std::vector<Eigen::Vector2d> ConvexHull(std::vector<Eigen::Vector2d> points);

/// Signed distance of p to the boundary of a counter-clockwise convex polygon, m:
/// positive inside, negative outside (distance to the nearest edge line).
double InsideMargin(const std::vector<Eigen::Vector2d>& hull, const Eigen::Vector2d& p);

/// Centre of pressure of normal forces f_i (N, >= 0) at points p_i; (0, 0) if all are 0.
Eigen::Vector2d CentreOfPressure(const std::vector<Eigen::Vector2d>& points, const std::vector<double>& forces);

}  // namespace vlab::models::testing
