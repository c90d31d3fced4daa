#include "vision/vision_locate.h"

#include <algorithm>
#include <cmath>

namespace vlab::vision {

bool MarkerTable::Apply(const std::vector<bridge::MarkerDescriptionMsg>& descriptions) {
  // the size after the whole packet, before changing anything
  std::map<std::pair<int, int>, double> next = sides_;
  for (const bridge::MarkerDescriptionMsg& d : descriptions) {
    if (d.side_m > 0) {
      next[{d.dictionary, d.id}] = d.side_m;
    } else {
      next.erase({d.dictionary, d.id});
    }
  }
  if (next.size() > capacity_) return false;
  sides_.swap(next);
  return true;
}

double MarkerTable::SideOf(int dictionary, int id) const {
  const auto it = sides_.find({dictionary, id});
  return it == sides_.end() ? 0.0 : it->second;
}

std::vector<int> MarkerTable::Dictionaries() const {
  std::vector<int> codes;
  for (const auto& [key, side] : sides_) {
    if (codes.empty() || codes.back() != key.first) codes.push_back(key.first);
  }
  return codes;
}

std::vector<bridge::MarkerDescriptionMsg> MarkerTable::Entries() const {
  std::vector<bridge::MarkerDescriptionMsg> entries;
  for (const auto& [key, side] : sides_) entries.push_back({key.first, key.second, side});
  return entries;
}

void ToRowMajor(const Eigen::Isometry3d& X, double* out) {
  const Eigen::Matrix4d& m = X.matrix();
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) out[4 * r + c] = m(r, c);
  }
}

LocateStats LocateMarkers(const cv::Mat& grey, const CameraModel& camera,
                          const std::optional<Eigen::Isometry3d>& X_world_camera, const MarkerTable& table,
                          const MarkerDetector& detector, bridge::MarkersStateMsg* out,
                          std::vector<MarkerPose>* poses) {
  LocateStats stats;
  std::vector<MarkerDetection> found;
  for (int code : table.Dictionaries()) detector.Detect(grey, code, &found);
  stats.detected = static_cast<int>(found.size());
  std::stable_sort(found.begin(), found.end(), [](const MarkerDetection& a, const MarkerDetection& b) {
    return a.dictionary != b.dictionary ? a.dictionary < b.dictionary : a.id < b.id;
  });

  out->described = static_cast<int>(table.size());
  out->unknown = 0;
  out->markers.clear();
  if (poses != nullptr) poses->clear();
  for (const MarkerDetection& d : found) {
    const double side = table.SideOf(d.dictionary, d.id);
    if (side <= 0) {
      ++out->unknown;
      continue;
    }
    if (static_cast<int>(out->markers.size()) >= bridge::kMaxMarkersPerState) {
      ++stats.dropped;
      continue;
    }
    const MarkerPose pose = detector.EstimatePose(d, side, camera);
    bridge::MarkerRecordMsg r;
    r.dictionary = d.dictionary;
    r.id = d.id;
    r.valid = pose.valid;
    r.reprojection_error_px = std::isfinite(pose.reprojection_error_px) ? pose.reprojection_error_px : 1e9;
    ToRowMajor(pose.X_camera_marker, r.T_camera);
    r.world_valid = X_world_camera.has_value();
    if (r.world_valid) ToRowMajor(*X_world_camera * pose.X_camera_marker, r.T_world);
    out->markers.push_back(r);
    if (poses != nullptr) poses->push_back(pose);
    ++stats.reported;
    stats.valid += pose.valid ? 1 : 0;
  }
  return stats;
}

}  // namespace vlab::vision
