// vlab vision --camera HOST:PORT: the vision program. Subscribes to a camera
// device, detects the described ArUco markers in every frame and serves their
// poses (camera frame, and world frame when the camera's pose is known) as a
// markers device. With --yoyo-port it tracks the yo-yo's colour blob instead
// and serves it as a yoyo device (vision_yoyo_program.h). Runs until
// SIGINT/SIGTERM, --frames or --duration.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "bridge/bridge_errors.h"
#include "bridge/bridge_signals.h"
#include "cli/cli_commands.h"
#include "core/core_errors.h"
#include "view/view_program.h"
#include "vision/vision_program.h"
#include "vision/vision_yoyo_program.h"

namespace vlab::cli {

namespace {

struct VisionArgs {
  std::string camera;
  int port = 50014;
  std::string bind = "127.0.0.1";
  std::string name;    // default: vision (markers), yoyo_vision (yoyo)
  int yoyo_port = -1;  // >= 0: the yo-yo tracker's yoyo device instead of the markers device
  std::string blob_color = "red";
  std::string line;  // "X,Y"
  std::vector<std::string> markers;
  double connect_timeout_s = 10;
  long frames = 0;
  double duration_s = 0;
  double max_error_px = 1.0;
  double ambiguity_margin_px = 0.1;
  bool quiet = false;
};

// "HOST:PORT", "[v6]:PORT" (view::SplitHostPort's rules), the example in the message a camera's port
void SplitHostPort(const std::string& text, std::string* host, int* port) {
  try {
    view::SplitHostPort("--camera", text, host, port);
  } catch (const vlab::InputError&) {
    throw vlab::InputError("--camera '" + text + "': expected HOST:PORT, e.g. 127.0.0.1:50013");
  }
}

// a counter line's frame parts: "N frames (R/s), S skipped, " and "M ms mean, X ms max per frame"
std::pair<std::string, std::string> FrameText(const vision::FrameCounters& c, double elapsed_s) {
  const double mean_ms = c.frames > 0 ? 1000 * c.process_s_sum / static_cast<double>(c.frames) : 0;
  char head[160], timing[96];
  std::snprintf(head, sizeof(head), "%ld frames (%.1f/s), %ld skipped, ", c.frames,
                elapsed_s > 0 ? static_cast<double>(c.frames) / elapsed_s : 0.0, c.frames_skipped);
  std::snprintf(timing, sizeof(timing), "%.1f ms mean, %.1f ms max per frame", mean_ms, 1000 * c.process_s_max);
  return {head, timing};
}

void Report(const vision::VisionProgram& p, double elapsed_s) {
  const vision::VisionCounters& c = p.counters();
  const auto [head, timing] = FrameText(c, elapsed_s);
  std::printf("vlab vision: %s%ld markers reported (%ld valid), %ld unknown; %s; %d subscribers, %ld refused\n",
              head.c_str(), c.reported, c.valid, c.unknown, timing.c_str(), p.server().subscribers(),
              p.server().counters().refused);
  std::fflush(stdout);
}

// "X,Y" (m, world) -> the yo-yo's vertical line
vision::YoyoLine ParseLine(const std::string& text) {
  vision::YoyoLine line;
  const std::size_t comma = text.find(',');
  std::size_t used_x = 0, used_y = 0;
  try {
    if (comma != std::string::npos) {
      line.x = std::stod(text.substr(0, comma), &used_x);
      line.y = std::stod(text.substr(comma + 1), &used_y);
    }
  } catch (const std::exception&) {
    used_x = 0;
  }
  if (comma == std::string::npos || used_x != comma || used_x == 0 || used_y == 0 ||
      used_y != text.size() - comma - 1 || !std::isfinite(line.x) || !std::isfinite(line.y)) {
    throw vlab::InputError("--line '" + text + "': expected X,Y in m (world), e.g. 0.725,0");
  }
  return line;
}

void ReportYoyo(const vision::YoyoVisionProgram& p, double elapsed_s) {
  const vision::YoyoVisionCounters& c = p.counters();
  const auto [head, timing] = FrameText(c, elapsed_s);
  std::printf("vlab vision: %syo-yo seen in %ld, no blob %ld, no pose %ld; %s; %ld refused\n", head.c_str(), c.seen,
              c.no_blob, c.no_pose, timing.c_str(), p.server().counters().refused);
  std::fflush(stdout);
}

// makes the program (it connects to its camera and binds its device); a bad address or a port
// in use is the options' fault (exit 2)
template <typename Program, typename Config>
std::unique_ptr<Program> StartProgram(const Config& config) {
  std::unique_ptr<Program> program;
  try {
    program = Program::Create(config);
  } catch (const bridge::NetworkError& e) {
    throw vlab::InputError(e.what());
  }
  return program;
}

// the start line's camera part: "camera 'NAME' at ADDR:PORT, WxH, fx .. cy .. px"
template <typename Program>
std::string CameraText(const Program& program) {
  const vision::CameraModel& m = program.camera_model();
  char text[160];
  std::snprintf(text, sizeof(text), ", %dx%d, fx %.1f fy %.1f cx %.1f cy %.1f px", m.width, m.height, m.fx, m.fy, m.cx,
                m.cy);
  return program.camera().Label() + text;
}

// processes frames until SIGINT/SIGTERM, --frames or --duration; a counter line
// every 5 s (unless --quiet) and at the end
template <typename Program>
int RunUntilDone(Program& program, const VisionArgs& a, void (*report)(const Program&, double)) {
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&start] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  double next_report_s = 5;
  while (g_stop_requested == 0) {
    program.Step(0.05);
    if (a.frames > 0 && program.counters().frames >= a.frames) break;
    if (a.duration_s > 0 && elapsed() >= a.duration_s) break;
    if (!a.quiet && elapsed() >= next_report_s) {
      report(program, elapsed());
      next_report_s += 5;
    }
  }
  report(program, elapsed());
  return 0;
}

int YoyoVision(const VisionArgs& a, vision::YoyoVisionConfig config) {
  if (a.yoyo_port > 65535) throw vlab::InputError("--yoyo-port " + std::to_string(a.yoyo_port) + " outside 0..65535");
  if (!a.markers.empty())
    throw vlab::InputError("--marker and --yoyo-port exclude each other: run two vision programs");
  config.blob = vision::BlobColor(a.blob_color);
  if (!a.line.empty()) config.line = ParseLine(a.line);
  config.connect_timeout_s = a.connect_timeout_s;
  config.server.name = a.name.empty() ? "yoyo_vision" : a.name;
  config.server.bind_address = a.bind;
  config.server.port = a.yoyo_port;
  const auto program = StartProgram<vision::YoyoVisionProgram>(config);
  if (!a.quiet) {
    std::printf("vlab vision: yoyo device '%s' on %s:%d (kind yoyo), %s blob on the line x %.3f y %.3f m; %s\n",
                config.server.name.c_str(), a.bind.c_str(), program->server().local_port(), config.blob.color.c_str(),
                config.line.x, config.line.y, CameraText(*program).c_str());
    std::fflush(stdout);
  }
  return RunUntilDone(*program, a, ReportYoyo);
}

int Vision(const VisionArgs& a) {
  // SIGINT, SIGTERM: the loop stops after the frame at hand and prints its counters; installed
  // first, so that one while the program waits for its camera is not lost
  InstallStopSignals();
  vision::VisionConfig config;
  SplitHostPort(a.camera, &config.camera_address, &config.camera_port);
  if (a.port < 0 || a.port > 65535) throw vlab::InputError("--port " + std::to_string(a.port) + " outside 0..65535");
  if (a.frames < 0) throw vlab::InputError("--frames must be >= 0");
  if (a.duration_s < 0) throw vlab::InputError("--duration must be >= 0 s");
  if (!(a.connect_timeout_s > 0)) throw vlab::InputError("--connect-timeout must be > 0 s");
  if (!(a.max_error_px > 0)) throw vlab::InputError("--max-error must be > 0 px");
  if (!(a.ambiguity_margin_px >= 0)) throw vlab::InputError("--ambiguity-margin must be >= 0 px");
  for (const std::string& m : a.markers) {
    const auto more = vision::ParseMarkerOption(m);
    config.markers.insert(config.markers.end(), more.begin(), more.end());
  }
  if (a.yoyo_port >= 0) {
    vision::YoyoVisionConfig yoyo;
    yoyo.camera_address = config.camera_address;
    yoyo.camera_port = config.camera_port;
    return YoyoVision(a, yoyo);
  }
  config.connect_timeout_s = a.connect_timeout_s;
  config.server.name = a.name.empty() ? "vision" : a.name;
  config.server.bind_address = a.bind;
  config.server.port = a.port;
  config.detector.max_reprojection_error_px = a.max_error_px;
  config.detector.min_alternative_error_px = a.ambiguity_margin_px;

  const auto program = StartProgram<vision::VisionProgram>(config);
  if (!a.quiet) {
    std::printf("vlab vision: markers device '%s' on %s:%d (kind markers), %zu markers described; %s\n",
                config.server.name.c_str(), a.bind.c_str(), program->server().local_port(),
                program->server().table().size(), CameraText(*program).c_str());
    std::fflush(stdout);
  }
  return RunUntilDone(*program, a, Report);
}

}  // namespace

Subcommand AddVisionCommand(CLI::App& app) {
  auto args = std::make_shared<VisionArgs>();
  CLI::App* cmd = app.add_subcommand(
      "vision", "Detect ArUco markers in a camera device's frames and serve their poses as a markers device");
  cmd->add_option("--camera", args->camera, "Camera device to subscribe to, HOST:PORT (e.g. 127.0.0.1:50013)")
      ->required();
  cmd->add_option("--port", args->port, "UDP port of the markers device (default 50014; 0: any free port)");
  cmd->add_option("--bind", args->bind, "Address the markers device binds to (default 127.0.0.1)");
  cmd->add_option("--name", args->name,
                  "Device name in the describe reply (default vision; yoyo_vision with --yoyo-port)");
  cmd->add_option("--yoyo-port", args->yoyo_port,
                  "Track the yo-yo's colour blob instead of markers and serve it as a yoyo device on this UDP port "
                  "(0: any free port)");
  cmd->add_option("--blob-color", args->blob_color, "With --yoyo-port: the yo-yo's colour (default red)");
  cmd->add_option("--line", args->line,
                  "With --yoyo-port: the yo-yo's vertical line X,Y, m, world (default 0.725,0: under the PA10's "
                  "tool in scenes/pa10_yoyo.xml's ready pose)");
  cmd->add_option("--marker", args->markers,
                  "DICT:ID:SIDE or DICT:FIRST-LAST:SIDE, side in m (e.g. 4X4_50:0-35:0.03); repeatable. Clients "
                  "may describe more markers over UDP");
  cmd->add_option("--connect-timeout", args->connect_timeout_s, "Wait this long for the camera, s (default 10)");
  cmd->add_option("--max-error", args->max_error_px,
                  "Largest RMS reprojection error of a valid pose, px (default 1.0)");
  cmd->add_option("--ambiguity-margin", args->ambiguity_margin_px,
                  "The other IPPE pose must fit at least this badly for a valid pose, px RMS (default 0.1; "
                  "for a real camera 2-3 times its corner noise)");
  cmd->add_option("--frames", args->frames, "Stop after this many frames (default: run until interrupted)");
  cmd->add_option("--duration", args->duration_s, "Stop after this many seconds (default: run until interrupted)");
  cmd->add_flag("-q,--quiet", args->quiet, "Only the final counter line");
  return {cmd, [args] { return WithErrorReport([&] { return Vision(*args); }); }};
}

}  // namespace vlab::cli
