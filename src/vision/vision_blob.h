// Colour-blob yo-yo tracker: finds the yo-yo's saturated red discs in an RGB
// frame and places their centre on the known vertical line the yo-yo hangs
// on (the yo-yo stage of the case study: a vision measurement of the yo-yo in
// place of MuJoCo's ground truth).
//
// Blob: the RGB frame -> HSV (OpenCV: H 0..180, S and V 0..255); a pixel is
// the colour when S >= s_min, V >= v_min and H lies in the hue band (red
// wraps around 0: H <= hue_hi or H >= hue_lo). The largest connected region
// (outer contour, 8-connected) is the yo-yo, if its area lies within
// [min_area_px, max_area_fraction of the image]; its centroid is that of the
// FILLED outer contour, so that holes (the white spin mark, a glint) and the
// string (white, outside the colour band) do not move it.
//
// Geometry (LocateOnLine): the yo-yo moves on a vertical line (x = line_x,
// y = line_y, world, z up). The centroid pixel (u, v), undistorted, gives the
// ray r(t) = c + t d from the camera centre c, d = R_WC [(u-cx)/fx,
// (v-cy)/fy, 1] (OpenCV camera frame in the world: the camera device's pose).
// The plane through the line that faces the camera is vertical with the
// horizontal normal n = horizontal part of (c - L), L = (line_x, line_y, 0);
// the measurement is the ray's point in that plane, t = n.(L - c) / n.d. On
// the line it is the yo-yo's centre; a yo-yo off the line sideways (across
// the view) shows as x, y off the line within the plane; depth along n is not
// measured. The silhouette of the two discs seen from the side is the hull of
// the near and far faces, whose centroid is the projection of the centre
// (the faces face the camera) up to 1-2 % of the disc-to-disc offset.
#pragma once

#include <optional>
#include <string>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "vision/vision_detector.h"

namespace vlab::vision {

struct BlobConfig {
  std::string color = "red";
  int hue_lo = 170, hue_hi = 10;  ///< hue band, OpenCV units (0..180); lo > hi wraps through 0
  /// saturation, value floors (0..255): the discs' rim facing away from the lights is dark
  /// (V ~20) but as saturated; leaving it out moves the centroid to the near face (4 mm at 0.5 m)
  int s_min = 150, v_min = 15;
  double min_area_px = 20;          ///< smaller regions are not the yo-yo (noise)
  double max_area_fraction = 0.25;  ///< larger regions are not the yo-yo (a red wall)
};

/// "red" -> the red yo-yo's band (the default above). Throws InputError for
/// any other name.
BlobConfig BlobColor(const std::string& name);

struct Blob {
  bool found = false;
  double u = 0, v = 0;  ///< centroid, px (pixel centres at integer coordinates)
  double area_px = 0;   ///< of the filled outer contour
  int candidates = 0;   ///< regions of the colour, any size
};

/// Finds the largest region of the colour in an RGB8 image. `hsv` and `mask`
/// are scratch (reused between frames).
Blob FindBlob(const cv::Mat& rgb, const BlobConfig& config, cv::Mat* hsv, cv::Mat* mask);

/// The vertical line the yo-yo moves on, world frame, m.
struct YoyoLine {
  double x = 0.725, y = 0;  ///< scenes/pa10_yoyo.xml: under the tool tip in the ready pose
};

/// The point of pixel (u, v)'s ray in the vertical plane through the line
/// that faces the camera (see above). X_world_camera: the OpenCV camera frame
/// in the world. nullopt when the ray runs parallel to the plane or meets it
/// behind the camera, or the camera stands on the line.
std::optional<Eigen::Vector3d> LocateOnLine(double u, double v, const CameraModel& camera,
                                            const Eigen::Isometry3d& X_world_camera, const YoyoLine& line);

/// Per-frame yo-yo state from the blob and the geometry, as the yoyo device
/// sends it: [status, x, y, z, vz, string_force, spin]. string_force and spin
/// are not measured: 0. vz is the finite difference of z between this and the
/// previous seen frame (their exposure times), 0 for the first one or after a
/// gap longer than max_gap_s.
class YoyoTracker {
 public:
  YoyoTracker(const BlobConfig& blob, const YoyoLine& line, double max_gap_s = 0.5)
      : blob_(blob), line_(line), max_gap_s_(max_gap_s) {}

  /// One frame exposed at time_s. X_world_camera nullopt: the camera's pose
  /// is unknown (not seen). Returns the state (also in state()).
  const double* Track(const cv::Mat& rgb, const CameraModel& camera,
                      const std::optional<Eigen::Isometry3d>& X_world_camera, double time_s);

  const double* state() const { return state_; }
  bool seen() const { return seen_; }
  const Blob& blob() const { return last_blob_; }
  const BlobConfig& blob_config() const { return blob_; }
  const YoyoLine& line() const { return line_; }

 private:
  BlobConfig blob_;
  YoyoLine line_;
  double max_gap_s_;
  cv::Mat hsv_, mask_;
  Blob last_blob_;
  bool seen_ = false, ever_seen_ = false;
  double last_z_ = 0, last_time_s_ = 0;
  double state_[7] = {0, 0, 0, 0, 0, 0, 0};  // the yoyo state's 7 values (bridge_layouts.h)
};

}  // namespace vlab::vision
