#include "lab/outputs/lab_poses.h"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "core/core_clock.h"
#include "core/core_errors.h"
#include "lab/devices/device_scene.h"
#include "lab/outputs/lab_log.h"
#include "lab/outputs/lab_output.h"

namespace vlab::lab {

std::unique_ptr<PoseRecorder> PoseRecorder::Create(const mjModel* m, double rate_hz, double period_s,
                                                   const std::string& scene, const std::string& where) {
  std::unique_ptr<PoseRecorder> r(new PoseRecorder());
  r->m_ = m;
  r->scene_ = scene;
  r->interval_s_ = rate_hz > 0 ? 1.0 / rate_hz : period_s;
  r->rate_hz_ = 1.0 / r->interval_s_;
  if (r->interval_s_ < period_s - kSameTime_s) {
    throw InputError(where + ": outputs.poses.rate: " + FormatDouble(rate_hz) +
                     " Hz is faster than the control rate (" + FormatDouble(1.0 / period_s) + " Hz)");
  }
  r->bodies_ = SceneBodies(m);
  r->poses_.assign(7 * r->bodies_.size(), 0.0);
  r->frame_.reserve(16 + 28 * r->bodies_.size());
  return r;
}

PoseRecorder::~PoseRecorder() {
  if (file_) std::fclose(file_);
}

nlohmann::json PoseRecorder::Geometry() const { return SceneGeometry(m_, bodies_); }

void PoseRecorder::Open(const OutputDir& out) {
  nlohmann::json scene = Geometry();
  scene["model"] = scene_;
  scene["rate_hz"] = rate_hz_;
  const std::string json_path = out.File("scene.json");
  std::ofstream json(json_path);
  json << scene.dump() << "\n";
  if (!json) throw std::runtime_error("poses: cannot write '" + json_path + "'");
  path_ = out.File("poses.bin");
  file_ = std::fopen(path_.c_str(), "wb");
  if (!file_) throw std::runtime_error("poses: cannot write '" + path_ + "'");
}

void PoseRecorder::Observe(double t, double k, const mjData& d) {
  if (!file_ || write_errno_ != 0 || t + kSameTime_s < next_) return;
  next_ += interval_s_;
  if (next_ < t + kSameTime_s) next_ = t + interval_s_;
  ScenePoses(d, bodies_, poses_.data());
  last_time_s_ = t;
  EncodePoseFrame(t, k, poses_.data(), static_cast<int>(poses_.size()), &frame_);
  errno = 0;
  if (std::fwrite(frame_.data(), 1, frame_.size(), file_) != frame_.size()) write_errno_ = errno ? errno : EIO;
  ++frames_;
}

void PoseRecorder::Finish() {
  if (!file_) return;
  errno = 0;
  if (std::fclose(file_) != 0 && write_errno_ == 0) write_errno_ = errno ? errno : EIO;
  file_ = nullptr;
  if (failed()) throw std::runtime_error(error());
}

std::vector<std::string> PoseRecorder::body_names() const {
  std::vector<std::string> names;
  for (int b : bodies_) {
    const char* name = mj_id2name(m_, mjOBJ_BODY, b);
    names.push_back(name ? name : "");
  }
  return names;
}

std::string PoseRecorder::error() const {
  return write_errno_ == 0 ? "" : "poses '" + path_ + "': write failed: " + std::strerror(write_errno_);
}

}  // namespace vlab::lab
