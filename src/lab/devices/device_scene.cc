// A scene stream (kind scene): what a viewer needs to draw the lab, the role
// RoboWorks and Blender had in the original lab. The describe reply carries
// the visual geometry (SceneGeometry); the state carries the pose of every
// visual body at a decimated rate.
//
// Ports
//   input   none
//   output  [x, y, z, qw, qx, qy, qz] of every body of SceneBodies(), world
//           frame (m, unit quaternion), in the describe reply's "bodies" order;
//           then the values of the `signals` (log columns, e.g. pa10.q.S1) in
//           the log row of the same period, in the reply's "signals" order
//   rate    a frame is due every 1 / rate s (rate 0: every control period) and
//           sampled at the first period end at or after that time; only due
//           frames are published, so subscribers get `rate` frames per second
//   log     none: the stream only copies xpos, xquat and the signals' log
//           values into a buffer sized at creation, so the run, its log and
//           its timing do not depend on it
#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "bridge/bridge_layouts.h"
#include "core/core_clock.h"
#include "core/core_errors.h"
#include "lab/devices/device_scene.h"
#include "lab/outputs/lab_log.h"
#include "lab/scenario/lab_yaml.h"

namespace vlab::lab {

namespace {

using scene::kPoseValues;  // x, y, z, qw, qx, qy, qz

std::string NameOf(const mjModel* m, mjtObj type, int id) {
  const char* name = mj_id2name(m, type, id);
  return name ? name : "";
}

class SimScene final : public Device, public LogReader {
 public:
  SimScene(const DeviceContext& context, const DeviceConfig& c)
      : Device(c), config_(c.ParamsAs<SceneParams>()), model_(context.model), scene_(context.scene) {
    capabilities_.log_reader = this;
    const double period_s = context.control_period_s;
    interval_s_ = config_.rate_hz > 0 ? 1.0 / config_.rate_hz : period_s;
    if (interval_s_ < period_s - kSameTime_s) {
      throw InputError(who() + ": rate " + FormatDouble(config_.rate_hz) + " Hz is faster than the control rate (" +
                       FormatDouble(1.0 / period_s) + " Hz)");
    }
    bodies_ = SceneBodies(model_);
    if (bodies_.empty()) throw InputError(who() + ": the scene has no body with a visible geom to stream");
    const int values = kPoseValues * static_cast<int>(bodies_.size()) + static_cast<int>(config_.signals.size());
    if (values + bridge::kHeaderValues > bridge::kMaxPacketValues) {
      throw InputError(who() + ": " + std::to_string(bodies_.size()) + " visual bodies and " +
                       std::to_string(config_.signals.size()) + " signals need " + std::to_string(values) +
                       " values, more than a datagram holds (" +
                       std::to_string(bridge::kMaxPacketValues - bridge::kHeaderValues) + ")");
    }
    poses_.assign(values, 0.0);
  }

  void BindLog(const std::vector<std::string>& columns) override {
    signal_columns_.clear();
    for (const std::string& signal : config_.signals) {
      const auto at = std::find(columns.begin(), columns.end(), signal);
      if (at == columns.end()) {
        throw InputError(who() + ": signals: the log has no column '" + signal +
                         "' (signals are log.csv columns, "
                         "e.g. ARM.q.JOINT)");
      }
      signal_columns_.push_back(static_cast<int>(at - columns.begin()));
    }
  }

  void LogRow(const double* row) override {
    if (!due_) return;
    double* out = poses_.data() + kPoseValues * bodies_.size();
    for (std::size_t i = 0; i < signal_columns_.size(); ++i) out[i] = row[signal_columns_[i]];
  }

  void Reset(const mjData& d) override {
    next_frame_ = d.time;
    Sample(d, d.time);
  }

  void Sample(const mjData& d, double t) override {
    due_ = t + kSameTime_s >= next_frame_;
    if (!due_) return;
    ScenePoses(d, bodies_, poses_.data());
    next_frame_ += interval_s_;
    if (next_frame_ < t + kSameTime_s) next_frame_ = t + interval_s_;  // an interval shorter than a period
  }

  bool PublishDue() const override { return due_; }
  void State(std::vector<double>* p) const override { p->assign(poses_.begin(), poses_.end()); }

  std::string DescribeFacts() const override {
    std::vector<std::string> values;
    for (int b : bodies_) {
      const std::string body = NameOf(model_, mjOBJ_BODY, b);
      for (const char* v : {".x", ".y", ".z", ".qw", ".qx", ".qy", ".qz"}) values.push_back(body + v);
    }
    for (const std::string& signal : config_.signals) values.push_back("signal." + signal);
    nlohmann::json j = SceneGeometry(model_, bodies_);
    j["layout"] = bridge::LayoutJson(kind(), values);
    j["units"] = {{"x", "m"}, {"y", "m"}, {"z", "m"}, {"qw", ""}, {"qx", ""}, {"qy", ""}, {"qz", ""}};
    j["frame"] = "world";
    j["rate_hz"] = 1.0 / interval_s_;
    j["signals"] = config_.signals;
    j["model"] = scene_;
    return j.dump();
  }

 private:
  SceneParams config_;
  const mjModel* model_;
  std::string scene_;
  double interval_s_ = 0;
  std::vector<int> bodies_;
  std::vector<double> poses_;  // the poses, then the signals
  std::vector<int> signal_columns_;
  double next_frame_ = 0;
  bool due_ = false;
};

}  // namespace

std::shared_ptr<const DeviceParams> ReadSceneParams(MapReader& r) {
  auto p = std::make_shared<SceneParams>();
  p->rate_hz = r.Number("rate", p->rate_hz);
  if (!(p->rate_hz >= 0 && std::isfinite(p->rate_hz))) r.Fail("rate", "must be >= 0 Hz (0: every control period)");
  p->signals = r.Strings("signals", {});
  if (static_cast<int>(p->signals.size()) > kMaxSceneSignals) {
    r.Fail("signals", "at most " + std::to_string(kMaxSceneSignals) + " log columns");
  }
  for (std::size_t i = 0; i < p->signals.size(); ++i) {
    if (p->signals[i].empty()) r.Fail("signals", "a signal name is empty");
    for (std::size_t j = 0; j < i; ++j) {
      if (p->signals[i] == p->signals[j]) r.Fail("signals", "'" + p->signals[i] + "' is listed twice");
    }
  }
  return p;
}

std::unique_ptr<Device> MakeScene(const DeviceContext& context, const DeviceConfig& config) {
  return std::make_unique<SimScene>(context, config);
}

}  // namespace vlab::lab
