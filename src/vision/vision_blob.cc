#include "vision/vision_blob.h"

#include <cmath>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "bridge/bridge_layouts.h"
#include "bridge/bridge_yoyo.h"
#include "core/core_errors.h"

namespace vlab::vision {

BlobConfig BlobColor(const std::string& name) {
  if (name == "red") return BlobConfig{};
  throw vlab::InputError("--blob-color '" + name + "': the colours known are: red");
}

Blob FindBlob(const cv::Mat& rgb, const BlobConfig& config, cv::Mat* hsv, cv::Mat* mask) {
  Blob blob;
  cv::cvtColor(rgb, *hsv, cv::COLOR_RGB2HSV);
  const double s = config.s_min, v = config.v_min;
  if (config.hue_lo > config.hue_hi) {  // the band wraps through hue 0 (red)
    cv::Mat upper;
    cv::inRange(*hsv, cv::Scalar(config.hue_lo, s, v), cv::Scalar(180, 255, 255), upper);
    cv::inRange(*hsv, cv::Scalar(0, s, v), cv::Scalar(config.hue_hi, 255, 255), *mask);
    cv::bitwise_or(*mask, upper, *mask);
  } else {
    cv::inRange(*hsv, cv::Scalar(config.hue_lo, s, v), cv::Scalar(config.hue_hi, 255, 255), *mask);
  }
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(*mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  blob.candidates = static_cast<int>(contours.size());
  if (contours.empty()) return blob;
  std::size_t best = 0;
  double best_area = -1;
  for (std::size_t i = 0; i < contours.size(); ++i) {
    const double a = cv::contourArea(contours[i]);
    if (a > best_area) {
      best_area = a;
      best = i;
    }
  }
  // the filled outer contour: holes inside it (the spin mark) count as the blob
  const cv::Rect box = cv::boundingRect(contours[best]);
  cv::Mat filled = cv::Mat::zeros(box.height, box.width, CV_8U);
  cv::drawContours(filled, contours, static_cast<int>(best), cv::Scalar(255), cv::FILLED, cv::LINE_8, cv::noArray(), 0,
                   cv::Point(-box.x, -box.y));
  const cv::Moments m = cv::moments(filled, true);
  const double max_area = config.max_area_fraction * rgb.cols * rgb.rows;
  if (m.m00 < config.min_area_px || m.m00 > max_area) return blob;
  blob.found = true;
  blob.area_px = m.m00;
  blob.u = box.x + m.m10 / m.m00;
  blob.v = box.y + m.m01 / m.m00;
  return blob;
}

std::optional<Eigen::Vector3d> LocateOnLine(double u, double v, const CameraModel& camera,
                                            const Eigen::Isometry3d& X_world_camera, const YoyoLine& line) {
  double xn = (u - camera.cx) / camera.fx, yn = (v - camera.cy) / camera.fy;
  if (!camera.distortion.empty()) {
    const cv::Matx33d K(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
    std::vector<cv::Point2d> in{{u, v}}, out;
    cv::undistortPoints(in, out, K, camera.distortion);
    xn = out[0].x;
    yn = out[0].y;
  }
  const Eigen::Vector3d c = X_world_camera.translation();
  const Eigen::Vector3d d = X_world_camera.linear() * Eigen::Vector3d(xn, yn, 1.0);
  const Eigen::Vector3d L(line.x, line.y, 0.0);
  Eigen::Vector3d n(c.x() - L.x(), c.y() - L.y(), 0.0);  // horizontal, towards the camera
  const double distance = n.norm();
  if (!(distance > 1e-9)) return std::nullopt;
  n /= distance;
  const double nd = n.dot(d);
  if (!(std::abs(nd) > 1e-12)) return std::nullopt;
  const double t = n.dot(L - c) / nd;
  if (!(t > 0) || !std::isfinite(t)) return std::nullopt;
  return c + t * d;
}

const double* YoyoTracker::Track(const cv::Mat& rgb, const CameraModel& camera,
                                 const std::optional<Eigen::Isometry3d>& X_world_camera, double time_s) {
  static_assert(sizeof(state_) / sizeof(state_[0]) == bridge::kYoyoValues);
  last_blob_ = FindBlob(rgb, blob_, &hsv_, &mask_);
  std::optional<Eigen::Vector3d> p;
  if (last_blob_.found && X_world_camera) p = LocateOnLine(last_blob_.u, last_blob_.v, camera, *X_world_camera, line_);
  seen_ = p.has_value();
  if (!seen_) {
    state_[bridge::kYoyoStatus] = static_cast<double>(bridge::kYoyoNotSeen);  // the values stay the last ones
    return state_;
  }
  const double dt = time_s - last_time_s_;
  const double vz = ever_seen_ && dt > 0 && dt <= max_gap_s_ ? (p->z() - last_z_) / dt : 0.0;
  state_[bridge::kYoyoStatus] = 0;
  state_[bridge::kYoyoX] = p->x();
  state_[bridge::kYoyoY] = p->y();
  state_[bridge::kYoyoZ] = p->z();
  state_[bridge::kYoyoVz] = vz;
  state_[bridge::kYoyoStringForce] = 0;  // not measured by vision
  state_[bridge::kYoyoSpin] = 0;         // not measured by vision
  ever_seen_ = true;
  last_z_ = p->z();
  last_time_s_ = time_s;
  return state_;
}

}  // namespace vlab::vision
