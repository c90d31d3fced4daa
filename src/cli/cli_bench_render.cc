// vlab bench render: offscreen frames per second of one camera of a scene.
//
// The state is the scenario's initial state (the lab's InitialState). Per
// variant, best of --repeat measurements of --duration wall seconds each
// (default 2 s):
//   a. Render() (scene update, GL render, read-back, row flip) at 640x480 and
//      320x240 in the fast and the quality profile, and at 640x480 in the draft one;
//   b. render + JPEG encoding (libjpeg, render/image_codec.h, quality 90) at 640x480, fast;
//   c. render + JPEG + send over the camera wire: a camera server on loopback
//      (the one `vlab serve` and `vlab camera` use) sends every frame in chunks
//      to a camera client in another thread, which reassembles them; the
//      figure is the sender's frame rate, with the share of frames the client
//      received whole.
// Goal: >= 100 fps at 640x480 in the fast profile on 2 cores. llvmpipe
// renders with LP_NUM_THREADS threads (default: one per CPU); the figures are
// what a user gets with the environment as it is.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <thread>

#include "bridge/bridge_camera_client.h"
#include "bridge/bridge_camera_server.h"
#include "cli/cli_commands.h"
#include "core/core_errors.h"
#include "core/core_mujoco.h"
#include "lab/devices/device_camera.h"
#include "lab/run/lab_runner.h"
#include "lab/scenario/lab_scenario.h"
#include "render/image_io.h"
#include "render/renderer.h"

namespace vlab::cli {

namespace {

constexpr const char* kCubeScenario = "scenes/pa10_cubes.yaml";
constexpr const char* kCubeCamera = "webcam";
constexpr const char* kFallbackScenario = "scenes/pa10_reach.yaml";
constexpr const char* kFallbackCamera = "overview";
constexpr double kGoalFps = 100;  // 640x480, fast profile
constexpr int kJpegQuality = 90;

using Clock = std::chrono::steady_clock;

// A camera server on loopback with a client thread that reassembles every frame
// it sends (JPEG not decoded: the receiving side's decode is the client's cost).
class LoopbackWire {
 public:
  LoopbackWire(int width, int height, int quality) {
    bridge::CameraServerConfig config;
    config.description.name = "bench";
    config.description.server = "vlab bench render";
    config.description.width = width;
    config.description.height = height;
    config.description.jpeg_quality = quality;
    config.description.fx = config.description.fy = height;  // any valid intrinsics: the bench sends no poses
    config.description.cx = width / 2.0 - 0.5;
    config.description.cy = height / 2.0 - 0.5;
    server_ = bridge::CameraServer::Create(config);
    receiver_ = std::thread([this, port = server_->port()] {
      bridge::CameraClientOptions options;
      options.decode = false;
      bridge::CameraClient client = bridge::CameraClient::Connect("127.0.0.1", port, options);
      bridge::CameraClient::Frame frame;
      while (!stop_) {
        try {
          client.Receive(0.1, &frame);
          ++received_;
        } catch (const bridge::TimeoutError&) {
        }
      }
    });
    // answer the client's describe request: it subscribes
    const auto deadline = Clock::now() + std::chrono::seconds(5);
    while (server_->subscribers() == 0 && Clock::now() < deadline) server_->Poll(0.01);
    if (server_->subscribers() == 0)
      throw std::runtime_error("bench render: the loopback camera client did not connect");
  }
  ~LoopbackWire() {
    stop_ = true;
    receiver_.join();
  }
  void Send(const render::RgbImage& rgb, double t) {
    server_->Poll(0.0);
    server_->SendImage(next_id_++, t, rgb.pixels.data(), bridge::CameraPose{});
  }
  long sent() const { return server_->counters().frames_sent; }
  long received() const { return received_; }
  long failures() const { return server_->counters().send_failures; }

 private:
  std::unique_ptr<bridge::CameraServer> server_;
  std::thread receiver_;
  std::atomic<bool> stop_{false};
  std::atomic<long> received_{0};
  std::int64_t next_id_ = 0;
};

// the camera measured in a scenario: its first camera device's, else "webcam", else the scene's first
std::string PickCamera(const lab::Scenario& s, const mjModel* m) {
  for (const auto& d : s.devices) {
    if (d.kind == bridge::DeviceKind::kCamera) return d.ParamsAs<lab::CameraParams>().camera;
  }
  if (mj_name2id(m, mjOBJ_CAMERA, kCubeCamera) >= 0) return kCubeCamera;
  if (m->ncam == 0) throw vlab::InputError("scene '" + s.scene + "': no camera to render");
  const char* name = mj_id2name(m, mjOBJ_CAMERA, 0);
  if (!name) throw vlab::InputError("scene '" + s.scene + "': its first camera has no name");
  return name;
}

// frames per second of `frame` over `seconds` of wall time (after 3 warm-up frames)
double Rate(const std::function<void()>& frame, double seconds) {
  for (int i = 0; i < 3; ++i) frame();
  const auto t0 = Clock::now();
  long n = 0;
  double elapsed = 0;
  do {
    frame();
    ++n;
    elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
  } while (elapsed < seconds);
  return n / elapsed;
}

double Best(int repeat, const std::function<double()>& measure) {
  double best = 0;
  for (int i = 0; i < repeat; ++i) best = std::max(best, measure());
  return best;
}

}  // namespace

int BenchRender(const BenchArgs& args) {
  return WithErrorReport([&args] {
    vlab::InstallMujocoHandlers();
    std::string path = args.scenario;
    std::string camera;
    if (path.empty()) {
      path = kCubeScenario;
      camera = kCubeCamera;
      if (!std::filesystem::exists(path)) {
        std::printf("note: %s not found: measuring %s, camera '%s' instead\n", kCubeScenario, kFallbackScenario,
                    kFallbackCamera);
        path = kFallbackScenario;
        camera = kFallbackCamera;
      }
    }
    lab::Scenario scenario = lab::LoadScenario(lab::ResolveScenarioPath(path));
    std::unique_ptr<lab::Lab> lab = lab::Lab::Create(scenario);
    const mjModel* m = lab->model();
    if (camera.empty()) camera = PickCamera(scenario, m);
    const int cam = render::CameraId(m, camera);
    vlab::DataPtr data = vlab::MakeData(m);
    mjData* d = data.get();
    lab->InitialState(d);
    const double seconds = args.duration_s > 0 ? args.duration_s : 2.0;

    const char* lp = std::getenv("LP_NUM_THREADS");
    const long cpus = ::sysconf(_SC_NPROCESSORS_ONLN);
    std::printf("vlab bench render: scenario %s, scene %s, camera '%s'\n", scenario.name.c_str(),
                scenario.scene.c_str(), camera.c_str());
    std::printf("  state at t = 0; %.2f s of rendering per measurement, best of %d; %ld CPUs; LP_NUM_THREADS %s\n",
                seconds, args.repeat, cpus, lp ? lp : "unset (llvmpipe: one thread per CPU)");

    render::RgbImage rgb;
    double fast_vga = 0;
    std::string gl;
    for (render::Profile profile : {render::Profile::kFast, render::Profile::kQuality, render::Profile::kDraft}) {
      render::Renderer::Options options;
      options.profile = profile;
      options.scene = scenario.scene;
      options.log_renderer = false;
      std::unique_ptr<render::Renderer> r = render::Renderer::Create(m, options);
      if (gl.empty()) {
        gl = r->gl_renderer();
        std::printf("  GL: %s\n", gl.c_str());
      }
      for (auto [w, h] : {std::pair{640, 480}, std::pair{320, 240}}) {
        if (profile == render::Profile::kDraft && w != 640) continue;  // (the size many cameras are served at)
        const double fps = Best(args.repeat, [&, w = w, h = h] {
          return Rate(
              [&] {
                rgb.width = w;
                rgb.height = h;
                r->Render(d, cam, &rgb);
              },
              seconds);
        });
        if (profile == render::Profile::kFast && w == 640) fast_vga = fps;
        std::printf("  a. render %-8s %4dx%-4d %8.1f fps  %6.2f ms/frame\n", render::ProfileName(profile), w, h, fps,
                    1000 / fps);
      }
    }

    // b and c: the camera device's path, fast profile at 640x480
    render::Renderer::Options options;
    options.scene = scenario.scene;
    options.log_renderer = false;
    std::unique_ptr<render::Renderer> r = render::Renderer::Create(m, options);
    std::vector<std::uint8_t> jpeg;
    rgb.width = rgb.height = 0;  // the renderer's size: 640x480
    const double encoded = Best(args.repeat, [&] {
      return Rate(
          [&] {
            r->Render(d, cam, &rgb);
            render::EncodeJpeg(rgb, kJpegQuality, &jpeg);
          },
          seconds);
    });
    std::printf("  b. render + JPEG q%d (fast 640x480) %8.1f fps  %6.2f ms/frame  (%zu bytes/frame)\n", kJpegQuality,
                encoded, 1000 / encoded, jpeg.size());
    {
      LoopbackWire wire(rgb.width, rgb.height, kJpegQuality);
      const double sent = Best(args.repeat, [&] {
        return Rate(
            [&] {
              r->Render(d, cam, &rgb);
              wire.Send(rgb, d->time);
            },
            seconds);
      });
      std::this_thread::sleep_for(std::chrono::milliseconds(200));  // the last frames in flight
      std::printf(
          "  c. render + JPEG + send (fast 640x480) %8.1f fps  %6.2f ms/frame  (%ld of %ld frames received "
          "whole, %ld datagrams not taken)\n",
          sent, 1000 / sent, wire.received(), wire.sent(), wire.failures());
    }
    std::printf("  goal: >= %.0f fps at 640x480 fast -> %.2fx the goal: %s\n", kGoalFps, fast_vga / kGoalFps,
                fast_vga >= kGoalFps ? "met" : "NOT met");
    return 0;
  });
}

}  // namespace vlab::cli
