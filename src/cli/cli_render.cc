// vlab render SCENARIO --camera NAME: runs the scenario and renders one MJCF
// camera offscreen every --every seconds of simulated time (from t = 0):
// RGB PNGs, optionally depth (16-bit, mm) and segmentation (16-bit, geom id +
// 1) PNGs, frames.csv, render.json, and optionally an MP4 video.
//
// The run is the scenario's own (same controller, same trajectory; rendering
// reads the state only), shortened to end right after the last frame. Its
// checks and image outputs are not evaluated or written: this command renders.
// SIGINT or SIGTERM ends the run at the next period: the frames rendered so far
// are kept (frames.csv, render.json saying so, the video closed), exit code 1.
// A frame that cannot be written ends the rendering the same way: the frames
// written whole before it are kept, render.json says which file failed, exit 1.
// The frames are the lab's image outputs (lab/outputs/lab_images.h), laid out flat.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "bridge/bridge_signals.h"
#include "cli/cli_commands.h"
#include "core/core_errors.h"
#include "core/core_mujoco.h"
#include "lab/devices/device_camera.h"
#include "lab/outputs/lab_images.h"
#include "lab/outputs/lab_log.h"
#include "lab/outputs/lab_output.h"
#include "lab/run/lab_runner.h"
#include "lab/scenario/lab_scenario.h"
#include "render/renderer.h"

namespace vlab::cli {

namespace {

struct RenderArgs {
  std::string scenario;
  std::string camera;
  double fps = 0;
  double every_s = 0;
  long frames = 0;  // 0: all that fit
  std::string out_dir;
  std::string video;
  bool depth = false;
  bool segmentation = false;
  int width = 0;  // 0: the scenario's setting for this camera, else 640 x 480
  int height = 0;
  std::string profile = "quality";
  bool quiet = false;
};

// the options that set an image output's fields, for messages
std::string OptionOf(std::size_t, const std::string& field) {
  if (field == "width, height") return "--width, --height";
  return "--" + field;
}

// the image size the scenario sets for this camera (a camera device or an image output), else 640 x 480
void ScenarioSize(const lab::Scenario& s, const std::string& camera, int* width, int* height) {
  *width = 640;
  *height = 480;
  for (const auto& d : s.devices) {
    if (d.kind == bridge::DeviceKind::kCamera && d.ParamsAs<lab::CameraParams>().camera == camera) {
      *width = d.ParamsAs<lab::CameraParams>().width;
      *height = d.ParamsAs<lab::CameraParams>().height;
      return;
    }
  }
  for (const auto& o : s.outputs.images) {
    if (o.camera == camera) {
      *width = o.width;
      *height = o.height;
      return;
    }
  }
}

int Render(const RenderArgs& a, const CLI::App& cmd) {
  auto given = [&cmd](const char* name) { return cmd.get_option(name)->count() > 0; };
  if (given("--fps") && given("--every")) throw vlab::InputError("--fps and --every: give one of them, not both");
  if (given("--fps") && !(a.fps > 0 && std::isfinite(a.fps))) throw vlab::InputError("--fps must be > 0");
  if (given("--every") && !(a.every_s > 0 && std::isfinite(a.every_s))) throw vlab::InputError("--every must be > 0 s");
  if (given("--out") && a.out_dir.empty())
    throw vlab::InputError("--out: an empty name (give a folder, e.g. --out frames)");
  if (given("--frames") && a.frames < 1) throw vlab::InputError("--frames must be >= 1");
  if (given("--width") && a.width < 1) throw vlab::InputError("--width must be >= 1 pixel");
  if (given("--height") && a.height < 1) throw vlab::InputError("--height must be >= 1 pixel");
  const render::Profile profile = render::ProfileFromName(a.profile);
  if (!a.video.empty() && std::filesystem::path(a.video).extension() != ".mp4") {
    throw vlab::InputError("--video '" + a.video + "': the file name must end in .mp4");
  }
  vlab::InstallMujocoHandlers();
  // SIGINT, SIGTERM from here on, before loading: the run ends at its next period and its frames
  // are kept (a signal before the run starts ends it at t = 0), never with the staging folder left
  InstallStopSignals();

  lab::Scenario scenario = lab::LoadScenario(lab::ResolveScenarioPath(a.scenario));
  const double period = scenario.control_period_s;
  const double every = given("--fps") ? 1.0 / a.fps : given("--every") ? a.every_s : 0.1;
  if (every < period * (1 - 1e-9)) {
    throw vlab::InputError("frame interval " + lab::FormatDouble(every) + " s is shorter than the control period " +
                           lab::FormatDouble(period) + " s of " + scenario.file + " (frames are taken at period ends)");
  }
  // frames that fit the scenario; the run ends at the first period end at or after the last one
  const long fit = static_cast<long>(std::floor(scenario.duration_s / every + lab::kFrameDueTolerance_s)) + 1;
  const long frames = given("--frames") ? std::min(a.frames, fit) : fit;
  if (given("--frames") && a.frames > fit && !a.quiet) {
    std::fprintf(stderr, "vlab: note: %s lasts %s s: %ld of the %ld frames asked for fit (every %s s)\n",
                 scenario.name.c_str(), lab::FormatDouble(scenario.duration_s).c_str(), fit, a.frames,
                 lab::FormatDouble(every).c_str());
  }
  const double last_frame_s = (frames - 1) * every;
  const double run_periods = std::ceil(last_frame_s / period - 1e-9);
  // (a run simulates at least one period, even for the frame at t = 0 alone)
  scenario.duration_s = std::min(scenario.duration_s, std::max(1.0, run_periods) * period);
  scenario.checks.clear();          // rendering is not a regression run
  scenario.outputs.images.clear();  // this command writes its own images

  std::unique_ptr<lab::Lab> lab = lab::Lab::Create(scenario);
  const mjModel* m = lab->model();
  lab::ImageOutputConfig image;
  image.camera = a.camera;
  ScenarioSize(scenario, a.camera, &image.width, &image.height);
  if (given("--width")) image.width = a.width;
  if (given("--height")) image.height = a.height;
  image.every_s = every;
  image.depth = a.depth;
  image.segmentation = a.segmentation;
  image.video = a.video;
  image.profile = profile;
  image.where = scenario.file;
  lab::ImageOptions layout;
  layout.flat = true;
  layout.video_anywhere = true;
  layout.max_frames = frames;
  layout.log_renderer = !a.quiet;
  layout.name = OptionOf;
  // the camera and size are checked, and the renderer made, before anything is written
  std::unique_ptr<lab::ImageOutputs> images = lab::ImageOutputs::Create(m, {image}, scenario.scene, period, layout);
  const int width = image.width, height = image.height;

  // outputs: a staging folder renamed into place whole; the video staged beside its final name
  const std::string out_dir = a.out_dir.empty() ? "out/" + scenario.name + "/render/" + a.camera : a.out_dir;
  std::unique_ptr<lab::OutputDir> out = lab::OutputDir::Create(out_dir);
  images->Open(*out);

  lab::RunOptions run;
  run.clock = ClockMode::kFast;  // offline: as fast as rendering allows, whatever the scenario's clock
  run.interrupt = &g_stop_requested;
  ProgressBar bar(!a.quiet);
  run.progress = [&bar](double f) { bar.Update(f); };
  run.observe = [&images](double t, const mjModel*, mjData* d) {
    try {
      images->Observe(t, d);
    } catch (const std::runtime_error&) {
      if (!images->failed()) throw;  // (not a write: rendering failed)
      // a frame not written: the rest of the run renders nothing; the frames before it are kept
    }
  };
  vlab::SetMujocoErrorCleanup([staging = out->File("")] {  // a MuJoCo error ends the process: leave nothing
    std::error_code ec;
    std::filesystem::remove_all(staging, ec);
  });
  const lab::RunResult r = lab->Run(run);
  bar.Finish();
  if (r.exit_code != 0 && !r.interrupted_by) {
    std::fprintf(stderr, "vlab: %s; no images written\n", r.failure.c_str());
    return 1;
  }

  // frames.csv (the video closed with it) and render.json: when each frame was taken, and how to read the images
  images->Finish();
  const std::vector<double>& times = images->frame_times(0);
  const double render_s = images->render_wall_s(0);
  const std::string gl = images->gl_renderer();
  {
    const int camera = render::CameraId(m, a.camera);
    const render::Intrinsics k = render::CameraIntrinsics(m, camera, width, height);
    nlohmann::json files = {{"rgb", "rgb_NNNNNN.png: 8-bit RGB"}, {"times", "frames.csv: frame, simulated time (s)"}};
    if (a.depth) files["depth"] = "depth_NNNNNN.png: 16-bit, mm along the optical axis, 0: nothing drawn";
    if (a.segmentation) files["segmentation"] = "seg_NNNNNN.png: 16-bit, geom id + 1, 0: no geom";
    if (!a.video.empty()) files["video"] = a.video;
    nlohmann::json meta = {{"scenario", scenario.name},
                           {"scene", scenario.scene},
                           {"camera", a.camera},
                           {"width", width},
                           {"height", height},
                           {"profile", render::ProfileName(profile)},
                           {"every_s", every},
                           {"frames", times.size()},
                           {"files", files},
                           {"intrinsics", {{"fx", k.fx}, {"fy", k.fy}, {"cx", k.cx}, {"cy", k.cy}}},
                           {"gl_renderer", gl},
                           {"render_wall_s", render_s},
                           {"mujoco", vlab::MujocoVersion()}};
    if (r.interrupted_by) meta["interrupted"] = r.failure;   // the frames before it are all there
    if (images->failed()) meta["failed"] = images->error();  // ... and here too
    std::ofstream json(out->File("render.json"));
    json << meta.dump(2) << "\n";
    if (!json) throw std::runtime_error("output folder '" + out_dir + "': write failed");
  }
  const std::string placed = out->Commit();  // out_dir, or a sibling when another run wrote out_dir meanwhile
  if (!out->note().empty()) std::fprintf(stderr, "vlab: %s\n", out->note().c_str());

  const double fps = render_s > 0 ? times.size() / render_s : 0.0;
  std::printf("%s: %zu frames %dx%d of camera '%s' (%s), every %s s, in %s/%s%s; %.1f fps rendered; %s\n",
              scenario.name.c_str(), times.size(), width, height, a.camera.c_str(), render::ProfileName(profile),
              lab::FormatDouble(every).c_str(), placed.c_str(), a.video.empty() ? "" : "; video ", a.video.c_str(), fps,
              gl.c_str());
  if (images->failed()) {
    std::fprintf(stderr, "vlab: %s; the %zu frames written before it are kept\n", images->error().c_str(),
                 times.size());
    return 1;
  }
  if (r.interrupted_by) {
    std::fprintf(stderr, "vlab: %s; the %zu frames rendered before it are kept\n", r.failure.c_str(), times.size());
    return 1;
  }
  return 0;
}

}  // namespace

Subcommand AddRenderCommand(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* cmd =
      app.add_subcommand("render",
                         "Render a scenario's camera offscreen: PNG frames (RGB, depth, segmentation) and MP4 video "
                         "(interrupted: the frames rendered so far are kept, exit 1)");
  cmd->add_option("scenario", args->scenario, "Scenario file (YAML); the .yaml extension may be left out")->required();
  cmd->add_option("--camera", args->camera, "MJCF camera to render")->required();
  cmd->add_option("--fps", args->fps, "Frames per simulated second (or --every)");
  cmd->add_option("--every", args->every_s, "Simulated seconds between frames, from t = 0 (default 0.1)");
  cmd->add_option("--frames", args->frames, "Number of frames (default: all that fit the scenario)");
  cmd->add_option("--out", args->out_dir, "Output folder (default: out/<scenario name>/render/<camera>)");
  cmd->add_option("--video", args->video, "Also write an MP4 video (mp4v) to this file");
  cmd->add_flag("--depth", args->depth, "Also write depth_NNNNNN.png (16-bit, millimetres)");
  cmd->add_flag("--segmentation", args->segmentation, "Also write seg_NNNNNN.png (16-bit, geom id + 1)");
  cmd->add_option("--width", args->width, "Image width, pixels (default: the scenario's for this camera, or 640)");
  cmd->add_option("--height", args->height, "Image height, pixels (default: the scenario's, or 480)");
  cmd->add_option(
      "--profile", args->profile,
      "draft (fast, no sky, coarser round geoms) | fast (no shadows, reflections, MSAA) | quality (default)");
  cmd->add_flag("-q,--quiet", args->quiet, "No GL renderer line, progress bar or notes");
  return {cmd, [args, cmd] { return WithErrorReport([&] { return Render(*args, *cmd); }); }};
}

}  // namespace vlab::cli
