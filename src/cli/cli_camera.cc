// vlab camera: a real webcam (V4L2) or a video file served as a camera device
// (kind 4) over UDP, with the same CameraServer as the lab's simulated webcam:
// a client tells them apart only by the pictures (and the describe reply's
// "server" and "source").
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "bridge/bridge_camera_server.h"
#include "bridge/bridge_camera_source.h"
#include "bridge/bridge_errors.h"
#include "bridge/bridge_signals.h"
#include "cli/cli_commands.h"
#include "core/core_errors.h"

namespace vlab::cli {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kEstimatedHfovDeg = 60.0;  // a typical USB webcam, when nothing better is known

struct CameraArgs {
  std::string source;
  int port = 50013;
  std::string bind = "127.0.0.1";
  std::string name = "webcam";
  double fps = 0;
  int width = 0, height = 0;
  std::string encoding = "jpeg";
  int jpeg_quality = 90;
  bool loop = false;
  long frames = -1;  // -1: no limit
  double fovy_deg = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  std::string distortion;  // k1,k2,p1,p2
  std::string pose;        // x,y,z,qw,qx,qy,qz
  int chunk_bytes = static_cast<int>(bridge::kDefaultChunkBytes);
};

// "a,b,c" -> n finite numbers; InputError naming the option
std::vector<double> Numbers(const std::string& text, std::size_t n, const std::string& option) {
  std::vector<double> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    std::size_t used = 0;
    double v = 0;
    try {
      v = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !std::isfinite(v)) {
      throw vlab::InputError(option + " '" + text + "': '" + item + "' is not a number");
    }
    values.push_back(v);
  }
  if (values.size() != n) {
    throw vlab::InputError(option + " '" + text + "': expected " + std::to_string(n) + " comma-separated numbers");
  }
  return values;
}

void Validate(const CameraArgs& a) {
  if (a.port < 0 || a.port > 65535) throw vlab::InputError("--port must be 0 to 65535");
  if (a.name.empty()) throw vlab::InputError("--name must not be empty");
  if (a.fps != 0 && !(a.fps > 0 && a.fps <= 1000)) throw vlab::InputError("--fps must be > 0 and <= 1000 Hz");
  if ((a.width == 0) != (a.height == 0)) throw vlab::InputError("--width and --height go together");
  if (a.width != 0 && (a.width < 1 || a.width > 8192 || a.height < 1 || a.height > 8192)) {
    throw vlab::InputError("--width and --height must be 1 to 8192 pixels");
  }
  if (a.jpeg_quality < 1 || a.jpeg_quality > 100) throw vlab::InputError("--jpeg-quality must be 1 to 100");
  if (a.frames != -1 && a.frames < 1) throw vlab::InputError("--frames must be >= 1");
  if (a.fovy_deg != 0 && !(a.fovy_deg > 0 && a.fovy_deg < 180)) {
    throw vlab::InputError("--fovy must be > 0 and < 180 deg");
  }
  const int calibration = (a.fx != 0) + (a.fy != 0) + (a.cx != 0) + (a.cy != 0);
  if (calibration != 0 && calibration != 4) throw vlab::InputError("--fx, --fy, --cx and --cy go together");
  if (calibration == 4 && !(a.fx > 0 && a.fy > 0 && std::isfinite(a.cx) && std::isfinite(a.cy))) {
    throw vlab::InputError("--fx and --fy must be > 0 pixels");
  }
  if (calibration == 4 && a.fovy_deg != 0) throw vlab::InputError("give either --fovy or --fx/--fy/--cx/--cy");
  if (a.chunk_bytes < 1 || a.chunk_bytes > static_cast<int>(bridge::kMaxChunkBytes)) {
    throw vlab::InputError("--chunk-bytes must be 1 to " + std::to_string(bridge::kMaxChunkBytes));
  }
}

bridge::CameraPose ParsePose(const std::string& text) {
  bridge::CameraPose pose;
  if (text.empty()) return pose;
  const std::vector<double> v = Numbers(text, 7, "--pose");
  const Eigen::Quaterniond q(v[3], v[4], v[5], v[6]);
  if (std::abs(q.norm() - 1.0) > 1e-3) {
    throw vlab::InputError("--pose '" + text + "': the quaternion qw,qx,qy,qz must have unit length");
  }
  pose.valid = true;
  pose.p_WC = Eigen::Vector3d(v[0], v[1], v[2]);
  pose.q_WC = q.normalized();
  return pose;
}

// intrinsics of the served images: calibration, fovy, or a 60 deg horizontal estimate
void SetIntrinsics(const CameraArgs& a, bridge::CameraDescription* d) {
  const double w = d->width, h = d->height;
  d->cx = 0.5 * w - 0.5;
  d->cy = 0.5 * h - 0.5;
  if (a.fx != 0) {
    d->fx = a.fx;
    d->fy = a.fy;
    d->cx = a.cx;
    d->cy = a.cy;
    d->intrinsics_source = "calibration";
  } else if (a.fovy_deg != 0) {
    d->fx = d->fy = 0.5 * h / std::tan(0.5 * a.fovy_deg * kPi / 180.0);
    d->intrinsics_source = "fovy";
  } else {
    d->fx = d->fy = 0.5 * w / std::tan(0.5 * kEstimatedHfovDeg * kPi / 180.0);
    d->intrinsics_source = "estimated";
  }
}

int RunCamera(const CameraArgs& a) {
  // SIGINT, SIGTERM: the loop stops before its next frame and prints its counters; installed
  // first, so that one while the source opens stops the camera before its first frame
  InstallStopSignals();
  Validate(a);
  bridge::CameraDescription d;
  if (!bridge::EncodingFromName(a.encoding, &d.encoding)) throw vlab::InputError("--encoding must be jpeg or raw");
  const bridge::CameraPose pose = ParsePose(a.pose);
  if (!a.distortion.empty()) {
    const std::vector<double> k = Numbers(a.distortion, 4, "--distortion");
    for (int i = 0; i < 4; ++i) d.distortion[i] = k[i];
  }

  // the source first: nothing is bound when it cannot be read
  std::unique_ptr<bridge::VideoSource> source;
  try {
    source = bridge::VideoSource::Open(a.source, {a.width, a.height, a.fps});
  } catch (const bridge::VideoSourceError& e) {
    throw vlab::InputError(std::string("--source: ") + e.what());
  }
  if (a.loop && source->is_device()) throw vlab::InputError("--loop is for video files, not devices");
  const double fps = a.fps > 0 ? a.fps : source->fps() > 0 ? source->fps() : 30.0;

  d.name = a.name;
  d.server = "vlab camera";
  d.source = a.source;
  d.clock = "realtime";
  d.width = source->width();
  d.height = source->height();
  d.fps = fps;
  d.jpeg_quality = a.jpeg_quality;
  d.pose = pose.valid ? "fixed" : "none";
  SetIntrinsics(a, &d);

  bridge::CameraServerConfig config;
  config.bind_address = a.bind;
  config.port = a.port;
  config.description = d;
  config.chunk_bytes = static_cast<std::size_t>(a.chunk_bytes);
  std::unique_ptr<bridge::CameraServer> server;
  try {
    server = bridge::CameraServer::Create(config);
  } catch (const bridge::NetworkError& e) {
    throw vlab::InputError(std::string("--bind/--port: ") + e.what());
  } catch (const std::invalid_argument& e) {
    throw vlab::InputError(e.what());
  }

  std::printf("vlab camera: '%s' from %s (%s, %dx%d, %g fps, %s) on udp %s:%d\n", d.name.c_str(), a.source.c_str(),
              source->backend().c_str(), d.width, d.height, fps, bridge::EncodingName(d.encoding), a.bind.c_str(),
              server->port());
  std::fflush(stdout);

  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = Clock::now();
  const auto since_start = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
  std::vector<std::uint8_t> rgb(3u * static_cast<std::size_t>(d.width) * d.height);
  std::string why = "end of file";
  std::int64_t id = 0;
  for (;;) {
    if (g_stop_requested != 0) {
      why = "interrupted by " + StopSignalName(g_stop_requested);
      break;
    }
    if (!source->Read(rgb.data())) {
      if (a.loop && source->Rewind() && source->Read(rgb.data())) {
        // next pass of the file
      } else if (g_stop_requested != 0) {
        continue;  // a read the signal cut short: the top of the loop stops
      } else if (source->is_device()) {
        std::fprintf(stderr, "vlab: error: video source '%s' stopped delivering frames\n", a.source.c_str());
        return 1;
      } else {
        break;
      }
    }
    // a file plays at its rate (frame i at i / fps); a device delivers at its own
    if (!source->is_device()) {
      const double due = static_cast<double>(id) / fps;
      for (double left = due - since_start(); left > 0 && g_stop_requested == 0; left = due - since_start()) {
        server->Poll(std::min(left, 0.05));
      }
    }
    server->Poll(0);
    server->SendImage(id, since_start(), rgb.data(), pose);
    ++id;
    if (a.frames > 0 && id >= a.frames) {
      why = "--frames reached";
      break;
    }
  }
  const bridge::CameraServerCounters& c = server->counters();
  std::printf(
      "vlab camera: %ld frames (%ld sent whole to subscribers, %ld chunks, %ld send failures), "
      "%d subscribers, %ld requests refused; %s\n",
      c.frames, c.frames_sent, c.chunks_sent, c.send_failures, server->subscribers(), c.endpoint.refused, why.c_str());
  return 0;
}

}  // namespace

Subcommand AddCameraCommand(CLI::App& app) {
  auto args = std::make_shared<CameraArgs>();
  CLI::App* cmd = app.add_subcommand(
      "camera", "Serve a real webcam (V4L2) or a video file as a camera device over UDP (docs/protocol_camera.md)");
  cmd->add_option("--source", args->source, "/dev/videoN (a V4L2 webcam) or a video file")->required();
  cmd->add_option("--port", args->port, "UDP port (default 50013; 0: any free port)");
  cmd->add_option("--bind", args->bind, "Address to bind (default 127.0.0.1)");
  cmd->add_option("--name", args->name, "Device name in the describe reply (default webcam)");
  cmd->add_option("--fps", args->fps, "Device: rate to ask for; file: rate to play at (default: the file's)");
  cmd->add_option("--width", args->width, "Image width, pixels (device: asked for; frames are scaled to it)");
  cmd->add_option("--height", args->height, "Image height, pixels (with --width)");
  cmd->add_option("--encoding", args->encoding, "jpeg | raw (default jpeg)")->check(CLI::IsMember({"jpeg", "raw"}));
  cmd->add_option("--jpeg-quality", args->jpeg_quality, "JPEG quality 1-100 (default 90)");
  cmd->add_flag("--loop", args->loop, "File: start again at its end");
  cmd->add_option("--frames", args->frames, "Stop after this many frames");
  cmd->add_option("--fovy", args->fovy_deg, "Vertical field of view, deg: intrinsics fx = fy = (H/2)/tan(fovy/2)");
  cmd->add_option("--fx", args->fx, "Calibrated focal length x, pixels (with --fy --cx --cy)");
  cmd->add_option("--fy", args->fy, "Calibrated focal length y, pixels");
  cmd->add_option("--cx", args->cx, "Calibrated principal point x, pixels");
  cmd->add_option("--cy", args->cy, "Calibrated principal point y, pixels");
  cmd->add_option("--distortion", args->distortion,
                  "k1,k2,p1,p2 of the calibration (describe only; images as captured)");
  cmd->add_option("--pose", args->pose, "x,y,z,qw,qx,qy,qz: the camera's pose in the world (m; OpenCV camera frame)");
  cmd->add_option("--chunk-bytes", args->chunk_bytes, "Frame bytes per datagram (default 60000)");
  return {cmd, [args] { return WithErrorReport([&] { return RunCamera(*args); }); }};
}

}  // namespace vlab::cli
