// Offscreen rendering of MJCF cameras on OSMesa (no GPU, no display).
//
// One Renderer owns one OSMesa GL context and one mjrContext for one model.
// Threads: create, use and destroy a Renderer on one thread. Renderers on
// different threads may draw at the same time and draw the same pixels as one
// thread would (Mesa dispatches MuJoCo's process-global GL function pointers to
// the calling thread's current context; tests/render/renderer_threads_test.cc);
// creation is serialised inside Create. Rendering reads mjData and never
// changes it (mjv_updateScene takes a non-const pointer; nothing is written).
//
// Images are W x H with rows top-down (image row 0 is the top of the view),
// for any W x H up to the scene's offscreen buffer (<visual><global offwidth
// offheight>). Pixel (u, v) centres follow the pinhole model of
// CameraIntrinsics(): u = fx X/Z + cx, v = fy Y/Z + cy in OpenCV's camera
// frame (x right, y down, z forward).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

namespace vlab::render {

enum class Profile {
  kFast,     ///< no shadows, no reflections, no multisampling
  kQuality,  ///< shadows, reflections, 4x multisampling
  kDraft,    ///< fast, and no skybox (nor haze); round geoms of kDraftSlices x kDraftStacks
};
/// Round geoms (spheres, capsules, cylinders, ellipsoids) of the draft profile:
/// slices around the axis and stacks along it, for MuJoCo's 28 and 16
/// (<visual><quality numslices numstacks>, which the other profiles keep).
constexpr int kDraftSlices = 16;
constexpr int kDraftStacks = 8;
/// "draft" / "fast" / "quality" -> *profile; false (and *profile unchanged) for anything else.
bool ParseProfile(const std::string& name, Profile* profile);
/// "draft" / "fast" / "quality" -> Profile; throws InputError for anything else.
Profile ProfileFromName(const std::string& name);
/// Profile -> "draft" / "fast" / "quality".
const char* ProfileName(Profile profile);
/// The names ProfileFromName takes, for messages: "draft, fast or quality".
const char* ProfileNames();

/// 8-bit RGB, rows top-down, 3 bytes per pixel (R, G, B).
struct RgbImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;
};

/// Distance along the optical axis (z in the camera frame), metres, rows
/// top-down; +infinity where nothing was drawn (beyond the far plane).
struct DepthImage {
  int width = 0;
  int height = 0;
  std::vector<float> metres;
};

/// Geom id per pixel, rows top-down; -1 where no geom was drawn.
struct SegmentationImage {
  int width = 0;
  int height = 0;
  std::vector<std::int32_t> geom;
};
/// Body ids of a segmentation (m->geom_bodyid of each pixel's geom; -1 where
/// no geom was drawn), same layout as seg.geom.
void GeomsToBodies(const mjModel* m, const SegmentationImage& seg, std::vector<std::int32_t>* bodies);

/// Pinhole intrinsics of an MJCF camera rendered at width x height: from the
/// vertical field of view, fx = fy = (H/2) / tan(fovy/2), cx = W/2 - 0.5,
/// cy = H/2 - 0.5 (pixel centres at whole numbers).
struct Intrinsics {
  int width = 0;
  int height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
};
Intrinsics CameraIntrinsics(const mjModel* m, int camera, int width, int height);

/// Id of the MJCF camera `name`; throws InputError naming it and listing the
/// model's cameras when there is none of that name.
int CameraId(const mjModel* m, const std::string& name);

/// Mesa's llvmpipe draws with a pool of rasterizer threads ("llvmpipe-N"), one
/// pool per process, made with the first GL context and shared by every
/// renderer. A renderer waits for them, so they must be scheduled as the thread
/// that renders: sets every such thread of this process to `policy` (SCHED_OTHER
/// with nice value `value`, SCHED_IDLE, or SCHED_FIFO at priority `value`).
/// Returns how many threads it changed (0 when there are none yet, or when not
/// permitted).
int SetRasterizerScheduling(int policy, int value);
/// Binds every such thread to `cpus` (sched_setaffinity); returns how many.
int BindRasterizers(const std::vector<int>& cpus);

class Renderer {
 public:
  struct Options {
    int width = 640;  ///< largest image this renderer will draw (<= offscreen buffer)
    int height = 480;
    Profile profile = Profile::kFast;
    std::string scene;         ///< scene file, named in error messages ("": "the scene")
    bool log_renderer = true;  ///< print "vlab: render: GL_RENDERER; GL_VERSION" to stderr, once per process
  };
  /// Creates the GL context and MuJoCo's render context for `m` (which must
  /// outlive the renderer). Throws InputError when width x height exceeds the
  /// offscreen buffer (naming <visual><global offwidth offheight>), and
  /// std::runtime_error when no GL context can be made.
  static std::unique_ptr<Renderer> Create(const mjModel* m, const Options& options);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// Renders camera `camera` of the state in `d` at rgb->width x rgb->height
  /// (0 x 0: the renderer's size). `depth` may be null; when given it gets the
  /// same size; it comes from a second, flat pass (no lighting, skybox or
  /// multisampling: the depth at each pixel's centre, +inf where only sky is).
  /// Allocates only when an image grows. Throws
  /// std::invalid_argument for a camera id out of range or a size above the
  /// renderer's.
  void Render(mjData* d, int camera, RgbImage* rgb, DepthImage* depth = nullptr);
  /// Geom ids seen by camera `camera` at seg->width x seg->height (0 x 0: the
  /// renderer's size).
  void RenderSegmentation(mjData* d, int camera, SegmentationImage* seg);

  int width() const;
  int height() const;
  Profile profile() const;
  /// GL_RENDERER and GL_VERSION of the context, e.g.
  /// "llvmpipe (LLVM 15.0.6, 256 bits); 4.5 (Compatibility Profile) Mesa 22.3.6".
  const std::string& gl_renderer() const;

 private:
  struct Impl;
  explicit Renderer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace vlab::render
