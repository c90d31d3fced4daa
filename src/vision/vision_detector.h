// Fiducial marker detection and pose: OpenCV's ArUco detector with AprilTag
// corner refinement (corners shifted by half a pixel to the pixel-centre
// convention), each outline then refined from the grey levels
// (vision_edges.h), and the square-marker pose solver IPPE (Collins and
// Bartoli, "Infinitesimal Plane-Based Pose Estimation", IJCV 109(3), 2014),
// which returns the two poses a planar square admits; both are refined by
// Levenberg-Marquardt, the detector keeps the better one and flags the pose
// invalid when the image cannot tell them apart.
//
// Frames: image pixels with (0, 0) at the centre of the top-left pixel;
// OpenCV's camera frame (x right, y down, z forward); a marker frame with its
// origin at the marker's centre, x to the right of the printed marker, y up,
// z out of the printed side. Lengths in metres.
//
// Not thread-safe: one detector per thread. Detect allocates (OpenCV does).
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

namespace vlab::vision {

/// Pinhole intrinsics (pixels) and Brown-Conrady distortion of an image.
struct CameraModel {
  int width = 0;
  int height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  std::vector<double> distortion;  ///< k1, k2, p1, p2[, k3]; empty: none
};
/// Throws InputError naming `what` unless the model is usable (positive
/// size and focal lengths, finite values, 0, 4 or 5 distortion values).
void CheckCameraModel(const CameraModel& camera, const std::string& what);

/// When a pose is reported valid.
struct DetectorConfig {
  /// Refine each detected outline from the grey levels (vision_edges.h).
  bool refine_edges = true;
  /// RMS reprojection error of the best pose above which it is not valid, px.
  double max_reprojection_error_px = 1.0;
  /// The second IPPE pose must fit this many times worse than the best one
  /// ...
  double min_ambiguity_ratio = 4.0;
  /// ... and worse than this in absolute terms, px RMS: beyond the noise of
  /// refined corners (below 0.05 px in rendered 640 x 480 images; a real
  /// camera's are noisier: set it to 2-3 times their RMS error) ...
  double min_alternative_error_px = 0.1;
  /// ... unless the two poses' rotations differ by less than this, deg (a
  /// marker seen nearly head-on: both poses are then nearly the same).
  double max_ambiguous_rotation_deg = 1.0;
  /// Markers whose normal is more oblique to the line of sight are not
  /// valid, deg: beyond 60 deg the corners of a small marker are so poorly
  /// conditioned that the wrong IPPE pose often fits better.
  double max_view_angle_deg = 60.0;
};

/// One marker found in an image.
struct MarkerDetection {
  int dictionary = 0;  ///< MarkerDictionary::code
  int id = 0;
  /// Corners in the marker's order (top-left, top-right, bottom-right,
  /// bottom-left of the printed marker), pixel-centre convention, px.
  std::array<Eigen::Vector2d, 4> corners;
};

/// The pose of one detected marker of known side.
struct MarkerPose {
  MarkerDetection detection;
  double side_m = 0;
  bool valid = false;                   ///< unambiguous, good fit, not too oblique
  double reprojection_error_px = 0;     ///< RMS over the corners, of the pose kept
  double alternative_error_px = 0;      ///< the same for the other IPPE pose
  double alternative_rotation_deg = 0;  ///< rotation between the two poses
  double view_angle_deg = 0;            ///< between the marker's normal and the line of sight
  Eigen::Isometry3d X_camera_marker = Eigen::Isometry3d::Identity();
};

class MarkerDetector {
 public:
  explicit MarkerDetector(const DetectorConfig& config = {});
  ~MarkerDetector();
  MarkerDetector(const MarkerDetector&) = delete;
  MarkerDetector& operator=(const MarkerDetector&) = delete;

  /// Finds the markers of one dictionary (code) in an 8-bit grey image and
  /// appends them to `found`.
  void Detect(const cv::Mat& grey, int dictionary, std::vector<MarkerDetection>* found) const;

  /// Pose of a detected marker of side `side_m` seen by `camera`.
  MarkerPose EstimatePose(const MarkerDetection& detection, double side_m, const CameraModel& camera) const;

  const DetectorConfig& config() const { return config_; }

 private:
  struct Impl;
  DetectorConfig config_;
  std::unique_ptr<Impl> impl_;
};

/// Angle of the rotation between two orientations, deg.
double RotationAngleDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b);

}  // namespace vlab::vision
