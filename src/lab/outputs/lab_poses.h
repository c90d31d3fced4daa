// The pose recording of a run (outputs: {poses: {rate: HZ}}): the pose of
// every visual body at a decimated rate, for `vlab view --replay` and
// `vlab export` (glTF). Written into the run's output folder:
//   scene.json  the visual geometry (SceneGeometry: bodies, geoms, meshes,
//               textures), the MJCF path ("model") and "rate_hz"
//   poses.bin   frames back to back, each 16 + 28 n bytes, little-endian:
//               float64 time (s), float64 period k, then float32 x, y, z, qw,
//               qx, qy, qz of each of the n bodies, world frame: the bytes of
//               a scene stream's frame as `vlab view` sends it to the page
// Observing only reads mjData: a run's log is the same with or without it.
#pragma once

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>
#include <nlohmann/json_fwd.hpp>

#include "scene/scene_pose_frame.h"

namespace vlab::lab {

class OutputDir;

/// The bytes of one pose frame (scene/scene_pose_frame.h, shared with the view).
using scene::EncodePoseFrame;

class PoseRecorder {
 public:
  /// Frames every 1 / rate_hz s at the first period end at or after each
  /// (rate 0: every period). Throws InputError (naming `where`) when the rate
  /// is faster than the control rate.
  static std::unique_ptr<PoseRecorder> Create(const mjModel* m, double rate_hz, double period_s,
                                              const std::string& scene, const std::string& where);
  ~PoseRecorder();
  /// Writes scene.json and opens poses.bin in the staging folder; throws
  /// std::runtime_error naming the file when it cannot.
  void Open(const OutputDir& out);
  /// At every period end t (k = period): a frame when one is due.
  void Observe(double t, double k, const mjData& d);
  /// Closes poses.bin; throws std::runtime_error (error()) when a write failed.
  void Finish();
  /// True once a write to poses.bin failed (Observe goes on writing nothing).
  bool failed() const { return write_errno_ != 0; }
  /// "poses 'PATH': write failed: ERRNO TEXT" once failed(), else "".
  std::string error() const;
  long frames() const { return frames_; }
  /// The last frame's time (s) and poses (7 doubles per body, before their
  /// float32 rounding in poses.bin).
  double last_time_s() const { return last_time_s_; }
  const std::vector<double>& poses() const { return poses_; }
  /// The bodies' MJCF names, in frame order ("" for an unnamed body).
  std::vector<std::string> body_names() const;
  /// The visual geometry of the recorded bodies, as scene.json holds it less
  /// "model" and "rate_hz" (scene::SceneGeometry).
  nlohmann::json Geometry() const;
  /// The time between frames, s.
  double interval_s() const { return interval_s_; }

 private:
  PoseRecorder() = default;
  const mjModel* m_ = nullptr;
  std::vector<int> bodies_;
  std::vector<double> poses_;
  std::string frame_, scene_, path_;
  double interval_s_ = 0, next_ = 0, rate_hz_ = 0, last_time_s_ = 0;
  std::FILE* file_ = nullptr;
  long frames_ = 0;
  int write_errno_ = 0;  // the errno of the first failed write (0: none)
};

}  // namespace vlab::lab
