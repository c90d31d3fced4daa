// vlab bench view: what the scene stream and a viewer cost the lab. The same
// scenario (default scenes/pa10_view: the PA10 under joint PD, 500 Hz) runs
// served, fast clock, (a) without its scene device and (b) with it and one
// viewer attached (`vlab view --scene` in its own process, started once the
// device is bound, and a WebSocket client of its page in this one); the
// figure is the lab's wall time per control period, the median over the
// run's second half (the viewer attaches during the first), best of
// --repeat runs, and the ratio b/a (goal <= 1.05).
// Then the stream's bytes per second, per subscriber, at real time.
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>

#include "cli/cli_commands.h"
#include "cli/cli_cpus.h"
#include "core/core_clock.h"
#include "core/core_errors.h"
#include "core/core_mujoco.h"
#include "core/core_realtime.h"
#include "lab/devices/device_scene.h"
#include "lab/run/lab_runner.h"
#include "lab/scenario/lab_scenario.h"

namespace vlab::cli {

namespace {

constexpr const char* kDefaultScenario = "scenes/pa10_view.yaml";

// a viewer: vlab view in its own process, and a WebSocket client of its page
class Viewer {
 public:
  explicit Viewer(int scene_port) {
    int fds[2];
    if (::pipe(fds) != 0) return;
    pid_ = ::fork();
    if (pid_ == 0) {
      ::dup2(fds[1], STDOUT_FILENO);
      ::close(fds[0]);
      ::close(fds[1]);
      const std::string scene = "127.0.0.1:" + std::to_string(scene_port);
      ::execl("/proc/self/exe", "vlab", "view", "--scene", scene.c_str(), "--http", "0", "-q",
              static_cast<char*>(nullptr));
      ::_exit(127);
    }
    ::close(fds[1]);
    out_ = fds[0];
    client_ = std::thread([this] { Read(); });
  }
  ~Viewer() {
    stop_ = true;
    if (pid_ > 0) {
      ::kill(pid_, SIGINT);
      ::waitpid(pid_, nullptr, 0);
    }
    if (client_.joinable()) client_.join();
    if (out_ >= 0) ::close(out_);
  }
  long frames() const { return frames_.load(); }
  /// Wall time of its first frame (0: none yet).
  double attached_at() const { return attached_at_.load(); }
  long bytes() const { return bytes_.load(); }

 private:
  // its start line names the page's port; then every WebSocket frame until it ends
  void Read() {
    std::string line;
    char c = 0;
    while (!stop_ && line.find('\n') == std::string::npos) {
      pollfd p{out_, POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      if (::read(out_, &c, 1) != 1) return;
      line += c;
    }
    const std::size_t colon = line.find(':', line.find("http://") + 7);
    if (colon == std::string::npos) return;
    namespace asio = boost::asio;
    asio::io_context io;
    boost::beast::websocket::stream<asio::ip::tcp::socket> ws(io);
    boost::beast::error_code ec;
    ws.next_layer().connect(
        {asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(std::atoi(line.c_str() + colon + 1))}, ec);
    if (!ec) ws.handshake("127.0.0.1", "/ws", ec);
    while (!ec && !stop_) {
      boost::beast::flat_buffer b;
      ws.read(b, ec);
      if (ec) break;
      if (frames_ == 0) attached_at_ = vlab::WallNow();
      ++frames_;
      bytes_ += static_cast<long>(b.size());
    }
  }
  pid_t pid_ = -1;
  int out_ = -1;
  std::thread client_;
  std::atomic<bool> stop_{false};
  std::atomic<long> frames_{0}, bytes_{0};
  std::atomic<double> attached_at_{0};
};

// one fast served run; the lab's wall time per period, median of the second half
double PeriodTime(const lab::Scenario& scenario, bool viewer, long* frames, long* bytes, bool* late) {
  std::unique_ptr<lab::Lab> lab = lab::Lab::Create(scenario);
  lab::BridgeOptions options;
  for (const auto& d : scenario.devices) {
    if (d.port != 0) options.ports[d.name] = 0;  // any free port
  }
  std::unique_ptr<Viewer> view;
  lab::RunOptions run;
  run.serve = &options;
  run.clock = ClockMode::kFast;
  run.on_serving = [&](const std::vector<lab::ServedDevice>& devices) {
    for (const auto& d : devices) {
      if (viewer && d.kind == "scene") view = std::make_unique<Viewer>(d.port);
    }
  };
  std::vector<double> ends;  // wall time at each period's end
  ends.reserve(static_cast<std::size_t>(scenario.duration_s / scenario.control_period_s) + 2);
  run.observe = [&ends](double, const mjModel*, mjData*) {
    if (ends.size() < ends.capacity()) ends.push_back(vlab::WallNow());
  };
  const lab::RunResult r = lab->Run(run);
  if (r.exit_code != 0 && r.failure.find("check") == std::string::npos) {
    std::printf("    (run: %s)\n", r.failure.c_str());
  }
  std::vector<double> periods;
  for (std::size_t i = ends.size() / 2 + 1; i < ends.size(); ++i) periods.push_back(ends[i] - ends[i - 1]);
  if (view) {
    *frames = view->frames();
    *bytes = view->bytes();
    *late = view->attached_at() == 0 || ends.empty() || view->attached_at() > ends[ends.size() / 2];
  }
  if (periods.empty()) return 0;
  std::nth_element(periods.begin(), periods.begin() + periods.size() / 2, periods.end());
  return periods[periods.size() / 2];
}

}  // namespace

int BenchView(const BenchArgs& args) {
  return WithErrorReport([&args] {
    vlab::InstallMujocoHandlers();
    lab::Scenario with =
        lab::LoadScenario(lab::ResolveScenarioPath(args.scenario.empty() ? kDefaultScenario : args.scenario));
    with.duration_s = args.duration_s > 0 ? args.duration_s : 30.0;
    with.checks.clear();
    lab::Scenario without = with;
    without.devices.erase(
        std::remove_if(without.devices.begin(), without.devices.end(),
                       [](const lab::DeviceConfig& d) { return d.kind == bridge::DeviceKind::kScene; }),
        without.devices.end());
    const lab::DeviceConfig* scene = nullptr;
    for (const auto& d : with.devices) {
      if (d.kind == bridge::DeviceKind::kScene) scene = &d;
    }
    if (!scene || scene->port == 0) {
      throw vlab::InputError(with.file + ": bench view needs a served device of kind scene (e.g. " + kDefaultScenario +
                             ")");
    }
    const std::vector<int> cpus = ThreadCpus();
    std::printf("vlab bench view: scenario %s, %.1f s simulated per run, control period %.3f ms, best of %d\n",
                with.name.c_str(), with.duration_s, with.control_period_s * 1e3, args.repeat);
    std::printf("  CPUs: %zu allowed (%s); fast clock, served\n", cpus.size(), CpuListText(cpus).c_str());
    double a = 1e9, b = 1e9;
    long frames = 0, bytes = 0;
    bool late = false;
    for (int i = 0; i < args.repeat; ++i) {
      long f = 0, by = 0;
      bool l = false;
      a = std::min(a, PeriodTime(without, false, &f, &by, &l));
      b = std::min(b, PeriodTime(with, true, &f, &by, &l));
      frames = std::max(frames, f);
      bytes = std::max(bytes, by);
      late = late || l;
    }
    const double ratio = b / a;
    std::printf("  the lab's wall time per control period, median of each run's second half:\n");
    std::printf("  (a) without the scene stream            %8.2f us per period\n", a * 1e6);
    std::printf("  (b) scene stream + one viewer (browser-side WebSocket client got %ld frames)\n", frames);
    std::printf("                                          %8.2f us per period; ratio b/a %.3f (goal <= 1.05) -> %s\n",
                b * 1e6, ratio, ratio <= 1.05 ? "met" : "NOT met");
    // the stream's size: the device's datagrams and the page's WebSocket frames
    std::unique_ptr<lab::Lab> lab = lab::Lab::Create(with);
    const std::size_t n = lab::SceneBodies(lab->model()).size();
    const double rate = scene->ParamsAs<lab::SceneParams>().rate_hz;
    const double udp = 8.0 * (7 + 7 * n), ws = 16.0 + 28 * n + 4;  // + the WebSocket frame header
    std::printf(
        "  stream: %zu bodies at %.0f Hz: UDP %.0f B/frame = %.1f kB/s per subscriber; WebSocket %.0f B/frame = "
        "%.1f kB/s per browser (at real time)\n",
        n, rate, udp, udp * rate / 1e3, ws, ws * rate / 1e3);
    if (late) std::printf("  (the viewer attached after a run's midpoint: give a longer --duration)\n");
    if (frames > 0)
      std::printf("  measured: %.0f B of payload per WebSocket frame\n", static_cast<double>(bytes) / frames);
    return 0;
  });
}

}  // namespace vlab::cli
