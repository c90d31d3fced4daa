// The run log as MCAP (log.mcap, lab_mcap.h), in ROS 2 messages
// (scene/scene_messages.h: schema encoding ros2msg, message encoding cdr), so
// that Foxglove and Lichtblick open a run with its plots, frames and images on
// one timeline:
//   /DEVICE        vlab_msgs/msg/<Device>: each device's log columns at every
//                  row (SignalChannels; the column "time" is the stamp)
//   /scene         foxglove_msgs/msg/SceneUpdate: the visual geometry of
//                  scene.json once at t = 0, an entity per body locked to its
//                  /tf frame (EncodeSceneUpdate; meshes left out: the file
//                  follows from the run folder alone, which has no mesh
//                  vertices); absent without outputs.poses
//   /tf            tf2_msgs/msg/TFMessage: every visual body's pose in
//                  "world" at outputs.poses' rate (the float32 values of
//                  poses.bin, frames named by BodyFrames; absent without
//                  outputs.poses)
//   /camera/NAME   sensor_msgs/msg/CompressedImage: each frame of an
//                  outputs.images camera with png: true, the bytes of its
//                  CAMERA/rgb_NNNNNN.png (cameras in name order)
// Every message's log and publish time is its row's or frame's simulated time
// in ns. Channels in that order: the devices, /tf, the cameras. A pose or
// frame at time t is written just before the first row later than t (at the
// end, after the last row), so the file's bytes follow from its contents
// alone, whichever thread handed them over when: a run and `vlab convert` of
// its log.csv, poses.bin and frames write the same file.
//
// Threads (McapLogSink): rows arrive on the log's writer thread (LogSink),
// poses and frames on the step loop's thread (PushPoses, PushFrame). Those go
// through two single-producer single-consumer rings sized for every pose and
// frame of kBlocks + 1 blocks of rows (the most the writer can be behind before
// the log itself makes the step loop wait), which the writer thread empties
// before each block: the step loop takes no lock and never waits here, and the
// writer alone compresses and writes. A frame is read from its PNG file, which
// ImageOutputs wrote whole before it was pushed.
// An interrupted run closes the log normally: the file is complete, with every
// period run. A killed run leaves every chunk written so far (lab_mcap.h).
#pragma once

#include <atomic>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "lab/outputs/lab_log.h"
#include "lab/outputs/lab_mcap.h"
#include "scene/scene_messages.h"

namespace vlab::lab {

/// An outputs.images camera whose frames log.mcap carries.
struct McapCamera {
  std::string name;    ///< the MJCF camera: topic /camera/NAME, frame_id NAME
  std::string folder;  ///< where its rgb_NNNNNN.png files are
  double every_s = 0;  ///< its frame interval (sizes the live ring)
};

/// What log.mcap carries besides the log's columns.
struct McapLogContent {
  /// The bodies of poses.bin, in order (an empty name becomes "body_N", N its
  /// index); empty: no /tf.
  std::vector<std::string> bodies;
  /// The scene's visual geometry (scene.json, scene::SceneGeometry), whose
  /// "bodies" are `bodies`: a /scene message at t = 0, and the /tf frames are
  /// BodyFrames'. Null: no /scene.
  std::shared_ptr<const nlohmann::json> scene;
  double poses_interval_s = 0;  ///< the live ring's sizing: one pose per interval
  std::vector<McapCamera> cameras;
  double period_s = 0;  ///< the control period (the live rings' sizing)
};

/// The contents of log.mcap merged in time order into an McapWriter. One thread.
class McapLog {
 public:
  /// Creates `path` with the schemas and channels of `columns` (which must
  /// hold "time") and `content`. Throws std::runtime_error naming the file.
  static std::unique_ptr<McapLog> Open(const std::string& path, const std::vector<std::string>& columns,
                                       McapLogContent content, const McapOptions& options = {});
  /// A /tf message at t of 7 floats per body (x, y, z, qw, qx, qy, qz).
  void AddPoses(double t, const float* poses);
  /// Frame `frame` of camera `camera` (index into content.cameras) at t.
  void AddFrame(int camera, long frame, double t);
  /// Rows of columns.size() values; before each, the poses and frames earlier
  /// than it. "" or why not (a write, a frame's file that cannot be read).
  std::string AddRows(const double* rows, int count);
  /// The poses and frames left, then the file completed. "" or why not.
  std::string Close();
  const McapLogContent& content() const { return content_; }
  /// The index of camera `name` in content().cameras (name order), or -1.
  int CameraIndex(const std::string& name) const;

 private:
  struct Pending {
    double t;
    long frame;  // a frame's number (poses: unused)
    std::vector<float> poses;
  };
  McapLog() = default;
  std::string WriteBefore(double t, bool all);  // the poses and frames earlier than t (all: every one)
  std::string WritePoses(const Pending& p);
  std::string WriteFrame(int camera, const Pending& p);

  std::string path_;
  std::unique_ptr<McapWriter> writer_;
  McapLogContent content_;
  std::size_t n_ = 0;
  int time_column_ = 0;
  std::vector<scene::SignalChannel> signals_;
  std::uint16_t tf_channel_ = 0, first_camera_channel_ = 0;
  std::vector<scene::FrameTransform> transforms_;
  std::deque<Pending> poses_;
  std::vector<std::deque<Pending>> frames_;  // per camera
  std::string message_, png_;                // reused buffers
};

/// Nanoseconds of a time t >= 0 (s), to the nearest: a message's log time.
std::uint64_t McapTime(double t);

/// The log's MCAP sink (see the header comment for its threads).
class McapLogSink : public LogSink {
 public:
  /// Throws std::runtime_error naming the file when it cannot be created.
  McapLogSink(const std::string& path, const std::vector<std::string>& columns, McapLogContent content);
  ~McapLogSink() override;

  /// Step loop: a pose frame at t, 7 doubles per body (written as float32).
  /// Lock-free, never waits; a full ring (never, by its size) fails the log.
  void PushPoses(double t, const double* poses);
  /// The index PushFrame takes for camera `name` (McapLog::CameraIndex).
  int CameraIndex(const std::string& name) const { return log_->CameraIndex(name); }
  /// Step loop: frame `frame` of camera `camera` was written whole at t.
  void PushFrame(int camera, long frame, double t);

  std::string Write(const double* rows, int count) override;
  std::string Close() override;

 private:
  // a single-producer single-consumer ring of fixed-size slots of T
  template <typename T>
  class Ring {
   public:
    void Resize(std::size_t slots, std::size_t slot_size);
    T* Slot();         // producer: the slot to fill, or null when full
    void Push();       // producer: publishes the slot Slot() returned
    const T* Front();  // consumer: the oldest slot, or null when empty
    void Pop();        // consumer: frees it

   private:
    std::vector<T> data_;
    std::size_t slots_ = 0, slot_size_ = 0;
    std::atomic<std::size_t> head_{0}, tail_{0};
  };
  void Drain();  // writer thread: the rings into the log

  std::string path_;
  std::unique_ptr<McapLog> log_;
  std::size_t pose_values_ = 0;
  Ring<double> poses_;   // t, then 7 per body
  Ring<double> frames_;  // camera, frame, t
  std::atomic<bool> overflow_{false};
};

}  // namespace vlab::lab
