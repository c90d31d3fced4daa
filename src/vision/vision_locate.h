// From one camera image to one markers state: detect the markers of every
// dictionary in the marker table, estimate the pose of each described one in
// the camera frame, and, when the camera's pose in the world is known, in the
// world frame: X_world_marker = X_world_camera * X_camera_marker.
#pragma once

#include <map>
#include <optional>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "bridge/bridge_markers.h"
#include "vision/vision_detector.h"

namespace vlab::vision {

/// The markers to track: (dictionary code, id) -> side, m.
class MarkerTable {
 public:
  explicit MarkerTable(std::size_t capacity = 1024) : capacity_(capacity) {}
  /// Applies descriptions in order (side 0 removes an entry). All or
  /// nothing: false, and no change, when the table would exceed its capacity.
  bool Apply(const std::vector<bridge::MarkerDescriptionMsg>& descriptions);
  /// Side of a marker, m; 0 when it is not in the table.
  double SideOf(int dictionary, int id) const;
  /// Dictionary codes with at least one entry, ascending.
  std::vector<int> Dictionaries() const;
  /// Entries ordered by dictionary, then id.
  std::vector<bridge::MarkerDescriptionMsg> Entries() const;
  std::size_t size() const { return sides_.size(); }
  std::size_t capacity() const { return capacity_; }

 private:
  std::size_t capacity_;
  std::map<std::pair<int, int>, double> sides_;
};

/// What LocateMarkers found besides the state.
struct LocateStats {
  int detected = 0;  ///< markers found in the image (described or not)
  int reported = 0;  ///< markers put in the state
  int valid = 0;     ///< of those, valid
  int dropped = 0;   ///< described markers beyond kMaxMarkersPerState, left out
};

/// Detects and locates the table's markers in an 8-bit grey image. The state
/// lists the described markers ordered by (dictionary, id, detection order),
/// at most kMaxMarkersPerState of them. `X_world_camera` is the OpenCV camera
/// frame in the world, when known. `out`'s vectors are reused.
LocateStats LocateMarkers(const cv::Mat& grey, const CameraModel& camera,
                          const std::optional<Eigen::Isometry3d>& X_world_camera, const MarkerTable& table,
                          const MarkerDetector& detector, bridge::MarkersStateMsg* out,
                          std::vector<MarkerPose>* poses = nullptr);

/// Row-major 16 values of a transform.
void ToRowMajor(const Eigen::Isometry3d& X, double* out);

}  // namespace vlab::vision
