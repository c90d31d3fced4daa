#include "render/video.h"

#include <unistd.h>

#include <filesystem>
#include <stdexcept>

#include "core/core_errors.h"

namespace vlab::render {

namespace fs = std::filesystem;

namespace {

// the writer vlab_render_video installs (a constant-initialised pointer: safe
// to set from another unit's static initialisation)
VideoFile::Factory g_factory = nullptr;

}  // namespace

void VideoFile::SetFactory(Factory factory) { g_factory = factory; }

std::unique_ptr<VideoFile> VideoFile::Create(const std::string& path, double fps, int width, int height) {
  const fs::path target(path);
  const std::string name = target.filename().string();
  if (name.size() < 5 || target.extension() != ".mp4") {
    throw vlab::InputError("video '" + path + "': the file name must end in .mp4");
  }
  const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
  if (!fs::is_directory(folder)) throw vlab::InputError("video '" + path + "': no folder '" + folder.string() + "'");
  if (!(fps > 0) || width < 1 || height < 1) {
    throw std::invalid_argument("video '" + path + "': needs fps > 0 and a frame size");
  }
  if (!g_factory) {
    throw std::runtime_error("video '" + path +
                             "': this program has no video writer (it is built without "
                             "vlab_render_video)");
  }
  // the container is chosen from the extension: keep .mp4 at the end of the temporary name
  const std::string staging =
      (folder / ("." + target.stem().string() + ".partial-" + std::to_string(::getpid()) + ".mp4")).string();
  return g_factory(path, staging, fps, width, height);
}

void VideoFile::CheckSize(const RgbImage& rgb) const {
  if (rgb.width != width_ || rgb.height != height_) {
    throw std::invalid_argument("video '" + path_ + "': frame " + std::to_string(rgb.width) + "x" +
                                std::to_string(rgb.height) + " in a " + std::to_string(width_) + "x" +
                                std::to_string(height_) + " video");
  }
}

}  // namespace vlab::render
