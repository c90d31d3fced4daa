#include "render/renderer.h"

#include <dirent.h>
#include <sched.h>
#include <sys/resource.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <mutex>
#include <stdexcept>

#include <GL/gl.h>  // with GL_GLEXT_PROTOTYPES (render/CMakeLists.txt): glBindFramebuffer, GL 3.0, exported by libOSMesa
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/core_errors.h"
#include "core/core_realtime.h"
#include "render/render_context.h"

namespace vlab::render {

namespace {

constexpr int kQualitySamples = 4;  // MSAA samples of the quality profile

// room for every model geom plus the decorations MuJoCo adds (tendon segments, ...)
int SceneCapacity(const mjModel* m) { return 1000 + 2 * m->ngeom + 2 * m->nwrap; }

std::atomic<bool> g_logged{false};

}  // namespace

bool ParseProfile(const std::string& name, Profile* profile) {
  for (const Profile p : {Profile::kDraft, Profile::kFast, Profile::kQuality}) {
    if (name == ProfileName(p)) {
      *profile = p;
      return true;
    }
  }
  return false;
}

Profile ProfileFromName(const std::string& name) {
  Profile profile = Profile::kFast;
  if (ParseProfile(name, &profile)) return profile;
  throw vlab::InputError("unknown render profile '" + name + "' (known: " + ProfileNames() + ")");
}

const char* ProfileName(Profile profile) {
  switch (profile) {
    case Profile::kDraft:
      return "draft";
    case Profile::kFast:
      return "fast";
    case Profile::kQuality:
      break;
  }
  return "quality";
}

const char* ProfileNames() { return "draft, fast or quality"; }

Intrinsics CameraIntrinsics(const mjModel* m, int camera, int width, int height) {
  if (camera < 0 || camera >= m->ncam) {
    throw std::invalid_argument("CameraIntrinsics: no camera " + std::to_string(camera));
  }
  Intrinsics k;
  k.width = width;
  k.height = height;
  const double half_fovy_rad = 0.5 * m->cam_fovy[camera] * M_PI / 180.0;
  k.fy = 0.5 * height / std::tan(half_fovy_rad);
  k.fx = k.fy;
  k.cx = 0.5 * width - 0.5;
  k.cy = 0.5 * height - 0.5;
  return k;
}

int CameraId(const mjModel* m, const std::string& name) {
  const int id = mj_name2id(m, mjOBJ_CAMERA, name.c_str());
  if (id >= 0) return id;
  std::string known;
  for (int i = 0; i < m->ncam; ++i) {
    const char* n = mj_id2name(m, mjOBJ_CAMERA, i);
    known += (i ? ", " : "") + std::string(n ? n : "(unnamed #" + std::to_string(i) + ")");
  }
  throw vlab::InputError("no camera '" + name + "' in the scene (" +
                         (known.empty() ? std::string("it has no cameras") : "cameras: " + known) + ")");
}

void GeomsToBodies(const mjModel* m, const SegmentationImage& seg, std::vector<std::int32_t>* bodies) {
  bodies->resize(seg.geom.size());
  for (std::size_t i = 0; i < seg.geom.size(); ++i) {
    const std::int32_t g = seg.geom[i];
    (*bodies)[i] = (g >= 0 && g < m->ngeom) ? m->geom_bodyid[g] : -1;
  }
}

struct Renderer::Impl {
  const mjModel* m = nullptr;
  Options options;
  std::unique_ptr<GlContext> gl;
  mjvScene scene;
  mjvOption vis;
  mjvCamera camera;
  mjrContext context;
  bool scene_made = false;
  bool context_made = false;
  std::vector<std::uint8_t> raw_rgb;   // bottom-up rows from mjr_readPixels
  std::vector<std::uint8_t> raw_rgba;  // bottom-up rows read as the buffer holds them (fast, draft)
  std::vector<float> raw_depth;

  ~Impl() {
    if (!gl) return;
    gl->MakeCurrent();
    if (context_made) mjr_freeContext(&context);
    if (scene_made) mjv_freeScene(&scene);
  }

  // size of the next image: the requested one, or the renderer's when 0 x 0
  void Size(int* width, int* height) const {
    if (*width == 0 && *height == 0) {
      *width = options.width;
      *height = options.height;
    }
    if (*width < 1 || *height < 1 || *width > options.width || *height > options.height) {
      throw std::invalid_argument("Renderer: image " + std::to_string(*width) + "x" + std::to_string(*height) +
                                  " outside 1x1 .. " + std::to_string(options.width) + "x" +
                                  std::to_string(options.height));
    }
  }

  // the scene of `cam` for the state in d
  void Update(mjData* d, int cam) {
    if (cam < 0 || cam >= m->ncam) throw std::invalid_argument("Renderer: no camera " + std::to_string(cam));
    gl->MakeCurrent();
    camera.type = mjCAMERA_FIXED;
    camera.fixedcamid = cam;
    mjv_updateScene(m, d, &vis, nullptr, &camera, mjCAT_ALL, &scene);
  }

  // one mjr_render pass into the offscreen buffer's lower-left corner; flat: segmentation colours,
  // no lighting, no skybox, no multisampling (depth and ids exactly at pixel centres)
  void Pass(const mjrRect& viewport, bool flat) {
    scene.flags[mjRND_SEGMENT] = flat;
    scene.flags[mjRND_IDCOLOR] = flat;
    mjr_render(viewport, &scene, &context);
    scene.flags[mjRND_SEGMENT] = 0;
    scene.flags[mjRND_IDCOLOR] = 0;
  }
};

Renderer::Renderer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
namespace {

// calls `change` with the thread id of every llvmpipe rasterizer thread of this process;
// returns how many calls returned true
template <typename Change>
int ForEachRasterizer(Change change) {
  DIR* tasks = ::opendir("/proc/self/task");
  if (!tasks) return 0;
  int changed = 0;
  while (const dirent* e = ::readdir(tasks)) {
    if (e->d_name[0] == '.') continue;
    std::ifstream comm(std::string("/proc/self/task/") + e->d_name + "/comm");
    std::string name;
    std::getline(comm, name);
    if (name.rfind("llvmpipe-", 0) == 0 && change(std::atoi(e->d_name))) ++changed;
  }
  ::closedir(tasks);
  return changed;
}

}  // namespace

int SetRasterizerScheduling(int policy, int value) {
  return ForEachRasterizer([policy, value](int tid) {
    sched_param param{};
    param.sched_priority = policy == SCHED_FIFO ? value : 0;
    if (::sched_setscheduler(tid, policy, &param) != 0) return false;
    return policy != SCHED_OTHER || ::setpriority(PRIO_PROCESS, static_cast<id_t>(tid), value) == 0;
  });
}

int BindRasterizers(const std::vector<int>& cpus) {
  return ForEachRasterizer([&cpus](int tid) { return BindThread(tid, cpus); });
}

Renderer::~Renderer() = default;
int Renderer::width() const { return impl_->options.width; }
int Renderer::height() const { return impl_->options.height; }
Profile Renderer::profile() const { return impl_->options.profile; }
const std::string& Renderer::gl_renderer() const { return impl_->gl->description(); }

std::unique_ptr<Renderer> Renderer::Create(const mjModel* m, const Options& options) {
  const int max_w = m->vis.global.offwidth, max_h = m->vis.global.offheight;
  if (options.width < 1 || options.height < 1 || options.width > max_w || options.height > max_h) {
    const std::string scene = options.scene.empty() ? "the scene" : "scene '" + options.scene + "'";
    throw vlab::InputError("image size " + std::to_string(options.width) + "x" + std::to_string(options.height) +
                           " does not fit the offscreen buffer " + std::to_string(max_w) + "x" + std::to_string(max_h) +
                           " of " + scene + " (raise <visual><global offwidth=\"...\" " +
                           "offheight=\"...\"/> in the scene)");
  }
  // one creation at a time in the process: MuJoCo loads its GL function pointers
  // (process-global) in mjr_makeContext, and offsamples is set on the shared model below
  static std::mutex create_mutex;
  std::lock_guard<std::mutex> lock(create_mutex);
  auto impl = std::make_unique<Impl>();
  Impl& r = *impl;
  r.m = m;
  r.options = options;
  r.gl = GlContext::Create();

  mjv_defaultOption(&r.vis);
  // a camera sees bodies, not the modelling aids: no sites, joints, rangefinder rays
  for (int i = 0; i < mjNGROUP; ++i) r.vis.sitegroup[i] = 0;
  r.vis.flags[mjVIS_RANGEFINDER] = 0;
  mjv_defaultCamera(&r.camera);
  mjv_defaultScene(&r.scene);
  mjv_makeScene(m, &r.scene, SceneCapacity(m));
  r.scene_made = true;
  const bool quality = options.profile == Profile::kQuality;
  const bool draft = options.profile == Profile::kDraft;
  r.scene.flags[mjRND_SHADOW] = quality;
  r.scene.flags[mjRND_REFLECTION] = quality;
  // the sky is the dearest thing a fast frame draws: llvmpipe samples its cube map at every
  // background pixel (measured: 4.5 ms of a 640x480 frame with nothing else in view, 1 CPU);
  // MuJoCo draws the haze with the skybox only
  r.scene.flags[mjRND_SKYBOX] = !draft;
  r.scene.flags[mjRND_HAZE] = !draft;

  // the sample count and the round geoms' tessellation are read only by mjr_makeContext
  // (its display lists): set them for this context, then restore the shared model
  mjModel* shared = const_cast<mjModel*>(m);
  const auto kept = shared->vis.quality;
  shared->vis.quality.offsamples = quality ? kQualitySamples : 0;
  if (draft) {
    shared->vis.quality.numslices = kDraftSlices;
    shared->vis.quality.numstacks = kDraftStacks;
  }
  mjr_defaultContext(&r.context);
  mjr_makeContext(m, &r.context, mjFONTSCALE_100);
  shared->vis.quality = kept;
  r.context_made = true;
  mjr_setBuffer(mjFB_OFFSCREEN, &r.context);
  if (r.context.currentBuffer != mjFB_OFFSCREEN) throw std::runtime_error("MuJoCo: no offscreen framebuffer");

  const std::size_t pixels = static_cast<std::size_t>(options.width) * options.height;
  r.raw_rgb.resize(pixels * 3);
  r.raw_rgba.resize(pixels * 4);
  r.raw_depth.resize(pixels);
  if (options.log_renderer && !g_logged.exchange(true)) {
    std::fprintf(stderr, "vlab: render: %s\n", r.gl->description().c_str());
  }
  return std::unique_ptr<Renderer>(new Renderer(std::move(impl)));
}

void Renderer::Render(mjData* d, int camera, RgbImage* rgb, DepthImage* depth) {
  Impl& r = *impl_;
  int w = rgb->width, h = rgb->height;
  r.Size(&w, &h);
  r.Update(d, camera);
  const mjrRect viewport = {0, 0, w, h};
  r.Pass(viewport, false);
  const std::size_t row = static_cast<std::size_t>(w) * 3;
  rgb->width = w;
  rgb->height = h;
  rgb->pixels.resize(row * h);
  cv::Mat out(h, w, CV_8UC3, rgb->pixels.data());
  cv::Mat bottom_up(h, w, CV_8UC3, r.raw_rgb.data());
  if (r.context.offSamples == 0) {
    // without multisampling, read the colour buffer as it is stored (RGBA): llvmpipe
    // copies it, where GL_RGB (mjr_readPixels) makes it convert every pixel, 0.5 ms a
    // 640x480 frame against 0.15 ms for this read and the two passes below. The same
    // bytes: the alpha byte is dropped either way
    glBindFramebuffer(GL_READ_FRAMEBUFFER, r.context.offFBO);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, r.raw_rgba.data());
    mjr_restoreBuffer(&r.context);
    cv::cvtColor(cv::Mat(h, w, CV_8UC4, r.raw_rgba.data()), bottom_up, cv::COLOR_RGBA2RGB);
  } else {
    mjr_readPixels(r.raw_rgb.data(), nullptr, viewport, &r.context);  // (resolves the samples first)
  }
  cv::flip(bottom_up, out, 0);  // rows bottom-up -> top-down
  if (!depth) return;

  // depth from a flat pass: the colour pass's depth buffer holds the skybox, and one
  // multisample per pixel (not its centre)
  r.Pass(viewport, true);
  mjr_readPixels(nullptr, r.raw_depth.data(), viewport, &r.context);
  // window depth b in [0, 1] of a perspective projection with near n and far f:
  // b = (1/n - 1/z) / (1/n - 1/f), so z = n f / (f - b (f - n))
  const double n = r.scene.camera[0].frustum_near, f = r.scene.camera[0].frustum_far;
  depth->width = w;
  depth->height = h;
  depth->metres.resize(static_cast<std::size_t>(w) * h);
  const float inf = std::numeric_limits<float>::infinity();
  for (int y = 0; y < h; ++y) {
    const float* src = r.raw_depth.data() + static_cast<std::size_t>(w) * (h - 1 - y);
    float* dst = depth->metres.data() + static_cast<std::size_t>(w) * y;
    for (int x = 0; x < w; ++x) {
      const double b = src[x];
      dst[x] = b >= 1.0 ? inf : static_cast<float>(n * f / (f - b * (f - n)));
    }
  }
}

void Renderer::RenderSegmentation(mjData* d, int camera, SegmentationImage* seg) {
  Impl& r = *impl_;
  int w = seg->width, h = seg->height;
  r.Size(&w, &h);
  // flat colours: scene geom index + 1 in 24 bits (R low byte), 0 where nothing was drawn
  r.Update(d, camera);
  const mjrRect viewport = {0, 0, w, h};
  r.Pass(viewport, true);
  mjr_readPixels(r.raw_rgb.data(), nullptr, viewport, &r.context);

  seg->width = w;
  seg->height = h;
  seg->geom.resize(static_cast<std::size_t>(w) * h);
  const mjvScene& scene = r.scene;
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* src = r.raw_rgb.data() + static_cast<std::size_t>(w) * 3 * (h - 1 - y);
    std::int32_t* dst = seg->geom.data() + static_cast<std::size_t>(w) * y;
    for (int x = 0; x < w; ++x, src += 3) {
      const int id = src[0] | (src[1] << 8) | (src[2] << 16);
      const int i = id - 1;  // index of the scene geom
      dst[x] = (i >= 0 && i < scene.ngeom && scene.geoms[i].objtype == mjOBJ_GEOM) ? scene.geoms[i].objid : -1;
    }
  }
}

}  // namespace vlab::render
