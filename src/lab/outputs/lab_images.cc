#include "lab/outputs/lab_images.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>

#include <nlohmann/json.hpp>

#include "core/core_errors.h"
#include "lab/outputs/lab_log.h"
#include "render/image_io.h"
#include "render/renderer.h"
#include "render/video.h"

namespace vlab::lab {

namespace {

std::string FrameName(const char* kind, long n) {
  char name[32];
  std::snprintf(name, sizeof(name), "%s_%06ld.png", kind, n);
  return name;
}

// where to write a video given as a path: inside the output folder's staging
// folder when the file lies in the output folder, else where it was asked for
std::string StagedPath(const std::string& file, const OutputDir& out) {
  namespace fs = std::filesystem;
  const fs::path rel =
      fs::absolute(file).lexically_normal().lexically_relative(fs::absolute(out.final_dir()).lexically_normal());
  if (rel.empty() || *rel.begin() == "..") return file;
  return out.File(rel.string());
}

}  // namespace

struct ImageOutputs::Impl {
  struct Output {
    ImageOutputConfig config;
    int camera = -1;
    render::Renderer* renderer = nullptr;
    std::string folder;  // staging CAMERA/ ("" when only a video is written)
    std::unique_ptr<render::VideoFile> video;
    long frames = 0;
    std::vector<double> times_s;
    double render_wall_s = 0;
    render::RgbImage rgb;
    render::DepthImage depth;
    render::SegmentationImage seg;
  };
  const mjModel* m = nullptr;
  ImageOptions options;
  std::map<render::Profile, std::unique_ptr<render::Renderer>> renderers;
  std::vector<Output> outputs;
  double write_wall_s = 0;
  std::string error;  // the first frame that could not be written ("": none)

  void Frame(Output& o, double t, mjData* d);
  void Write(Output& o, std::vector<std::string>* written);
};

ImageOutputs::ImageOutputs(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ImageOutputs::~ImageOutputs() = default;

std::unique_ptr<ImageOutputs> ImageOutputs::Create(const mjModel* m, const std::vector<ImageOutputConfig>& configs,
                                                   const std::string& scene, double control_period_s,
                                                   const ImageOptions& options) {
  auto impl = std::make_unique<Impl>();
  impl->m = m;
  impl->options = options;
  std::map<render::Profile, std::pair<int, int>> sizes;  // largest image per profile
  for (std::size_t i = 0; i < configs.size(); ++i) {
    const ImageOutputConfig& c = configs[i];
    const auto key = [&](const std::string& field) {
      if (options.name) return options.name(i, field);
      return c.where + ": outputs.images[" + std::to_string(i) + "]." + field;
    };
    Impl::Output o;
    o.config = c;
    try {
      o.camera = render::CameraId(m, c.camera);
    } catch (const InputError& e) {
      throw InputError(key("camera") + ": scene '" + scene + "': " + e.what());
    }
    if (c.width > m->vis.global.offwidth || c.height > m->vis.global.offheight) {
      throw InputError(key("width, height") + ": " + std::to_string(c.width) + "x" + std::to_string(c.height) +
                       " exceeds the offscreen buffer " + std::to_string(m->vis.global.offwidth) + "x" +
                       std::to_string(m->vis.global.offheight) + " of scene '" + scene +
                       "' (<visual><global offwidth offheight>)");
    }
    if (c.every_s < control_period_s * (1 - 1e-9)) {
      throw InputError(key("every") + ": " + FormatDouble(c.every_s) + " s is shorter than the control period " +
                       FormatDouble(control_period_s) + " s (frames are taken at period ends)");
    }
    for (const Impl::Output& other : impl->outputs) {
      if (other.config.camera == c.camera) {
        throw InputError(key("camera") + ": a second output of camera '" + c.camera + "' (one output per camera)");
      }
      if (!c.video.empty() && other.config.video == c.video) {
        throw InputError(key("video") + ": '" + c.video + "' is written by another output too");
      }
    }
    const render::Profile profile = c.profile;
    auto& size = sizes[profile];
    size = {std::max(size.first, c.width), std::max(size.second, c.height)};
    impl->outputs.push_back(std::move(o));
  }
  for (const auto& [profile, size] : sizes) {
    render::Renderer::Options options;
    options.width = size.first;
    options.height = size.second;
    options.profile = profile;
    options.scene = scene;
    options.log_renderer = impl->options.log_renderer;
    impl->renderers[profile] = render::Renderer::Create(m, options);
  }
  for (Impl::Output& o : impl->outputs) {
    o.renderer = impl->renderers.at(o.config.profile).get();
    o.rgb.width = o.depth.width = o.seg.width = o.config.width;
    o.rgb.height = o.depth.height = o.seg.height = o.config.height;
  }
  return std::unique_ptr<ImageOutputs>(new ImageOutputs(std::move(impl)));
}

void ImageOutputs::Open(const OutputDir& out) {
  for (Impl::Output& o : impl_->outputs) {
    const ImageOutputConfig& c = o.config;
    if (c.png || c.depth || c.segmentation) {
      o.folder = impl_->options.flat ? out.staging_dir() : out.File(c.camera);
      std::error_code ec;
      std::filesystem::create_directories(o.folder, ec);
      if (ec) throw std::runtime_error("image folder '" + o.folder + "': " + ec.message());
    }
    if (c.video.empty()) continue;
    std::string path = out.File(c.video);
    if (impl_->options.video_anywhere) {
      // a video inside the output folder is written into its staging folder, so
      // that it moves into place with the frames instead of being replaced by them
      path = StagedPath(c.video, out);
      const std::filesystem::path parent = std::filesystem::path(path).parent_path();
      std::error_code ec;
      if (!parent.empty()) std::filesystem::create_directories(parent, ec);
    }
    o.video = render::VideoFile::Create(path, 1.0 / c.every_s, c.width, c.height);
  }
}

void ImageOutputs::Impl::Frame(Output& o, double t, mjData* d) {
  const ImageOutputConfig& c = o.config;
  const auto t0 = std::chrono::steady_clock::now();
  if (c.png || c.depth || !c.video.empty()) o.renderer->Render(d, o.camera, &o.rgb, c.depth ? &o.depth : nullptr);
  if (c.segmentation) o.renderer->RenderSegmentation(d, o.camera, &o.seg);
  const auto t1 = std::chrono::steady_clock::now();
  o.render_wall_s += std::chrono::duration<double>(t1 - t0).count();
  std::vector<std::string> written;
  try {
    Write(o, &written);
  } catch (const std::runtime_error& e) {
    // nothing half-written: the frame's files that did go out are removed, and the outputs stop
    for (const std::string& path : written) {
      std::error_code ec;
      std::filesystem::remove(path, ec);
    }
    error = e.what();
    throw;
  }
  write_wall_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  o.times_s.push_back(t);
  ++o.frames;
}

void ImageOutputs::Impl::Write(Output& o, std::vector<std::string>* written) {
  const ImageOutputConfig& c = o.config;
  const std::string stem = o.folder + "/";
  if (c.png) {
    written->push_back(stem + FrameName("rgb", o.frames));
    render::WritePng(written->back(), o.rgb);
  }
  if (c.depth) {
    written->push_back(stem + FrameName("depth", o.frames));
    render::WriteDepthPng(written->back(), o.depth);
  }
  if (c.segmentation) {
    written->push_back(stem + FrameName("seg", o.frames));
    render::WriteSegmentationPng(written->back(), o.seg);
  }
  if (o.video) o.video->Add(o.rgb);  // (last: a frame is in the video only when its PNGs are written)
}

void ImageOutputs::Observe(double t, mjData* d) {
  if (failed()) return;
  const long max_frames = impl_->options.max_frames;
  for (Impl::Output& o : impl_->outputs) {
    if (max_frames > 0 && o.frames >= max_frames) continue;
    if (t + kFrameDueTolerance_s >= o.frames * o.config.every_s) impl_->Frame(o, t, d);
  }
}

void ImageOutputs::ObserveLast(double t, mjData* d) {
  if (failed()) return;
  const long max_frames = impl_->options.max_frames;
  for (Impl::Output& o : impl_->outputs) {
    if (!o.config.last || (max_frames > 0 && o.frames >= max_frames)) continue;
    if (o.times_s.empty() || o.times_s.back() + kFrameDueTolerance_s < t) impl_->Frame(o, t, d);
  }
}

bool ImageOutputs::failed() const { return !impl_->error.empty(); }

const std::string& ImageOutputs::error() const { return impl_->error; }

const std::vector<double>& ImageOutputs::frame_times(std::size_t i) const { return impl_->outputs.at(i).times_s; }

double ImageOutputs::render_wall_s(std::size_t i) const { return impl_->outputs.at(i).render_wall_s; }

std::string ImageOutputs::gl_renderer() const {
  return impl_->renderers.empty() ? std::string() : impl_->renderers.begin()->second->gl_renderer();
}

void ImageOutputs::Finish() {
  for (Impl::Output& o : impl_->outputs) {
    if (o.video) o.video->Finish();
    if (o.folder.empty()) continue;
    const std::string path = o.folder + "/frames.csv";
    std::ofstream csv(path);
    csv << "frame,time\n";
    for (std::size_t n = 0; n < o.times_s.size(); ++n) csv << n << "," << FormatDouble(o.times_s[n]) << "\n";
    csv.close();
    if (!csv) throw std::runtime_error("'" + path + "': write failed");
  }
}

nlohmann::json ImageOutputs::Summary() const {
  nlohmann::json outputs = nlohmann::json::array();
  for (const Impl::Output& o : impl_->outputs) {
    const ImageOutputConfig& c = o.config;
    nlohmann::json files = nlohmann::json::array();
    if (c.png) files.push_back(c.camera + "/rgb_NNNNNN.png");
    if (c.depth) files.push_back(c.camera + "/depth_NNNNNN.png");
    if (c.segmentation) files.push_back(c.camera + "/seg_NNNNNN.png");
    if (!c.video.empty()) files.push_back(c.video);
    outputs.push_back({{"camera", c.camera},
                       {"width", c.width},
                       {"height", c.height},
                       {"profile", render::ProfileName(c.profile)},
                       {"every_s", c.every_s},
                       {"frames", o.frames},
                       {"files", files},
                       {"render_wall_s", o.render_wall_s}});
  }
  return {{"gl_renderer", gl_renderer()}, {"outputs", outputs}, {"write_wall_s", impl_->write_wall_s}};
}

}  // namespace vlab::lab
