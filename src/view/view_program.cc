// The view's sources: a scene device's frames as they come; an arm device's
// joint states turned into body poses by mj_kinematics at a decimated rate;
// or a recording served whole for the page to replay.
#include "view/view_program.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "bridge/bridge_camera_client.h"
#include "bridge/bridge_client.h"
#include "bridge/bridge_client_device.h"
#include "core/core_clock.h"
#include "core/core_errors.h"
#include "scene/scene_geometry.h"
#include "view/view_access.h"
#include "view/view_foxglove_feed.h"
#include "view/view_model.h"
#include "view/view_panels.h"

namespace vlab::view {

namespace fs = std::filesystem;

namespace {

constexpr double kKeepAlive_s = 2.0;  // a passive subscriber renews well inside the device's 10 s

std::string ReadWhole(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("vlab view: cannot read '" + path + "'");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string DefaultWebDir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string("view_web") : (exe.parent_path() / "view_web").string();
}

// the page's files, read once: the only files the server ever answers with
std::map<std::string, StaticFile> PageFiles(const std::string& dir) {
  const std::pair<const char*, const char*> files[] = {{"index.html", "text/html; charset=utf-8"},
                                                       {"view.js", "application/javascript"},
                                                       {"three.min.js", "application/javascript"},
                                                       {"OrbitControls.js", "application/javascript"}};
  std::map<std::string, StaticFile> table;
  for (const auto& [name, type] : files) {
    const std::string path = (fs::path(dir) / name).string();
    if (!fs::is_regular_file(path)) {
      throw InputError("vlab view: the page's file '" + path + "' is missing (build vlab, or give --web)");
    }
    table["/" + std::string(name)] = {type, ReadWhole(path)};
  }
  return table;
}

// "/mesh/12" -> 12; -1 unless PREFIX followed by 1-6 digits
int IdAfter(const std::string& path, const std::string& prefix) {
  if (path.compare(0, prefix.size(), prefix) != 0) return -1;
  const std::string digits = path.substr(prefix.size());
  if (digits.empty() || digits.size() > 6 || digits.find_first_not_of("0123456789") != std::string::npos) return -1;
  return std::stoi(digits);
}

// the WebSocket channels (ViewServerConfig::channels)
constexpr int kPoseChannel = 0, kCameraChannel = 1, kPlotChannel = 2;

// --arm's plots: the arm's states, decimated to `rate_hz`, on the plot channel
class PlotFeed {
 public:
  PlotFeed(const bridge::Arm& arm, const std::vector<std::string>& signals, double rate_hz)
      : signals_(arm.name(), arm.joint_names(), signals), interval_s_(1.0 / rate_hz) {}
  // publishes the state if a sample is due; true if it did
  bool Offer(const bridge::Arm::State& s, ViewServer* server) {
    if (s.time + 1e-9 < next_) return false;
    next_ = std::max(next_ + interval_s_, s.time);
    server->Publish(EncodePlotMessage(s.time, static_cast<double>(s.seq), signals_.Values(s.q, s.qd, s.tau)),
                    kPlotChannel);
    return true;
  }

 private:
  ArmSignals signals_;
  double interval_s_;
  double next_ = -1;
};

// a receiving loop on its own thread (the camera): it never blocks the pose
// feed, and what it gets goes out newest first
class Feeder {
 public:
  template <typename Step>
  Feeder(volatile std::sig_atomic_t* stop, Step step)
      : thread_([this, stop, step]() mutable {
          while (!*stop && !quit_) {
            try {
              if (step()) ++count_;
            } catch (const bridge::TimeoutError&) {
            } catch (const std::exception&) {
              ++errors_;  // a stray or malformed datagram: counted, the panel goes on
              std::this_thread::sleep_for(std::chrono::milliseconds(10));
            }
          }
        }) {}
  ~Feeder() {
    quit_ = true;
    thread_.join();
  }
  long count() const { return count_; }
  long errors() const { return errors_; }

 private:
  std::atomic<bool> quit_{false};
  std::atomic<long> count_{0}, errors_{0};
  std::thread thread_;
};

}  // namespace

void SplitHostPort(const std::string& option, const std::string& text, std::string* host, int* port) {
  const std::size_t colon = text.rfind(':');
  bool ok = colon != std::string::npos && colon > 0 && colon + 1 < text.size();
  if (ok) {
    *host = text.substr(0, colon);
    if (host->size() > 2 && host->front() == '[' && host->back() == ']') *host = host->substr(1, host->size() - 2);
    const std::string digits = text.substr(colon + 1);
    ok = digits.find_first_not_of("0123456789") == std::string::npos && digits.size() <= 5;
    *port = ok ? std::stoi(digits) : 0;
    ok = ok && *port >= 1 && *port <= 65535;
  }
  if (!ok) throw InputError(option + " '" + text + "': expected HOST:PORT, e.g. 127.0.0.1:50020");
}

int RunView(const ViewOptions& o, volatile std::sig_atomic_t* stop) {
  const int sources = !o.scene.empty() + !o.arm.empty() + !o.replay.empty();
  if (sources != 1) throw InputError("vlab view: give exactly one of --scene, --arm, --replay");
  if (!o.arm.empty() && o.model.empty()) throw InputError("vlab view: --arm needs --model SCENE.xml");
  if (!(o.rate_hz > 0 && o.rate_hz <= 1000)) throw InputError("vlab view: --rate must be > 0 and <= 1000 Hz");
  if (o.server.port < 0 || o.server.port > 65535) throw InputError("vlab view: --http must be 0 to 65535");
  if (o.server.max_connections < 1) throw InputError("vlab view: --max-connections must be >= 1");
  if (o.server.max_per_address < 1) throw InputError("vlab view: --max-per-address must be >= 1");
  for (const std::string& h : o.server.allowed_hosts) {
    if (h.empty() || h.find_first_of(" /:@?#") != std::string::npos || h == "*") {
      if (!(h.size() > 2 && h.front() == '[' && h.back() == ']')) {
        throw InputError("vlab view: --allow-host '" + h +
                         "': expected a host name or address, without port or scheme");
      }
    }
  }
  for (const std::string& origin : o.server.allowed_origins) {
    if (!ValidOrigin(origin)) {
      throw InputError("vlab view: --allow-origin '" + origin +
                       "': expected a whole origin, http:// or https:// and a host, e.g. https://app.foxglove.dev");
    }
  }
  if (!o.replay.empty() && !o.camera.empty()) throw InputError("vlab view: --camera is for live views, not --replay");
  if (o.foxglove_port < -1 || o.foxglove_port > 65535) throw InputError("vlab view: --foxglove must be 0 to 65535");
  if (!o.replay.empty() && o.foxglove_port >= 0) {
    throw InputError("vlab view: --foxglove is for live views (--scene, --arm), not --replay");
  }
  const std::vector<std::string> plots = o.plot.empty() ? std::vector<std::string>() : ParsePlotSignals(o.plot);
  std::map<std::string, StaticFile> page = PageFiles(o.web.empty() ? DefaultWebDir() : o.web);

  // the source and what the page is told about the scene
  std::unique_ptr<bridge::Device> scene_device;
  std::unique_ptr<bridge::Arm> arm;
  std::unique_ptr<ViewModel> model;
  nlohmann::json info;
  std::vector<int> bodies;
  std::string recording, source, plot_rows;
  std::vector<int> scene_signals;  // --scene: where each plotted signal is in the scene device's state
  std::size_t scene_pose_values = 0;
  std::unique_ptr<bridge::CameraClient> camera;
  std::unique_ptr<PlotFeed> plot_feed;
  std::vector<std::string> live_signals;  // --foxglove: the log columns the source gives
  if (!o.scene.empty()) {
    std::string host;
    int port = 0;
    SplitHostPort("--scene", o.scene, &host, &port);
    scene_device = std::make_unique<bridge::Device>(
        bridge::Device::Connect(bridge::DeviceKind::kScene, host, port, o.connect_timeout_s));
    const nlohmann::json& d = scene_device->describe();
    for (const char* key : {"bodies", "geoms", "meshes", "textures", "rate_hz"})
      info[key] = d.value(key, nlohmann::json());
    const std::string path = o.model.empty() ? d.value("model", std::string()) : o.model;
    if (!o.model.empty() || (!path.empty() && fs::is_regular_file(path)))
      model = ViewModel::Load(path);
    else if (!o.quiet)
      std::printf("vlab view: no model '%s' here: drawing primitives only (give --model)\n", path.c_str());
    info["mode"] = "live";
    source = "scene device '" + scene_device->name() + "' at " + o.scene;
    scene_pose_values = 7 * info["bodies"].size();
    const std::vector<std::string> sent = d.value("signals", std::vector<std::string>());
    live_signals = sent;
    if (static_cast<std::size_t>(scene_device->state_length()) != scene_pose_values + sent.size()) {
      throw bridge::ProtocolError("vlab view: scene device '" + scene_device->name() + "': its layout has " +
                                  std::to_string(scene_device->state_length()) +
                                  " values, not 7 per body and one per signal");
    }
    for (const std::string& p : plots) {
      const auto at = std::find(sent.begin(), sent.end(), p);
      if (at == sent.end()) {
        std::string list;
        for (const std::string& s : sent) list += (list.empty() ? "" : ", ") + s;
        throw InputError("vlab view: --plot: scene device '" + scene_device->name() + "' does not send signal '" + p +
                         "' (it sends: " + (list.empty() ? std::string("none") : list) +
                         "; add it to the scenario's scene device: signals: [...])");
      }
      scene_signals.push_back(static_cast<int>(scene_pose_values + (at - sent.begin())));
    }
  } else if (!o.arm.empty()) {
    std::string host;
    int port = 0;
    SplitHostPort("--arm", o.arm, &host, &port);
    model = ViewModel::Load(o.model);
    arm = std::make_unique<bridge::Arm>(bridge::Arm::Connect(host, port, o.connect_timeout_s));
    model->BindJoints(arm->joint_names());
    if (!plots.empty()) plot_feed = std::make_unique<PlotFeed>(*arm, plots, o.rate_hz);
    for (const char* quantity : {"q", "qd", "tau"}) {
      for (const std::string& joint : arm->joint_names())
        live_signals.push_back(arm->name() + "." + quantity + "." + joint);
    }
    bodies = scene::SceneBodies(model->model());
    info = scene::SceneGeometry(model->model(), bodies);
    info["rate_hz"] = o.rate_hz;
    info["mode"] = "live";
    source = "arm '" + arm->name() + "' at " + o.arm + ", poses by MuJoCo kinematics of " + o.model;
  } else {
    info = nlohmann::json::parse(ReadWhole((fs::path(o.replay) / "scene.json").string()), nullptr, false);
    if (info.is_discarded() || !info.contains("bodies")) {
      throw InputError("vlab view: '" + (fs::path(o.replay) / "scene.json").string() + "' is not a scene description");
    }
    recording = ReadWhole((fs::path(o.replay) / "poses.bin").string());
    const std::size_t frame = kFrameHeaderBytes + 28 * info["bodies"].size();
    if (recording.empty() || recording.size() % frame != 0) {
      throw InputError("vlab view: '" + (fs::path(o.replay) / "poses.bin").string() + "' is not whole frames of " +
                       std::to_string(info["bodies"].size()) + " bodies");
    }
    const std::string path = o.model.empty() ? info.value("model", std::string()) : o.model;
    if (!o.model.empty() || (!path.empty() && fs::is_regular_file(path))) model = ViewModel::Load(path);
    if (!plots.empty()) plot_rows = ReplayPlotRows((fs::path(o.replay) / "log.csv").string(), plots);
    info["mode"] = "replay";
    source = "replay of " + o.replay + " (" + std::to_string(recording.size() / frame) + " frames)";
  }
  if (!o.camera.empty()) {
    std::string host;
    int port = 0;
    SplitHostPort("--camera", o.camera, &host, &port);
    bridge::CameraClientOptions options;
    options.timeout_s = o.connect_timeout_s;
    options.decode = false;  // relayed as sent (raw frames: as PNG)
    camera = std::make_unique<bridge::CameraClient>(bridge::CameraClient::Connect(host, port, options));
    info["camera"] = {{"name", camera->name()},
                      {"width", camera->width()},
                      {"height", camera->height()},
                      {"fps", camera->fps()},
                      {"address", o.camera}};
    source += "; camera '" + camera->name() + "' at " + o.camera;
  }
  if (!plots.empty()) {
    info["plots"] = plots;
    info["plot_source"] = !o.replay.empty() ? std::string("log.csv")
                          : arm             ? "arm '" + arm->name() + "'"
                                            : "scene device '" + scene_device->name() + "'";
    source += "; plotting " + o.plot;
  }
  info["cameras"] = model ? model->Cameras() : nlohmann::json::array();
  info["lights"] = model ? model->Lights() : nlohmann::json::array();
  info["shadows"] = o.shadows;
  const std::string info_text = info.dump();
  const ViewModel* m = model.get();
  auto resources = [m, info_text, &recording, &plot_rows](const std::string& path, std::string* type,
                                                          std::string* body) {
    if (path == "/scene.json") {
      *type = "application/json";
      *body = info_text;
      return true;
    }
    if (path == "/recording.bin" && !recording.empty()) {
      *type = "application/octet-stream";
      *body = recording;
      return true;
    }
    if (path == "/plots.bin" && !plot_rows.empty()) {
      *type = "application/octet-stream";
      *body = plot_rows;
      return true;
    }
    *type = path.compare(0, 5, "/tex/") == 0 ? "image/png" : "application/octet-stream";
    if (const int id = IdAfter(path, "/mesh/"); m && id >= 0) return m->MeshBytes(id, body);
    if (const int id = IdAfter(path, "/tex/"); m && id >= 0) return m->TexturePng(id, body);
    return false;
  };
  ViewServerConfig server_config = o.server;
  server_config.channels = {"/ws", "/camera", "/plot"};  // kPoseChannel, kCameraChannel, kPlotChannel
  std::unique_ptr<ViewServer> server = ViewServer::Create(server_config, std::move(page), resources);
  // the Foxglove server: its own port, the page's bounds and Host/Origin rules
  std::unique_ptr<FoxgloveFeed> fox_feed;
  std::unique_ptr<ViewServer> fox;
  std::string fox_line;
  if (o.foxglove_port >= 0) {
    fox_feed = std::make_unique<FoxgloveFeed>(info, model ? model->model() : nullptr, live_signals,
                                              camera ? camera->name() : std::string());
    ViewServerConfig fox_config = o.server;
    fox_config.port = o.foxglove_port;
    fox_config.foxglove = true;
    fox_config.foxglove_channels = fox_feed->channels();
    fox_config.max_ws_message_bytes = 65536;  // a subscribe to every channel at once
    fox = ViewServer::Create(fox_config, {}, nullptr);
    fox_feed->PublishScene(0, fox.get());
    fox_line = "; foxglove ws://" + UrlHost(fox->address()) + ":" + std::to_string(fox->port()) + " (" +
               std::to_string(fox_feed->channels().size()) + " channels)";
  }
  std::printf("vlab view: http://%s:%d/ (%s; %zu bodies)%s\n", UrlHost(server->address()).c_str(), server->port(),
              source.c_str(), info["bodies"].size(), fox_line.c_str());
  std::fflush(stdout);
  if (!IsLoopbackAddress(server->address())) {
    std::fprintf(stderr,
                 "vlab view: warning: bound to %s, beyond loopback: anyone who can reach port %d of this machine can "
                 "watch the lab (poses, plots, camera pictures); bind 127.0.0.1 (the default) and use ssh -L to watch "
                 "from elsewhere (a browser that opens it by a host name needs --allow-host NAME)\n",
                 server->address().c_str(), server->port());
  }

  // the panels' feeds, each on its own thread
  std::unique_ptr<Feeder> camera_feed;
  if (camera) {
    bridge::CameraClient* c = camera.get();
    ViewServer* v = server.get();
    ViewServer* f = fox.get();
    FoxgloveFeed* feed = fox_feed.get();
    auto frame = std::make_shared<bridge::CameraClient::Frame>();
    camera_feed = std::make_unique<Feeder>(stop, [c, v, f, feed, frame] {
      c->ReceiveLatest(0.2, frame.get());
      std::string message = EncodeCameraMessage(*frame);
      if (f) {
        const char* format = frame->encoding == bridge::CameraEncoding::kJpeg ? "jpeg" : "png";
        feed->PublishCamera(frame->time_s, format, message.substr(kCameraHeaderBytes), f);
      }
      v->Publish(std::move(message), kCameraChannel);
      return true;
    });
  }

  // feed the newest frame until stopped
  const double start = WallNow();
  double last_keepalive = start, next_arm_frame = -1;
  long frames = 0, timeouts = 0, plot_samples = 0;
  std::vector<double> poses(7 * bodies.size()), arm_signals;
  while (!*stop && (o.duration_s <= 0 || WallNow() - start < o.duration_s)) {
    try {
      if (scene_device) {
        const bridge::Device::State s = scene_device->ReadLatest(0.1);
        server->Publish(
            EncodeFrame(s.time, static_cast<double>(s.seq), s.values.data(), static_cast<int>(scene_pose_values)));
        if (!scene_signals.empty()) {
          std::vector<double> values;
          for (int i : scene_signals) values.push_back(s.values[i]);
          server->Publish(EncodePlotMessage(s.time, static_cast<double>(s.seq), values), kPlotChannel);
          ++plot_samples;
        }
        if (fox) fox_feed->PublishFrame(s.time, s.values.data(), s.values.data() + scene_pose_values, fox.get());
        ++frames;
      } else if (arm) {
        const bridge::Arm::State s = arm->ReadLatest(0.1);
        if (s.time + 1e-9 < next_arm_frame) continue;
        if (plot_feed && plot_feed->Offer(s, server.get())) ++plot_samples;
        next_arm_frame = std::max(next_arm_frame + 1.0 / o.rate_hz, s.time);
        model->ArmPoses(std::vector<double>(s.q.data(), s.q.data() + s.q.size()), bodies, poses.data());
        server->Publish(EncodeFrame(s.time, static_cast<double>(s.seq), poses.data(), static_cast<int>(poses.size())));
        if (fox) {
          // q, qd, tau, one value per joint each; a short vector padded with zeros, as the plot's
          const std::size_t joints = live_signals.size() / 3;
          arm_signals.clear();
          for (const Eigen::VectorXd* v : {&s.q, &s.qd, &s.tau}) {
            const std::size_t n = std::min(joints, static_cast<std::size_t>(v->size()));
            arm_signals.insert(arm_signals.end(), v->data(), v->data() + n);
            arm_signals.resize(arm_signals.size() + joints - n, 0.0);
          }
          fox_feed->PublishFrame(s.time, poses.data(), arm_signals.data(), fox.get());
        }
        ++frames;
      } else {
        ::usleep(100000);
      }
    } catch (const bridge::TimeoutError&) {
      ++timeouts;  // the lab paused or ended: keep serving the last pose
    }
    if ((scene_device || arm) && WallNow() - last_keepalive > kKeepAlive_s) {
      if (scene_device) scene_device->KeepAlive();
      if (arm) arm->KeepAlive();
      last_keepalive = WallNow();
    }
  }
  const long camera_frames = camera_feed ? camera_feed->count() : 0,
             camera_errors = camera_feed ? camera_feed->errors() : 0;
  camera_feed.reset();  // joins: nothing publishes from here on
  if (camera && !o.quiet) {
    std::printf(
        "vlab view: camera: %ld frames relayed, %ld receive errors, %ld incomplete frames dropped, %ld chunks "
        "refused\n",
        camera_frames, camera_errors, camera->counters().frames_dropped, camera->counters().refused);
  }
  if (!plots.empty() && o.replay.empty() && !o.quiet) std::printf("vlab view: plots: %ld samples sent\n", plot_samples);
  const ViewServerCounters c = server->counters();
  std::printf(
      "vlab view: %ld frames in, %ld sent, %ld skipped by slow clients; %ld requests (%ld errors, %ld refused for "
      "their Host or Origin), %ld connections refused, %ld closed for a newer one, %ld without a request in time; %ld "
      "WebSocket sessions (%ld closed for bad messages, %ld for not reading)\n",
      frames, c.frames_sent, c.frames_skipped, c.requests, c.errors, c.bad_host, c.refused, c.evicted,
      c.header_timeouts, c.ws_sessions, c.ws_closed_bad, c.ws_closed_slow);
  if (fox) {
    const ViewServerCounters f = fox->counters();
    std::printf(
        "vlab view: foxglove: %ld messages sent, %ld skipped by slow clients; %ld WebSocket sessions (%ld refused "
        "for their Host or Origin, %ld refused: too many); %ld client writes refused (read-only), %ld malformed client "
        "messages\n",
        f.frames_sent, f.frames_skipped, f.ws_sessions, f.bad_host, f.refused, f.client_refused, f.client_bad);
  }
  return 0;
}

}  // namespace vlab::view
