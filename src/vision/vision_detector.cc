#include "vision/vision_detector.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>

#include "bridge/bridge_markers.h"
#include "core/core_errors.h"
#include "vision/vision_edges.h"

namespace vlab::vision {

namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

Eigen::Matrix3d RotationOf(const cv::Mat& rvec) {
  cv::Matx33d r;
  cv::Rodrigues(rvec, r);
  Eigen::Matrix3d out;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) out(i, j) = r(i, j);
  }
  return out;
}

// an ArUco detection with its corners moved by `shift` px into the pixel-centre convention
MarkerDetection MakeDetection(int dictionary, int id, const std::vector<cv::Point2f>& corners, double shift) {
  MarkerDetection d;
  d.dictionary = dictionary;
  d.id = id;
  for (std::size_t k = 0; k < 4; ++k) d.corners[k] = Eigen::Vector2d(corners[k].x + shift, corners[k].y + shift);
  return d;
}

Eigen::Vector2d Centre(const MarkerDetection& d) {
  return (d.corners[0] + d.corners[1] + d.corners[2] + d.corners[3]) / 4;
}

}  // namespace

void CheckCameraModel(const CameraModel& c, const std::string& what) {
  const bool finite = std::isfinite(c.fx) && std::isfinite(c.fy) && std::isfinite(c.cx) && std::isfinite(c.cy) &&
                      std::all_of(c.distortion.begin(), c.distortion.end(), [](double v) { return std::isfinite(v); });
  if (c.width < 1 || c.height < 1 || !(c.fx > 0) || !(c.fy > 0) || !finite) {
    throw vlab::InputError(what + ": camera intrinsics need a positive size and focal lengths and finite values");
  }
  const std::size_t n = c.distortion.size();
  if (n != 0 && n != 4 && n != 5) {
    throw vlab::InputError(what + ": distortion has " + std::to_string(n) + " values, expected 0, 4 or 5");
  }
}

struct MarkerDetector::Impl {
  cv::Ptr<cv::aruco::DetectorParameters> parameters = cv::aruco::DetectorParameters::create();
  // the second pass: ArUco's own candidates (contours of the adaptively thresholded image)
  cv::Ptr<cv::aruco::DetectorParameters> contour_parameters = cv::aruco::DetectorParameters::create();
  std::vector<cv::Ptr<cv::aruco::Dictionary>> dictionaries;  // by code, made on first use
  // scratch
  mutable std::vector<std::vector<cv::Point2f>> corners;
  mutable std::vector<int> ids;
};

MarkerDetector::MarkerDetector(const DetectorConfig& config) : config_(config), impl_(std::make_unique<Impl>()) {
  // AprilTag 2 quad fitting gives sub-pixel corners; its corners follow the
  // pixel-corner convention, hence the half-pixel shift in Detect
  impl_->parameters->cornerRefinementMethod = cv::aruco::CORNER_REFINE_APRILTAG;
  // On small noisy markers the AprilTag quads miss many that ArUco's contours find: on
  // the lettered-cubes webcam's first frames (640 x 480, markers 15-21 px, 2 grey
  // levels of noise, JPEG 90) of 7 seeds, AprilTag found 5-9 markers where contours
  // found 8-12, and the cube farthest from the camera often not at all. Contour
  // corners are pixel-centred and good to about a pixel, so a marker found only by
  // contours is kept only when RefineMarkerEdges brings its outline to sub-pixel.
  impl_->contour_parameters->cornerRefinementMethod = cv::aruco::CORNER_REFINE_NONE;
  impl_->dictionaries.resize(bridge::MarkerDictionaries().size());
}

MarkerDetector::~MarkerDetector() = default;

void MarkerDetector::Detect(const cv::Mat& grey, int dictionary, std::vector<MarkerDetection>* found) const {
  const bridge::MarkerDictionary* info = bridge::FindMarkerDictionary(dictionary);
  if (info == nullptr) return;
  cv::Ptr<cv::aruco::Dictionary>& dict = impl_->dictionaries[static_cast<std::size_t>(dictionary)];
  if (!dict) dict = cv::aruco::getPredefinedDictionary(dictionary);
  impl_->corners.clear();
  impl_->ids.clear();
  cv::aruco::detectMarkers(grey, dict, impl_->corners, impl_->ids, impl_->parameters);
  for (std::size_t i = 0; i < impl_->ids.size(); ++i) {
    MarkerDetection d = MakeDetection(dictionary, impl_->ids[i], impl_->corners[i], -0.5);  // AprilTag: pixel corners
    if (config_.refine_edges) RefineMarkerEdges(grey, info->bits + 2, &d.corners);          // kept as found if it fails
    found->push_back(d);
  }
  if (!config_.refine_edges) return;
  const std::size_t first_pass = found->size();
  impl_->corners.clear();
  impl_->ids.clear();
  cv::aruco::detectMarkers(grey, dict, impl_->corners, impl_->ids, impl_->contour_parameters);
  for (std::size_t i = 0; i < impl_->ids.size(); ++i) {
    MarkerDetection d = MakeDetection(dictionary, impl_->ids[i], impl_->corners[i], 0.0);  // contours: pixel centres
    // the same marker as one of the first pass: its centre within 2 px
    bool known = false;
    for (std::size_t j = 0; j < first_pass && !known; ++j) {
      const MarkerDetection& f = (*found)[j];
      known = f.dictionary == d.dictionary && f.id == d.id && (Centre(f) - Centre(d)).norm() < 2.0;
    }
    if (!known && RefineMarkerEdges(grey, info->bits + 2, &d.corners)) found->push_back(d);
  }
}

MarkerPose MarkerDetector::EstimatePose(const MarkerDetection& detection, double side_m,
                                        const CameraModel& camera) const {
  const double h = side_m / 2;
  const std::vector<cv::Point3d> object = {{-h, h, 0}, {h, h, 0}, {h, -h, 0}, {-h, -h, 0}};
  std::vector<cv::Point2d> image(4);
  for (std::size_t k = 0; k < 4; ++k) image[k] = cv::Point2d(detection.corners[k].x(), detection.corners[k].y());
  const cv::Matx33d K(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  const cv::Mat dist = camera.distortion.empty() ? cv::Mat() : cv::Mat(camera.distortion, true);

  // both IPPE poses, each refined (Levenberg-Marquardt on the reprojection error)
  std::vector<cv::Mat> rvecs, tvecs;
  cv::solvePnPGeneric(object, image, K, dist, rvecs, tvecs, false, cv::SOLVEPNP_IPPE_SQUARE);
  struct Candidate {
    cv::Mat rvec, tvec;
    double error = std::numeric_limits<double>::infinity();
  };
  std::vector<Candidate> candidates;
  std::vector<cv::Point2d> projected;
  for (std::size_t i = 0; i < rvecs.size(); ++i) {
    Candidate c{rvecs[i].clone(), tvecs[i].clone()};
    cv::solvePnPRefineLM(object, image, K, dist, c.rvec, c.tvec);
    cv::projectPoints(object, c.rvec, c.tvec, K, dist, projected);
    double sum = 0;
    for (std::size_t k = 0; k < 4; ++k) {
      const cv::Point2d e = projected[k] - image[k];
      sum += e.dot(e);
    }
    c.error = std::sqrt(sum / 4);
    candidates.push_back(c);
  }
  MarkerPose pose;
  pose.detection = detection;
  pose.side_m = side_m;
  if (candidates.empty()) {
    pose.reprojection_error_px = pose.alternative_error_px = std::numeric_limits<double>::infinity();
    return pose;
  }
  std::sort(candidates.begin(), candidates.end(),
            [](const Candidate& a, const Candidate& b) { return a.error < b.error; });
  const Candidate& best = candidates.front();
  const Eigen::Matrix3d R = RotationOf(best.rvec);
  const Eigen::Vector3d t(best.tvec.at<double>(0), best.tvec.at<double>(1), best.tvec.at<double>(2));
  pose.X_camera_marker.linear() = R;
  pose.X_camera_marker.translation() = t;
  pose.reprojection_error_px = best.error;
  if (candidates.size() > 1) {
    pose.alternative_error_px = candidates[1].error;
    pose.alternative_rotation_deg = RotationAngleDeg(R, RotationOf(candidates[1].rvec));
  } else {
    pose.alternative_error_px = std::numeric_limits<double>::infinity();
  }
  // the normal (z) points back at the camera when the printed side is seen
  const double cos_view = -R.col(2).dot(t.normalized());
  pose.view_angle_deg = std::acos(std::clamp(cos_view, -1.0, 1.0)) * kRadToDeg;

  const bool distinct = pose.alternative_error_px >= config_.min_ambiguity_ratio * pose.reprojection_error_px &&
                        pose.alternative_error_px >= config_.min_alternative_error_px;
  const bool alike = pose.alternative_rotation_deg <= config_.max_ambiguous_rotation_deg;
  pose.valid = pose.reprojection_error_px <= config_.max_reprojection_error_px && (distinct || alike) &&
               pose.view_angle_deg <= config_.max_view_angle_deg && t.z() > 0;
  return pose;
}

double RotationAngleDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const double c = ((a.transpose() * b).trace() - 1) / 2;
  return std::acos(std::clamp(c, -1.0, 1.0)) * kRadToDeg;
}

}  // namespace vlab::vision
