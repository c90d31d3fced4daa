#include "lab/outputs/lab_log_mcap.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "scene/scene_geometry.h"

namespace vlab::lab {

namespace {

constexpr int kPose = scene::kPoseValues;

// a frame's PNG file in its camera's folder (ImageOutputs' names)
std::string RgbPath(const std::string& folder, long frame) {
  char name[32];
  std::snprintf(name, sizeof(name), "rgb_%06ld.png", frame);
  return folder + "/" + name;
}

// how many of `interval_s` fit the periods the writer may be behind, and a spare
std::size_t RingSlots(double interval_s, double period_s) {
  const double span_s = (RunLog::kBlocks + 1.0) * RunLog::kRowsPerBlock * period_s;
  return static_cast<std::size_t>(std::ceil(span_s / std::max(interval_s, period_s))) + 2;
}

}  // namespace

std::uint64_t McapTime(double t) { return static_cast<std::uint64_t>(std::llround(t * 1e9)); }

std::unique_ptr<McapLog> McapLog::Open(const std::string& path, const std::vector<std::string>& columns,
                                       McapLogContent content, const McapOptions& options) {
  std::unique_ptr<McapLog> log(new McapLog());
  log->path_ = path;
  log->n_ = columns.size();
  const auto time = std::find(columns.begin(), columns.end(), "time");
  if (time == columns.end()) throw std::runtime_error("log '" + path + "': the log has no column 'time'");
  log->time_column_ = static_cast<int>(time - columns.begin());
  std::sort(content.cameras.begin(), content.cameras.end(),
            [](const McapCamera& a, const McapCamera& b) { return a.name < b.name; });
  log->content_ = std::move(content);
  log->writer_ = McapWriter::Create(path, "log '" + path + "'", options);
  McapWriter& w = *log->writer_;
  // the schemas and channels, all before the first chunk
  log->signals_ = scene::SignalChannels(columns);
  for (const scene::SignalChannel& s : log->signals_) {
    w.AddChannel(w.AddSchema(s.schema.name, scene::kSchemaEncoding, s.schema.text), s.topic, scene::kMessageEncoding);
  }
  const std::vector<std::string>& bodies = log->content_.bodies;
  const nlohmann::json* geometry = log->content_.scene.get();
  std::string scene_update;  // written once every channel is there
  std::uint16_t scene_channel = 0;
  if (geometry) {
    const scene::MessageSchema update = scene::SceneUpdateSchema();
    scene_channel =
        w.AddChannel(w.AddSchema(update.name, scene::kSchemaEncoding, update.text), "/scene", scene::kMessageEncoding);
    try {
      scene::EncodeSceneUpdate(0.0, *geometry, nullptr, &scene_update);
    } catch (const std::exception& e) {
      throw std::runtime_error("log '" + path + "': the scene's geometry: " + e.what());
    }
  }
  if (!bodies.empty()) {
    const scene::MessageSchema tf = scene::TfMessageSchema();
    log->tf_channel_ =
        w.AddChannel(w.AddSchema(tf.name, scene::kSchemaEncoding, tf.text), "/tf", scene::kMessageEncoding);
    const std::vector<std::string> frames = geometry ? scene::BodyFrames(*geometry) : std::vector<std::string>();
    if (geometry && frames.size() != bodies.size()) {
      throw std::runtime_error("log '" + path + "': the scene's geometry has " + std::to_string(frames.size()) +
                               " bodies, the poses " + std::to_string(bodies.size()));
    }
    for (std::size_t b = 0; b < bodies.size(); ++b) {
      scene::FrameTransform& transform = log->transforms_.emplace_back();
      transform.parent = "world";
      transform.child = geometry ? frames[b] : bodies[b].empty() ? "body_" + std::to_string(b) : bodies[b];
    }
  }
  if (!log->content_.cameras.empty()) {
    const scene::MessageSchema image = scene::CompressedImageSchema();
    const std::uint16_t schema = w.AddSchema(image.name, scene::kSchemaEncoding, image.text);
    for (std::size_t c = 0; c < log->content_.cameras.size(); ++c) {
      const std::uint16_t id =
          w.AddChannel(schema, "/camera/" + log->content_.cameras[c].name, scene::kMessageEncoding);
      if (c == 0) log->first_camera_channel_ = id;
    }
  }
  log->frames_.resize(log->content_.cameras.size());
  if (geometry) {
    const std::string why = w.Write(scene_channel, 0, scene_update.data(), scene_update.size());
    if (!why.empty()) throw std::runtime_error(why);
  }
  return log;
}

void McapLog::AddPoses(double t, const float* poses) {
  poses_.push_back({t, 0, std::vector<float>(poses, poses + kPose * transforms_.size())});
}

int McapLog::CameraIndex(const std::string& name) const {
  for (std::size_t c = 0; c < content_.cameras.size(); ++c) {
    if (content_.cameras[c].name == name) return static_cast<int>(c);
  }
  return -1;
}

void McapLog::AddFrame(int camera, long frame, double t) { frames_.at(camera).push_back({t, frame, {}}); }

std::string McapLog::WritePoses(const Pending& p) {
  for (std::size_t b = 0; b < transforms_.size(); ++b) {
    const float* v = p.poses.data() + kPose * b;
    scene::FrameTransform& transform = transforms_[b];
    for (int i = 0; i < 3; ++i) transform.translation[i] = v[i];
    for (int i = 0; i < 4; ++i) transform.rotation_wxyz[i] = v[3 + i];
  }
  scene::EncodeTfMessage(p.t, transforms_.data(), transforms_.size(), &message_);
  return writer_->Write(tf_channel_, McapTime(p.t), message_.data(), message_.size());
}

std::string McapLog::WriteFrame(int camera, const Pending& p) {
  const McapCamera& c = content_.cameras[camera];
  const std::string file = RgbPath(c.folder, p.frame);
  std::ifstream in(file, std::ios::binary);
  png_.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) {
    return "log '" + path_ + "': camera '" + c.name + "' frame " + std::to_string(p.frame) + ": cannot read '" + file +
           "'";
  }
  scene::EncodeCompressedImage(p.t, c.name, "png", reinterpret_cast<const std::uint8_t*>(png_.data()), png_.size(),
                               &message_);
  return writer_->Write(static_cast<std::uint16_t>(first_camera_channel_ + camera), McapTime(p.t), message_.data(),
                        message_.size());
}

std::string McapLog::WriteBefore(double t, bool all) {
  // the earliest first; at one time the poses, then the cameras in order
  for (;;) {
    int next = -2;  // -1: poses, c >= 0: camera c
    double next_t = 0;
    if (!poses_.empty() && (all || poses_.front().t < t)) {
      next = -1;
      next_t = poses_.front().t;
    }
    for (std::size_t c = 0; c < frames_.size(); ++c) {
      if (frames_[c].empty() || !(all || frames_[c].front().t < t)) continue;
      if (next == -2 || frames_[c].front().t < next_t) {
        next = static_cast<int>(c);
        next_t = frames_[c].front().t;
      }
    }
    if (next == -2) return "";
    std::deque<Pending>& queue = next == -1 ? poses_ : frames_[next];
    const std::string why = next == -1 ? WritePoses(queue.front()) : WriteFrame(next, queue.front());
    queue.pop_front();
    if (!why.empty()) return why;
  }
}

std::string McapLog::AddRows(const double* rows, int count) {
  for (int r = 0; r < count; ++r) {
    const double* row = rows + static_cast<std::size_t>(r) * n_;
    const double t = row[time_column_];
    std::string why = WriteBefore(t, false);
    for (const scene::SignalChannel& s : signals_) {
      if (!why.empty()) return why;
      scene::EncodeSignals(t, s, row, &message_);
      why = writer_->Write(static_cast<std::uint16_t>(&s - signals_.data()), McapTime(t), message_.data(),
                           message_.size());
    }
    if (!why.empty()) return why;
  }
  return "";
}

std::string McapLog::Close() {
  if (!writer_) return "";
  const std::string why = WriteBefore(0, true);
  const std::string closed = writer_->Close();
  writer_.reset();
  return why.empty() ? closed : why;
}

template <typename T>
void McapLogSink::Ring<T>::Resize(std::size_t slots, std::size_t slot_size) {
  slots_ = slots + 1;  // one always empty: full and empty differ
  slot_size_ = slot_size;
  data_.assign(slots_ * slot_size, T{});
}

template <typename T>
T* McapLogSink::Ring<T>::Slot() {
  const std::size_t tail = tail_.load(std::memory_order_relaxed);
  if ((tail + 1) % slots_ == head_.load(std::memory_order_acquire)) return nullptr;
  return data_.data() + tail * slot_size_;
}

template <typename T>
void McapLogSink::Ring<T>::Push() {
  tail_.store((tail_.load(std::memory_order_relaxed) + 1) % slots_, std::memory_order_release);
}

template <typename T>
const T* McapLogSink::Ring<T>::Front() {
  const std::size_t head = head_.load(std::memory_order_relaxed);
  if (head == tail_.load(std::memory_order_acquire)) return nullptr;
  return data_.data() + head * slot_size_;
}

template <typename T>
void McapLogSink::Ring<T>::Pop() {
  head_.store((head_.load(std::memory_order_relaxed) + 1) % slots_, std::memory_order_release);
}

McapLogSink::McapLogSink(const std::string& path, const std::vector<std::string>& columns, McapLogContent content)
    : path_(path) {
  log_ = McapLog::Open(path, columns, std::move(content));
  const McapLogContent& c = log_->content();
  pose_values_ = kPose * c.bodies.size();
  if (!c.bodies.empty()) poses_.Resize(RingSlots(c.poses_interval_s, c.period_s), 1 + pose_values_);
  std::size_t frames = 0;
  for (const McapCamera& camera : c.cameras) frames += RingSlots(camera.every_s, c.period_s);
  frames_.Resize(std::max<std::size_t>(frames, 1), 3);
}

McapLogSink::~McapLogSink() = default;

void McapLogSink::PushPoses(double t, const double* poses) {
  if (pose_values_ == 0) return;
  double* slot = poses_.Slot();
  if (!slot) {
    overflow_.store(true, std::memory_order_relaxed);
    return;
  }
  slot[0] = t;
  std::memcpy(slot + 1, poses, pose_values_ * sizeof(double));
  poses_.Push();
}

void McapLogSink::PushFrame(int camera, long frame, double t) {
  double* slot = frames_.Slot();
  if (!slot) {
    overflow_.store(true, std::memory_order_relaxed);
    return;
  }
  slot[0] = camera;
  slot[1] = static_cast<double>(frame);
  slot[2] = t;
  frames_.Push();
}

void McapLogSink::Drain() {
  std::vector<float> poses(pose_values_);
  while (const double* slot = poses_.Front()) {
    // float32, as poses.bin holds them (scene_pose_frame.h)
    for (std::size_t i = 0; i < pose_values_; ++i) poses[i] = static_cast<float>(slot[1 + i]);
    log_->AddPoses(slot[0], poses.data());
    poses_.Pop();
  }
  while (const double* slot = frames_.Front()) {
    log_->AddFrame(static_cast<int>(slot[0]), static_cast<long>(slot[1]), slot[2]);
    frames_.Pop();
  }
}

std::string McapLogSink::Write(const double* rows, int count) {
  if (overflow_.load(std::memory_order_relaxed)) {
    return "log '" + path_ + "': more poses or frames than the writer's queue holds";
  }
  Drain();
  return log_->AddRows(rows, count);
}

std::string McapLogSink::Close() {
  Drain();
  return log_->Close();
}

}  // namespace vlab::lab
