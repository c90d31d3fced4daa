// Image outputs: PNG frames (RGB, 16-bit depth in mm, 16-bit segmentation) and
// MP4 videos of MJCF cameras, written into an output folder's staging folder.
// The scenario's outputs.images of a run, and `vlab render`'s one camera.
//
// Ports: input, the state at t = 0 and at every control period end (Observe);
// output, OUT/CAMERA/rgb_NNNNNN.png, depth_NNNNNN.png, seg_NNNNNN.png,
// OUT/CAMERA/frames.csv (frame number, simulated time of the frame, s) and
// OUT/VIDEO.mp4 (ImageOptions::flat: the frames and frames.csv in OUT itself;
// video_anywhere: the video where its path says). Frame n is due at n * every
// (from t = 0) and is rendered at the first observed time t >= n * every; an
// output with `last` also renders the run's last state (ObserveLast).
// Rendering reads the state, never changes it; it allocates per frame, never
// in the periods without a frame. Rendering happens on the thread that calls
// Observe (see render/renderer.h).
//
// A frame that cannot be written (a PNG, the video) stops the outputs: Observe
// throws std::runtime_error naming the file, the files of that frame already
// written are removed, and nothing more is rendered; frames.csv and the video
// hold the frames written whole before it (the output folder's rule: what ran
// is kept, nothing half-written).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>
#include <nlohmann/json_fwd.hpp>

#include "lab/outputs/lab_output.h"
#include "lab/scenario/lab_scenario.h"

namespace vlab::lab {

/// Frame n is due once t + kFrameDueTolerance_s >= n * every (s): the sums of control periods
/// round, and `vlab render` counts the frames a duration holds with the same tolerance.
inline constexpr double kFrameDueTolerance_s = 1e-9;

/// How ImageOutputs lays its files out and names its settings (the defaults: a scenario's outputs.images).
struct ImageOptions {
  /// The frames and frames.csv of every output in the output folder itself, not in CAMERA/.
  bool flat = false;
  /// A video's path is where to write it (relative to the working folder, made
  /// if missing): staged with the frames when it lies inside the output folder,
  /// else written in place. Otherwise it is a name inside the output folder.
  bool video_anywhere = false;
  /// The most frames an output renders (0: no limit).
  long max_frames = 0;
  /// The renderers print "vlab: render: GL_RENDERER" once (render::Renderer::Options).
  bool log_renderer = true;
  /// The name of output i's setting in messages ("camera", "width, height",
  /// "every", "video"); null: "FILE:LINE: outputs.images[i].FIELD".
  std::function<std::string(std::size_t i, const std::string& field)> name;
};

class ImageOutputs {
 public:
  /// Checks every output against the scene before anything is written:
  /// unknown camera, a size above the scene's offscreen buffer, a frame
  /// interval shorter than the control period, two outputs of one camera or
  /// one video name -> InputError naming the setting (FILE:LINE of the
  /// output, or options.name). Then makes one renderer per profile. `scene`
  /// is the scene file, for messages.
  static std::unique_ptr<ImageOutputs> Create(const mjModel* m, const std::vector<ImageOutputConfig>& configs,
                                              const std::string& scene, double control_period_s,
                                              const ImageOptions& options = {});
  ~ImageOutputs();
  ImageOutputs(const ImageOutputs&) = delete;
  ImageOutputs& operator=(const ImageOutputs&) = delete;

  /// Creates the camera folders and opens the videos inside `out`'s staging
  /// folder. Throws std::runtime_error naming a folder or video that cannot be made.
  void Open(const OutputDir& out);
  /// Renders and writes the frames due at simulated time t (s). Throws
  /// std::runtime_error naming the file when a frame cannot be written (then
  /// failed(), and later calls do nothing).
  void Observe(double t, mjData* d);
  /// At the run's end t: the frame of the last state of each output that asks
  /// for it (`last`), unless its last frame is of t already. Throws as Observe.
  void ObserveLast(double t, mjData* d);
  /// Closes the videos and writes frames.csv; call before out.Commit().
  /// Throws std::runtime_error naming a file that cannot be written.
  void Finish();
  /// Per output: camera, size, profile, interval, frames, files, render time;
  /// and the GL renderer.
  nlohmann::json Summary() const;

  /// True once a frame could not be written; error() says which file and why.
  bool failed() const;
  const std::string& error() const;
  /// Simulated times (s) of the frames output i wrote whole, in order.
  const std::vector<double>& frame_times(std::size_t i) const;
  /// Wall time output i spent rendering (not writing), s.
  double render_wall_s(std::size_t i) const;
  /// The GL renderer's name ("" without outputs).
  std::string gl_renderer() const;

 private:
  struct Impl;
  explicit ImageOutputs(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace vlab::lab
