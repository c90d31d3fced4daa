// Planar geometry of standing: the support polygon of point contacts and the
// signed distance of a centre of pressure to its edge.
//
// Points are (x, y) in one plane (the floor's, world frame, m). The functions
// allocate nothing once their output buffers have the capacity documented, so
// a device may call them every control period.
#pragma once

#include <vector>

#include <Eigen/Core>

namespace vlab::lab {

/// Convex hull of `points`, counter-clockwise, without repeated or collinear
/// points (Andrew's monotone chain): 0 points, 1 point, the 2 ends of a
/// segment, or a polygon of >= 3 vertices. Sorts `points` in place and writes
/// `hull`, which allocates nothing when its capacity is >= 2 points.size() + 1.
void ConvexHull(std::vector<Eigen::Vector2d>& points, std::vector<Eigen::Vector2d>* hull);

/// Signed distance of p to the edge of a convex hull from ConvexHull(), m:
/// positive inside a polygon (the distance to its nearest edge), negative
/// outside (minus the distance to the polygon). A segment or a single point
/// has no inside: minus the distance to it (0 on it). NaN for an empty hull.
double SignedDistanceToHull(const std::vector<Eigen::Vector2d>& hull, const Eigen::Vector2d& p);

}  // namespace vlab::lab
