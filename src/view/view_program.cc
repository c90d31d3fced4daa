// The view's sources: a scene device's frames as they come; an arm device's
// joint states turned into body poses by mj_kinematics at a decimated rate;
// or a recording served whole for the page to replay.
#include "view/view_program.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "bridge/bridge_client.h"
#include "bridge/bridge_client_device.h"
#include "core/core_errors.h"
#include "lab/devices/device_scene.h"
#include "view/view_model.h"

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

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

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
  std::map<std::string, StaticFile> page = PageFiles(o.web.empty() ? DefaultWebDir() : o.web);

  // the source and what the page is told about the scene
  std::unique_ptr<bridge::Device> scene_device;
  std::unique_ptr<bridge::Arm> arm;
  std::unique_ptr<ViewModel> model;
  nlohmann::json info;
  std::vector<int> bodies;
  std::string recording, source;
  if (!o.scene.empty()) {
    std::string host;
    int port = 0;
    SplitHostPort("--scene", o.scene, &host, &port);
    scene_device = std::make_unique<bridge::Device>(
        bridge::Device::Connect(bridge::DeviceKind::kScene, host, port, o.connect_timeout_s));
    const nlohmann::json& d = scene_device->describe();
    for (const char* key : {"bodies", "geoms", "meshes", "textures", "rate_hz"}) info[key] = d.value(key, nlohmann::json());
    const std::string path = o.model.empty() ? d.value("model", std::string()) : o.model;
    if (!o.model.empty() || (!path.empty() && fs::is_regular_file(path))) model = ViewModel::Load(path);
    else if (!o.quiet) std::printf("vlab view: no model '%s' here: drawing primitives only (give --model)\n", path.c_str());
    info["mode"] = "live";
    source = "scene device '" + scene_device->name() + "' at " + o.scene;
  } else if (!o.arm.empty()) {
    std::string host;
    int port = 0;
    SplitHostPort("--arm", o.arm, &host, &port);
    model = ViewModel::Load(o.model);
    arm = std::make_unique<bridge::Arm>(bridge::Arm::Connect(host, port, o.connect_timeout_s));
    model->BindJoints(arm->joint_names());
    bodies = lab::SceneBodies(model->model());
    info = lab::SceneGeometry(model->model(), bodies);
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
    info["mode"] = "replay";
    source = "replay of " + o.replay + " (" + std::to_string(recording.size() / frame) + " frames)";
  }
  info["cameras"] = model ? model->Cameras() : nlohmann::json::array();
  const std::string info_text = info.dump();
  const ViewModel* m = model.get();
  auto resources = [m, info_text, &recording](const std::string& path, std::string* type, std::string* body) {
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
    *type = path.compare(0, 5, "/tex/") == 0 ? "image/png" : "application/octet-stream";
    if (const int id = IdAfter(path, "/mesh/"); m && id >= 0) return m->MeshBytes(id, body);
    if (const int id = IdAfter(path, "/tex/"); m && id >= 0) return m->TexturePng(id, body);
    return false;
  };
  std::unique_ptr<ViewServer> server = ViewServer::Create(o.server, std::move(page), resources);
  std::printf("vlab view: http://%s:%d/ (%s; %zu bodies)\n", server->address().c_str(), server->port(),
              source.c_str(), info["bodies"].size());
  std::fflush(stdout);

  // feed the newest frame until stopped
  const double start = Now();
  double last_keepalive = start, next_arm_frame = -1;
  long frames = 0, timeouts = 0;
  std::vector<double> poses(7 * bodies.size());
  while (!*stop && (o.duration_s <= 0 || Now() - start < o.duration_s)) {
    try {
      if (scene_device) {
        const bridge::Device::State s = scene_device->ReadLatest(0.1);
        server->Publish(EncodeFrame(s.time, static_cast<double>(s.seq), s.values.data(), static_cast<int>(s.values.size())));
        ++frames;
      } else if (arm) {
        const bridge::Arm::State s = arm->ReadLatest(0.1);
        if (s.time + 1e-9 < next_arm_frame) continue;
        next_arm_frame = std::max(next_arm_frame + 1.0 / o.rate_hz, s.time);
        model->ArmPoses(std::vector<double>(s.q.data(), s.q.data() + s.q.size()), bodies, poses.data());
        server->Publish(EncodeFrame(s.time, static_cast<double>(s.seq), poses.data(), static_cast<int>(poses.size())));
        ++frames;
      } else {
        ::usleep(100000);
      }
    } catch (const bridge::TimeoutError&) {
      ++timeouts;  // the lab paused or ended: keep serving the last pose
    }
    if ((scene_device || arm) && Now() - last_keepalive > kKeepAlive_s) {
      if (scene_device) scene_device->KeepAlive();
      if (arm) arm->KeepAlive();
      last_keepalive = Now();
    }
  }
  const ViewServerCounters c = server->counters();
  std::printf(
      "vlab view: %ld frames in, %ld sent, %ld skipped by slow clients; %ld requests (%ld errors), %ld connections "
      "refused, %ld WebSocket sessions (%ld closed for bad messages)\n",
      frames, c.frames_sent, c.frames_skipped, c.requests, c.errors, c.refused, c.ws_sessions, c.ws_closed_bad);
  return 0;
}

}  // namespace vlab::view
