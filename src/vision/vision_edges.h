// Sub-pixel refinement of a detected marker's outline.
//
// The AprilTag quad fit places each side on the boundary between thresholded
// black and white pixels, so a side that runs along the pixel grid lands on a
// pixel edge even when the true edge is a quarter pixel away (corners off by
// up to 0.5 px). This step finds each side again from the grey levels: along
// the side's normal, at points spaced along it, the position of the dark-to-
// light step (the centroid of the intensity gradient, bilinear samples), then
// a least-squares line through those positions; adjacent lines intersect at
// the refined corners. The same idea as the edge refinement of AprilTag 3
// (E. Olson's group, "Flexible Layouts for Fiducial Tags", IROS 2019).
#pragma once

#include <array>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace vlab::vision {

/// Refines the four outer corners of a marker (top-left, top-right,
/// bottom-right, bottom-left of the printed marker; clockwise in the image;
/// pixel-centre convention) in an 8-bit grey image, in place. `cells` is the
/// marker's width in cells (bits + 2): the search stays within 0.4 cell of
/// each side. Returns false, leaving the corners unchanged, when a side gives
/// too few edge points or a corner would move more than 1.5 px.
bool RefineMarkerEdges(const cv::Mat& grey, int cells, std::array<Eigen::Vector2d, 4>* corners);

}  // namespace vlab::vision
