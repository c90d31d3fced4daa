// Image outputs of a run (the scenario's outputs.images): PNG frames (RGB,
// 16-bit depth in mm, 16-bit segmentation) and MP4 videos of MJCF cameras,
// written into the run's staging folder.
//
// Ports: input, the state at t = 0 and at every control period end (Observe);
// output, OUT/CAMERA/rgb_NNNNNN.png, depth_NNNNNN.png, seg_NNNNNN.png,
// OUT/CAMERA/frames.csv (frame number, simulated time of the frame, s) and
// OUT/VIDEO.mp4. Frame n is due at n * every (from t = 0) and is rendered at
// the first observed time t >= n * every. Rendering reads the state, never
// changes it; it allocates per frame, never in the periods without a frame.
// Rendering happens on the thread that calls Observe (see render/renderer.h).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>
#include <nlohmann/json_fwd.hpp>

#include "lab/outputs/lab_output.h"
#include "lab/scenario/lab_scenario.h"

namespace vlab::lab {

class ImageOutputs {
 public:
  /// Checks every output against the scene before anything is written:
  /// unknown camera, a size above the scene's offscreen buffer, a frame
  /// interval shorter than the control period, two outputs of one camera or
  /// one video name -> InputError naming FILE:LINE of the output. Then makes
  /// one renderer per profile. `scene` is the scene file, for messages.
  static std::unique_ptr<ImageOutputs> Create(const mjModel* m, const std::vector<ImageOutputConfig>& configs,
                                              const std::string& scene, double control_period_s);
  ~ImageOutputs();
  ImageOutputs(const ImageOutputs&) = delete;
  ImageOutputs& operator=(const ImageOutputs&) = delete;

  /// Creates the camera folders and opens the videos inside `out`'s staging folder.
  void Open(const OutputDir& out);
  /// Renders and writes the frames due at simulated time t (s).
  void Observe(double t, mjData* d);
  /// Closes the videos and writes frames.csv; call before out.Commit().
  void Finish();
  /// Per output: camera, size, profile, interval, frames, files, render time;
  /// and the GL renderer.
  nlohmann::json Summary() const;

 private:
  struct Impl;
  explicit ImageOutputs(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace vlab::lab
