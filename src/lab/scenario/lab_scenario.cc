#include "lab/scenario/lab_scenario.h"

#include <cctype>
#include <cmath>
#include <filesystem>

#include "core/core_errors.h"
#include "core/core_input_file.h"
#include "core/core_mujoco.h"
#include "core/core_realtime.h"
#include "lab/devices/device_kinds.h"
#include "lab/judge/lab_golden.h"
#include "lab/outputs/lab_log_formats.h"
#include "lab/scenario/lab_overrides.h"
#include "lab/scenario/lab_yaml.h"
#include "task/task_runtime.h"

namespace vlab::lab {

namespace fs = std::filesystem;

namespace {

Eigen::Quaterniond OrientationOf(MapReader& r) {
  const bool has_rpy = r.Has("rpy_deg");
  const bool has_quat = r.Has("quat");
  if (has_rpy && has_quat) r.Fail("quat", "give either rpy_deg or quat, not both");
  if (has_quat) {
    const std::vector<double> q = r.Numbers("quat", {});
    if (q.size() != 4) r.Fail("quat", "expected 4 numbers (w, x, y, z)");
    Eigen::Quaterniond quat(q[0], q[1], q[2], q[3]);
    if (quat.norm() < 1e-9) r.Fail("quat", "zero quaternion");
    return quat.normalized();
  }
  const std::vector<double> rpy = r.Numbers("rpy_deg", {0, 0, 0});
  if (rpy.size() != 3) r.Fail("rpy_deg", "expected 3 numbers (roll, pitch, yaw about fixed x, y, z), deg");
  const double k = M_PI / 180.0;
  // fixed-axis x, then y, then z: R = Rz(yaw) Ry(pitch) Rx(roll)
  return Eigen::Quaterniond(Eigen::AngleAxisd(rpy[2] * k, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(rpy[1] * k, Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(rpy[0] * k, Eigen::Vector3d::UnitX()));
}

double PositiveDuration(MapReader& r) {
  const double duration = r.Number("duration");
  if (!(duration > 0)) r.Fail("duration", "must be > 0 s");
  return duration;
}

// outputs.log: true (csv), false, or {format: NAME or [NAME, ...]}
void ReadLogOutput(const std::string& file, MapReader& outputs, OutputsConfig* out) {
  const YAML::Node node = outputs.Raw("log");
  if (!node || node.IsNull()) return;
  if (!node.IsMap()) {
    out->log = outputs.Bool("log", out->log);
    out->log_formats = out->log ? std::vector<std::string>{"csv"} : std::vector<std::string>{};
    return;
  }
  MapReader log(file, node, "outputs.log");
  const YAML::Node format = log.Raw("format");
  const std::vector<std::string> names =
      format.IsScalar() ? std::vector<std::string>{log.String("format")} : log.Strings("format", {});
  if (names.empty()) log.Fail("format", "expected csv, mat, hdf5 or mcap, or a list of them");
  out->log = true;
  out->log_formats.clear();
  for (const std::string& name : names) {
    ParseLogFormat(name, YamlWhere(file, format) + ": outputs.log.format");
    for (const std::string& taken : out->log_formats) {
      if (taken == name) log.Fail("format", "'" + name + "' listed twice");
    }
    out->log_formats.push_back(name);
  }
  log.Finish();
}

bool WritesCsv(const OutputsConfig& outputs) {
  for (const std::string& format : outputs.log_formats) {
    if (format == "csv") return true;
  }
  return false;
}

ImageOutputConfig ReadImageOutput(const std::string& file, const YAML::Node& node, const std::string& path) {
  MapReader r(file, node, path);
  ImageOutputConfig o;
  o.where = YamlWhere(file, node);
  o.camera = r.String("camera");
  o.every_s = r.Number("every", o.every_s);
  if (!(o.every_s > 0)) r.Fail("every", "must be > 0 s");
  o.width = r.Integer("width", o.width);
  o.height = r.Integer("height", o.height);
  if (o.width < 1 || o.width > 8192) r.Fail("width", "must be 1 to 8192 pixels");
  if (o.height < 1 || o.height > 8192) r.Fail("height", "must be 1 to 8192 pixels");
  o.png = r.Bool("png", o.png);
  o.depth = r.Bool("depth", o.depth);
  o.segmentation = r.Bool("segmentation", o.segmentation);
  o.last = r.Bool("last", o.last);
  o.video = r.String("video", o.video);
  if (!o.video.empty() && (o.video.find('/') != std::string::npos || o.video.size() < 5 ||
                           o.video.compare(o.video.size() - 4, 4, ".mp4") != 0)) {
    r.Fail("video", "must be a file name ending in .mp4, written in the output folder");
  }
  const std::string profile = r.String("profile", "quality");
  if (!render::ParseProfile(profile, &o.profile)) r.Fail("profile", std::string("must be ") + render::ProfileNames());
  if (!o.png && !o.depth && !o.segmentation && o.video.empty())
    r.Fail("png", "nothing to write: png, depth, segmentation and video are all off");
  r.Finish();
  return o;
}

// type: task, programs: [{robot, script, tip_site, base_body, wrench}, ...]
ControllerConfig ReadTaskController(MapReader& r, ControllerConfig c) {
  c.type = ControllerType::kTask;
  const double budget = r.Number("instruction_budget", static_cast<double>(c.instruction_budget));
  if (!(budget >= 1000 && budget <= 1e12) || budget != std::floor(budget)) {
    r.Fail("instruction_budget", "must be a whole number between 1000 and 1e12");
  }
  c.instruction_budget = static_cast<long>(budget);
  // markers: {NAME: HOST:PORT}: vision programs beside the lab (docs/tasks.md)
  const YAML::Node markers = r.Raw("markers");
  if (markers && !markers.IsNull()) {
    if (!markers.IsMap()) r.Fail("markers", "expected a mapping NAME: HOST:PORT (e.g. {vision: 127.0.0.1:50014})");
    for (const auto& kv : markers) {
      const std::string name = kv.first.as<std::string>();
      const std::string endpoint = kv.second.IsScalar() ? kv.second.as<std::string>() : "";
      const auto colon = endpoint.rfind(':');
      // the port: 1 to 5 decimal digits, nothing after them
      const std::string digits = colon == std::string::npos ? "" : endpoint.substr(colon + 1);
      const bool numeric =
          !digits.empty() && digits.size() <= 5 && digits.find_first_not_of("0123456789") == std::string::npos;
      const int port = numeric ? std::stoi(digits) : 0;
      if (colon == std::string::npos || colon == 0 || port < 1 || port > 65535) {
        r.Fail("markers", "'" + name + "': expected HOST:PORT (port 1..65535), got '" + endpoint + "'");
      }
      c.markers[name] = endpoint;
    }
  }
  const YAML::Node programs = r.Sequence("programs");
  if (programs.size() == 0)
    r.Fail("programs", "needs at least one program: {robot: ARM, script: FILE.lua, tip_site: SITE}");
  const std::filesystem::path dir = std::filesystem::path(r.file()).parent_path();
  for (std::size_t i = 0; i < programs.size(); ++i) {
    MapReader p(r.file(), programs[i], r.Child("programs") + "[" + std::to_string(i) + "]");
    TaskProgramEntry e;
    e.where = YamlWhere(r.file(), programs[i]) + ": " + p.path();
    e.robot = p.String("robot", "");
    e.script = (dir / p.String("script")).lexically_normal().string();
    e.tip_site = p.String("tip_site", "");
    e.base_body = p.String("base_body", e.base_body);
    e.wrench = p.String("wrench", "");
    // params: {NAME: VALUE}: the script's PARAMS (scalars; docs/tasks.md)
    const YAML::Node params = p.Raw("params");
    if (params && !params.IsNull()) {
      if (!params.IsMap()) p.Fail("params", "expected a mapping NAME: VALUE (e.g. {word: FACE})");
      for (const auto& kv : params) {
        const std::string name = kv.first.as<std::string>();
        task::CheckParamName(name, YamlWhere(r.file(), kv.first) + ": " + p.Child("params"));
        if (!kv.second.IsScalar()) p.Fail("params", "'" + name + "': expected a number, true/false or a string");
        e.params[name] = kv.second.as<std::string>();
      }
    }
    if (!e.robot.empty() && e.tip_site.empty())
      p.Fail("tip_site", "required with a robot (the site at the tool flange)");
    p.Finish();
    c.programs.push_back(e);
  }
  r.Finish();
  return c;
}

ControllerConfig ReadController(MapReader r) {
  ControllerConfig c;
  c.where = YamlWhere(r.file(), r.node());
  const std::string type = r.String("type", "none");
  if (type == "none") {
    r.Finish();
    return c;
  }
  if (type == "external") {
    c.type = ControllerType::kExternal;
    c.command = r.Strings("command", {});
    if (c.command.empty() || c.command[0].empty()) r.Fail("command", "expected [PROGRAM, ARGUMENT, ...]");
    c.realtime_priority = r.Integer("realtime_priority", 0);
    if (c.realtime_priority < 0 || c.realtime_priority > kMaxRealtimePriority) {
      r.Fail("realtime_priority", "must be 0 (normal priority) to 99 (SCHED_FIFO)");
    }
    c.ends_run = r.Bool("ends_run", c.ends_run);
    r.Finish();
    return c;
  }
  if (type == "task") return ReadTaskController(r, c);
  c.arm = r.String("arm");
  const std::string timing = r.String("timing", "quintic");
  if (timing != "quintic" && timing != "trapezoidal") r.Fail("timing", "must be quintic or trapezoidal");
  c.timing = timing == "trapezoidal" ? control::TimeScalingType::kTrapezoidal : control::TimeScalingType::kQuintic;
  c.start_s = r.Number("start", c.start_s);
  if (c.start_s < 0) r.Fail("start", "must be >= 0 s");
  c.base_body = r.String("base_body", c.base_body);
  c.tip_site = r.String("tip_site");
  const YAML::Node waypoints = r.Sequence("waypoints");
  if (waypoints.size() == 0) r.Fail("waypoints", "needs at least one waypoint");
  if (type == "task_space") {
    c.type = ControllerType::kTaskSpace;
    MapReader gains = r.Map("gains");
    c.k_position = gains.Number("position", c.k_position);
    c.k_orientation = gains.Number("orientation", c.k_orientation);
    c.k_null = gains.Number("null_space", c.k_null);
    c.damping = gains.Number("damping", c.damping);
    if (c.k_position < 0 || c.k_orientation < 0 || c.k_null < 0 || c.damping < 0) {
      gains.Fail("position", "gains must be >= 0");
    }
    gains.Finish();
    for (std::size_t i = 0; i < waypoints.size(); ++i) {
      MapReader w(r.file(), waypoints[i], r.Child("waypoints") + "[" + std::to_string(i) + "]");
      CartesianWaypoint wp;
      const std::vector<double> p = w.Numbers("position", {});
      if (p.size() != 3) w.Fail("position", "expected 3 numbers (x, y, z), m, world frame");
      wp.position_W = Eigen::Vector3d(p[0], p[1], p[2]);
      wp.orientation_W = OrientationOf(w);
      wp.duration_s = PositiveDuration(w);
      w.Finish();
      c.cartesian.push_back(wp);
    }
  } else if (type == "joint_pd") {
    c.type = ControllerType::kJointPd;
    MapReader gains = r.Map("gains");
    c.kp = gains.Numbers("kp", {});
    c.kd = gains.Numbers("kd", {});
    c.pd_bandwidth_hz = gains.Number("bandwidth_hz", c.pd_bandwidth_hz);
    if (!(c.pd_bandwidth_hz > 0)) gains.Fail("bandwidth_hz", "must be > 0 Hz");
    gains.Finish();
    for (std::size_t i = 0; i < waypoints.size(); ++i) {
      MapReader w(r.file(), waypoints[i], r.Child("waypoints") + "[" + std::to_string(i) + "]");
      JointWaypoint wp;
      wp.q = w.Numbers("q", {});
      if (wp.q.empty()) w.Fail("q", "missing required key");
      wp.duration_s = PositiveDuration(w);
      w.Finish();
      c.joint.push_back(wp);
    }
  } else {
    r.Fail("type", "unknown controller type '" + type + "' (known: none, joint_pd, task_space, external, task)");
  }
  r.Finish();
  return c;
}

CheckConfig ReadCheck(const std::string& file, const YAML::Node& node, const std::string& path) {
  MapReader r(file, node, path);
  CheckConfig c;
  c.where = YamlWhere(file, node);
  c.name = r.String("name");
  if (r.Has("golden")) {
    const std::string golden = r.String("golden");
    c.golden = (fs::path(file).parent_path() / golden).lexically_normal().string();
    if (!fs::exists(c.golden)) r.Fail("golden", "no such golden folder or log: " + c.golden);
    c.signal = "golden:" + golden;
    c.max = 1.0;  // the worst divergence, in multiples of its tolerance
    c.tolerances = ReadTolerances(file, r.Sequence("tolerances"), r.Child("tolerances"));
    c.from_s = r.Number("from", c.from_s);
    c.to_s = r.Number("to", c.to_s);
    if (c.to_s < c.from_s) r.Fail("to", "must be >= from");
    r.Finish();
    return c;
  }
  c.signal = r.String("signal");
  const std::string reduce = r.String("reduce", "max");
  if (!ReduceFromName(reduce, &c.reduce))
    r.Fail("reduce", "unknown reduction '" + reduce +
                         "' (known: max, min, mean, rms, final, max_abs, min_of_window_max, max_of_window_min, range)");
  c.min = r.Number("min", c.min);
  c.max = r.Number("max", c.max);
  if (!r.Has("min") && !r.Has("max")) r.Fail("max", "a check needs a bound: min, max or both");
  c.from_s = r.Number("from", c.from_s);
  c.to_s = r.Number("to", c.to_s);
  if (c.to_s < c.from_s) r.Fail("to", "must be >= from");
  const bool windowed = c.reduce == Reduce::kMinOfWindowMax || c.reduce == Reduce::kMaxOfWindowMin;
  if (windowed) {
    if (!r.Has("window")) r.Fail("window", "reduce '" + reduce + "' needs a window (s, > 0)");
    c.window_s = r.Number("window", 0.0);
    if (!(c.window_s > 0.0) || !std::isfinite(c.window_s)) r.Fail("window", "must be a finite number of seconds > 0");
  } else if (r.Has("window")) {
    r.Fail("window", "only for reduce min_of_window_max or max_of_window_min");
  }
  r.Finish();
  return c;
}

}  // namespace

std::string ResolveScenarioPath(const std::string& arg) {
  if (fs::is_regular_file(arg)) return arg;
  for (const char* ext : {".yaml", ".yml"}) {
    if (fs::is_regular_file(arg + ext)) return arg + ext;
  }
  return arg;
}

const char* ReduceName(Reduce reduce) {
  switch (reduce) {
    case Reduce::kMax:
      return "max";
    case Reduce::kMin:
      return "min";
    case Reduce::kMean:
      return "mean";
    case Reduce::kRms:
      return "rms";
    case Reduce::kFinal:
      return "final";
    case Reduce::kMaxAbs:
      return "max_abs";
    case Reduce::kMinOfWindowMax:
      return "min_of_window_max";
    case Reduce::kMaxOfWindowMin:
      return "max_of_window_min";
    case Reduce::kRange:
      return "range";
  }
  return "?";
}

bool ReduceFromName(const std::string& name, Reduce* reduce) {
  for (Reduce k : {Reduce::kMax, Reduce::kMin, Reduce::kMean, Reduce::kRms, Reduce::kFinal, Reduce::kMaxAbs,
                   Reduce::kMinOfWindowMax, Reduce::kMaxOfWindowMin, Reduce::kRange}) {
    if (name == ReduceName(k)) {
      *reduce = k;
      return true;
    }
  }
  return false;
}

const char* ControllerTypeName(ControllerType type) {
  switch (type) {
    case ControllerType::kNone:
      return "none";
    case ControllerType::kJointPd:
      return "joint_pd";
    case ControllerType::kTaskSpace:
      return "task_space";
    case ControllerType::kExternal:
      return "external";
    case ControllerType::kTask:
      return "task";
  }
  return "?";
}

ClockConfig ScenarioClock(const Scenario& scenario, ClockMode mode) {
  ClockConfig c;
  c.mode = mode;
  c.period_s = scenario.control_period_s;
  c.lockstep = scenario.lockstep;
  c.realtime = scenario.realtime;
  return c;
}

Scenario LoadScenario(const std::string& path) { return LoadScenario(path, {}); }

namespace {

// True when `message` speaks of `key_path` or something under it.
bool MentionsPath(const std::string& message, const std::string& key_path) {
  for (std::size_t at = message.find(key_path); at != std::string::npos; at = message.find(key_path, at + 1)) {
    const bool starts = at == 0 || message[at - 1] == ' ';
    const std::size_t end = at + key_path.size();
    const bool ends = end == message.size() || message[end] == ':' || message[end] == '.' || message[end] == '[' ||
                      message[end] == ' ';
    if (starts && ends) return true;
  }
  return false;
}

Scenario ParseScenario(const std::string& path, const YAML::Node& root);

}  // namespace

Scenario LoadScenario(const std::string& path, const std::vector<std::string>& sets) {
  // an MJCF scene where a scenario is expected: say so, not what YAML makes of XML
  const std::string text = ReadInputFile(path, "scenario '" + path + "'", kMaxYamlBytes);
  const std::size_t first = text.find_first_not_of(" \t\r\n\f\v");
  if (first != std::string::npos && text[first] == '<') {
    throw InputError(path +
                     ": this is an MJCF scene, not a scenario: a scenario is a YAML file that names its "
                     "scene (scene: FILE.xml), its devices and checks (docs/scenarios.md)");
  }
  const YAML::Node root = ParseYamlText(path, text);
  if (!root.IsMap()) throw InputError(path + ": a scenario must be a YAML mapping");
  std::vector<Override> overrides;
  for (const std::string& set : sets) overrides.push_back(ParseOverride(set));
  const std::vector<std::string> paths = ApplyOverrides(path, root, overrides);
  YAML::Emitter resolved;
  resolved << root;
  try {
    Scenario s = ParseScenario(path, root);
    for (const Override& o : overrides) s.overrides.emplace_back(o.key, o.value);
    s.resolved_yaml = resolved.c_str();
    return s;
  } catch (const InputError& e) {
    // name the --set behind a bad value (the last one that touched its key)
    const std::string message = e.what();
    for (std::size_t i = overrides.size(); i-- > 0;) {
      if (MentionsPath(message, paths[i])) {
        throw InputError(message + " (from --set " + overrides[i].key + "=" + overrides[i].value + ")");
      }
    }
    throw;
  }
}

namespace {

Scenario ParseScenario(const std::string& path, const YAML::Node& root) {
  MapReader r(path, root, "");
  Scenario s;
  s.file = path;
  s.name = r.String("name", fs::path(path).stem().string());
  if (s.name.empty() || s.name.find_first_of("/\\") != std::string::npos || s.name[0] == '.') {
    r.Fail("name", "must be a plain folder name");
  }
  s.description = r.String("description", "");
  const std::string scene = r.String("scene");
  s.scene = (fs::path(path).parent_path() / scene).lexically_normal().string();
  s.scene_where = YamlWhere(path, root["scene"]);
  s.duration_s = r.Number("duration");
  if (!ValidDuration(s.duration_s)) r.Fail("duration", "must be > 0 s and at most 1e6 s");
  s.control_period_s = r.Number("control_period", s.control_period_s);
  if (!(s.control_period_s > 0 && s.control_period_s <= kMaxControlPeriod_s)) {
    r.Fail("control_period", "must be > 0 s and at most 10 s");
  }
  s.seed = r.Has("seed") ? YamlSeed(path, r.Raw("seed"), "seed") : 1;
  if (r.Has("clock")) {
    const std::string clock = r.String("clock");
    if (clock != "fast" && clock != "lockstep" && clock != "realtime") {
      r.Fail("clock", "unknown clock '" + clock + "' (known: fast, lockstep, realtime)");
    }
    s.clock = ParseClockMode(clock, "clock");
  }
  MapReader lockstep = r.Map("lockstep");
  s.lockstep.timeout_s = lockstep.Number("timeout", s.lockstep.timeout_s);
  s.lockstep.start_timeout_s = lockstep.Number("start_timeout", s.lockstep.start_timeout_s);
  const std::string on_timeout = lockstep.String("on_timeout", "hold");
  s.lockstep.release_after = lockstep.Integer("release_after", s.lockstep.release_after);
  if (!(s.lockstep.timeout_s > 0)) lockstep.Fail("timeout", "must be > 0 s");
  if (!(s.lockstep.start_timeout_s > 0)) lockstep.Fail("start_timeout", "must be > 0 s");
  if (on_timeout != "hold" && on_timeout != "fail") lockstep.Fail("on_timeout", "must be hold or fail");
  s.lockstep.on_timeout = on_timeout == "fail" ? OnTimeout::kFail : OnTimeout::kHold;
  if (s.lockstep.release_after < 1) lockstep.Fail("release_after", "must be >= 1");
  lockstep.Finish();
  MapReader realtime = r.Map("realtime");
  s.realtime.factor = realtime.Number("factor", s.realtime.factor);
  if (!(s.realtime.factor > 0 && s.realtime.factor <= 1000)) realtime.Fail("factor", "must be in (0, 1000]");
  s.realtime.priority = realtime.Integer("priority", s.realtime.priority);
  if (s.realtime.priority < 0 || s.realtime.priority > kMaxRealtimePriority) {
    realtime.Fail("priority", "must be 0 (normal priority) to 99 (SCHED_FIFO)");
  }
  realtime.Finish();
  s.keyframe = r.String("keyframe", "");
  if (r.Has("keyframe")) s.keyframe_where = YamlWhere(path, root["keyframe"]);
  if (r.Has("randomize")) {
    MapReader randomize = r.Map("randomize");
    s.randomize = ReadRandomize(randomize);
  }
  s.allow_warnings = r.Strings("allow_warnings", {});
  for (const std::string& w : s.allow_warnings) {
    if (WarningIndex(w) < 0 || IsDivergenceWarning(WarningIndex(w))) {
      r.Fail("allow_warnings", "unknown or non-allowable warning '" + w +
                                   "' (allowable: inertia, contactfull, cnstrfull, vgeomfull, badctrl)");
    }
  }

  const YAML::Node devices = r.Sequence("devices");
  for (std::size_t i = 0; i < devices.size(); ++i) {
    s.devices.push_back(ReadDevice(path, devices[i], "devices[" + std::to_string(i) + "]"));
    for (std::size_t j = 0; j < i; ++j) {
      if (s.devices[j].name == s.devices[i].name) {
        throw InputError(s.devices[i].where + ": devices[" + std::to_string(i) + "].name: duplicate device name '" +
                         s.devices[i].name + "'");
      }
    }
  }
  if (r.Has("controller")) s.controller = ReadController(r.Map("controller"));
  MapReader outputs = r.Map("outputs");
  ReadLogOutput(path, outputs, &s.outputs);
  const YAML::Node images = outputs.Sequence("images");
  for (std::size_t i = 0; i < images.size(); ++i) {
    s.outputs.images.push_back(ReadImageOutput(path, images[i], "outputs.images[" + std::to_string(i) + "]"));
  }
  const YAML::Node plots = outputs.Sequence("plots");
  for (std::size_t i = 0; i < plots.size(); ++i) {
    MapReader pr(path, plots[i], "outputs.plots[" + std::to_string(i) + "]");
    PlotConfig plot;
    plot.where = YamlWhere(path, plots[i]);
    plot.file = pr.String("file");
    if (plot.file.size() < 5 || plot.file.substr(plot.file.size() - 4) != ".png" ||
        plot.file.find('/') != std::string::npos) {
      pr.Fail("file", "expected a PNG file name in the output folder (NAME.png)");
    }
    plot.csv = pr.String("csv", plot.csv);
    if (plot.csv.find('/') != std::string::npos) pr.Fail("csv", "expected a file name in the output folder");
    plot.x = pr.String("x", plot.x);
    plot.y = pr.Strings("y", {});
    if (plot.y.empty()) pr.Fail("y", "needs at least one column");
    plot.title = pr.String("title", "");
    plot.ylabel = pr.String("ylabel", "");
    pr.Finish();
    s.outputs.plots.push_back(plot);
  }
  if (outputs.Has("poses")) {
    MapReader poses = outputs.Map("poses");
    s.outputs.poses = true;
    s.outputs.poses_where = path;
    s.outputs.poses_rate_hz = poses.Number("rate", s.outputs.poses_rate_hz);
    if (!(s.outputs.poses_rate_hz >= 0 && std::isfinite(s.outputs.poses_rate_hz))) {
      poses.Fail("rate", "must be >= 0 Hz (0: every control period)");
    }
    poses.Finish();
  }
  outputs.Finish();
  const YAML::Node checks = r.Sequence("checks");
  for (std::size_t i = 0; i < checks.size(); ++i) {
    s.checks.push_back(ReadCheck(path, checks[i], "checks[" + std::to_string(i) + "]"));
    if (!s.checks.back().golden.empty() && !WritesCsv(s.outputs)) {
      throw InputError(s.checks.back().where + ": checks[" + std::to_string(i) +
                       "].golden: a golden check compares log.csv: it needs outputs.log: true (or a format list "
                       "with csv)");
    }
  }
  r.Finish();
  return s;
}

}  // namespace

}  // namespace vlab::lab
