#include "lab/lab_scenario.h"

#include <cmath>
#include <filesystem>

#include "lab/lab_errors.h"
#include "lab/lab_mujoco.h"
#include "lab/lab_yaml.h"

namespace vlab::lab {

namespace fs = std::filesystem;

namespace {

std::string Where(const std::string& file, const YAML::Node& node) {
  return file + ":" + std::to_string(node.Mark().line + 1);
}

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

DeviceConfig ReadDevice(const std::string& file, const YAML::Node& node, const std::string& path) {
  MapReader r(file, node, path);
  DeviceConfig device;
  device.where = Where(file, node);
  device.name = r.String("name");
  device.kind = r.String("kind");
  device.port = r.Integer("port", 0);
  if (device.port < 0 || device.port > 65535) r.Fail("port", "must be 0 (not served) to 65535");
  if (device.kind == "arm") {
    ArmDeviceConfig& arm = device.arm;
    arm.joints = r.Strings("joints", {});
    if (arm.joints.empty()) r.Fail("joints", "an arm needs at least one joint");
    arm.actuators = r.Strings("actuators", arm.joints);
    if (arm.actuators.size() != arm.joints.size()) r.Fail("actuators", "needs one actuator per joint");
    arm.initial = r.Numbers("initial", {});
    if (!arm.initial.empty() && arm.initial.size() != arm.joints.size()) {
      r.Fail("initial", "needs one value per joint (" + std::to_string(arm.joints.size()) + ")");
    }
    MapReader servo = r.Map("servo");
    arm.max_velocity = r.Numbers("max_velocity", {});
    if (!arm.max_velocity.empty() && arm.max_velocity.size() != arm.joints.size()) {
      r.Fail("max_velocity", "needs one value per joint (" + std::to_string(arm.joints.size()) + ")");
    }
    for (double v : arm.max_velocity) {
      if (!(v > 0)) r.Fail("max_velocity", "values must be > 0 rad/s");
    }
    arm.watchdog_periods = r.Integer("watchdog_periods", arm.watchdog_periods);
    if (arm.watchdog_periods < 0) r.Fail("watchdog_periods", "must be >= 0 (0: off)");
    arm.owner_timeout_s = r.Number("owner_timeout", arm.owner_timeout_s);
    if (!(arm.owner_timeout_s > 0)) r.Fail("owner_timeout", "must be > 0 s");
    arm.log_following_error = r.Bool("log_following_error", arm.log_following_error);
    arm.servo.bandwidth_hz = servo.Number("bandwidth_hz", arm.servo.bandwidth_hz);
    arm.servo.damping_ratio = servo.Number("damping_ratio", arm.servo.damping_ratio);
    if (!(arm.servo.bandwidth_hz > 0)) servo.Fail("bandwidth_hz", "must be > 0 Hz");
    if (!(arm.servo.damping_ratio > 0)) servo.Fail("damping_ratio", "must be > 0");
    servo.Finish();
  } else if (device.kind == "wrench") {
    WrenchDeviceConfig& w = device.wrench;
    w.site = r.String("site", "");
    w.force_sensor = r.String("force_sensor");
    w.torque_sensor = r.String("torque_sensor");
    w.model = r.String("model", w.model);
    w.full_scale = r.Numbers("full_scale", {});
    if (!w.full_scale.empty() && w.full_scale.size() != 6) r.Fail("full_scale", "expected 6 numbers (N, N, N, N·m, N·m, N·m)");
    w.filter = r.Integer("filter", w.filter);
    if (w.filter < 0 || w.filter > 6) r.Fail("filter", "must be 0 (unfiltered) to 6");
    w.noise = r.Bool("noise", w.noise);
    w.bias = r.Bool("bias", w.bias);
    w.quantization = r.Bool("quantization", w.quantization);
  } else if (device.kind == "camera") {
    CameraDeviceConfig& c = device.camera;
    c.camera = r.String("camera");
    c.width = r.Integer("width", c.width);
    c.height = r.Integer("height", c.height);
    if (c.width < 1 || c.width > 8192) r.Fail("width", "must be 1 to 8192 pixels");
    if (c.height < 1 || c.height > 8192) r.Fail("height", "must be 1 to 8192 pixels");
    c.fps = r.Number("fps", c.fps);
    if (!(c.fps > 0 && c.fps <= 1000)) r.Fail("fps", "must be > 0 and <= 1000 Hz");
    c.exposure_s = r.Number("exposure", c.exposure_s);
    if (!(c.exposure_s >= 0 && c.exposure_s < 1 / c.fps)) r.Fail("exposure", "must be >= 0 s and shorter than a frame");
    c.latency_s = r.Number("latency", c.latency_s);
    if (!(c.latency_s >= 0 && c.latency_s <= 1)) r.Fail("latency", "must be 0 to 1 s");
    c.distortion = r.Numbers("distortion", {});
    if (!c.distortion.empty() && c.distortion.size() != 4) r.Fail("distortion", "expected 4 numbers: k1, k2, p1, p2");
    c.noise = r.Number("noise", c.noise);
    if (!(c.noise >= 0 && c.noise <= 64)) r.Fail("noise", "must be 0 to 64 grey levels");
    c.encoding = r.String("encoding", c.encoding);
    if (c.encoding != "jpeg" && c.encoding != "raw") r.Fail("encoding", "must be jpeg or raw");
    c.jpeg_quality = r.Integer("jpeg_quality", c.jpeg_quality);
    if (c.jpeg_quality < 1 || c.jpeg_quality > 100) r.Fail("jpeg_quality", "must be 1 to 100");
    c.profile = r.String("profile", c.profile);
    if (c.profile != "fast" && c.profile != "quality") r.Fail("profile", "must be fast or quality");
  } else if (device.kind == "feet" || device.kind == "imu") {
    device.sensors.sensors = r.Strings("sensors", {});
    if (device.sensors.sensors.empty()) r.Fail("sensors", "needs at least one MJCF sensor");
    device.sensors.noise = r.Number("noise", 0.0);
    if (!(device.sensors.noise >= 0)) r.Fail("noise", "must be >= 0");
    if (device.kind == "feet") {
      SensorDeviceConfig& f = device.sensors;
      f.pads = r.Strings("pads", {});
      if (!f.pads.empty() && f.pads.size() != f.sensors.size()) {
        r.Fail("pads", "needs one site per sensor (" + std::to_string(f.sensors.size()) + ")");
      }
      f.weight_of = r.String("weight_of", "");
      f.contact_threshold = r.Number("contact_threshold", f.contact_threshold);
      if (!(f.contact_threshold >= 0)) r.Fail("contact_threshold", "must be >= 0 N");
    }
  } else if (device.kind == "base") {
    BaseDeviceConfig& b = device.base;
    b.joints = r.Strings("joints", {});
    if (b.joints.size() != 3) r.Fail("joints", "a base needs 3 joints: x, y (slide) and yaw (hinge)");
    b.actuators = r.Strings("actuators", b.joints);
    if (b.actuators.size() != 3) r.Fail("actuators", "needs one velocity actuator per joint (3)");
    b.max_velocity = r.Numbers("max_velocity", b.max_velocity);
    b.max_acceleration = r.Numbers("max_acceleration", b.max_acceleration);
    for (const char* key : {"max_velocity", "max_acceleration"}) {
      const auto& v = std::string(key) == "max_velocity" ? b.max_velocity : b.max_acceleration;
      if (v.size() != 3 || !(v[0] > 0 && v[1] > 0 && v[2] > 0)) r.Fail(key, "expected 3 numbers > 0 (x, y, yaw)");
    }
    MapReader odometry = r.Map("odometry");
    b.odometry_drift = odometry.Bool("drift", b.odometry_drift);
    b.drift_scale = odometry.Number("scale_std", b.drift_scale);
    b.drift_yaw_rate = odometry.Number("yaw_rate_std", b.drift_yaw_rate);
    if (!(b.drift_scale >= 0 && b.drift_scale < 0.5)) odometry.Fail("scale_std", "must be 0 to 0.5");
    if (!(b.drift_yaw_rate >= 0)) odometry.Fail("yaw_rate_std", "must be >= 0 rad/s");
    odometry.Finish();
    b.watchdog_periods = r.Integer("watchdog_periods", b.watchdog_periods);
    if (b.watchdog_periods < 0) r.Fail("watchdog_periods", "must be >= 0 (0: off)");
    b.owner_timeout_s = r.Number("owner_timeout", b.owner_timeout_s);
    if (!(b.owner_timeout_s > 0)) r.Fail("owner_timeout", "must be > 0 s");
  } else if (device.kind == "gripper") {
    GripperDeviceConfig& g = device.gripper;
    g.servo = r.String("servo", g.servo);
    g.force_actuator = r.String("force_actuator", g.force_actuator);
    g.touch = r.Strings("touch", g.touch);
    if (g.touch.empty()) r.Fail("touch", "needs at least one pad touch sensor");
    g.max_speed = r.Number("max_speed", g.max_speed);
    if (!(g.max_speed > 0)) r.Fail("max_speed", "must be > 0 m/s");
    g.grasp_force = r.Number("grasp_force", g.grasp_force);
    if (!(g.grasp_force > 0)) r.Fail("grasp_force", "must be > 0 N");
    g.watchdog_periods = r.Integer("watchdog_periods", g.watchdog_periods);
    if (g.watchdog_periods < 0) r.Fail("watchdog_periods", "must be >= 0 (0: off)");
    g.owner_timeout_s = r.Number("owner_timeout", g.owner_timeout_s);
    if (!(g.owner_timeout_s > 0)) r.Fail("owner_timeout", "must be > 0 s");
  } else if (device.kind == "pose") {
    device.pose.site = r.String("site");
    device.pose.relative_to = r.String("relative_to", device.pose.relative_to);
    device.pose.target = r.String("target", "");
  } else if (device.kind == "gaze") {
    GazeDeviceConfig& g = device.gaze;
    g.camera = r.String("camera");
    g.target = r.String("target");
    g.width = r.Integer("width", g.width);
    g.height = r.Integer("height", g.height);
    if (g.width < 1 || g.width > 8192) r.Fail("width", "must be 1 to 8192 pixels");
    if (g.height < 1 || g.height > 8192) r.Fail("height", "must be 1 to 8192 pixels");
  } else if (device.kind == "point") {
    PointDeviceConfig& p = device.point;
    p.arm = r.String("arm");
    p.site = r.String("site", p.site);
    p.base_body = r.String("base_body", p.base_body);
    MapReader gains = r.Map("gains");
    p.k_position = gains.Number("position", p.k_position);
    p.k_orientation = gains.Number("orientation", p.k_orientation);
    p.k_null = gains.Number("null_space", p.k_null);
    p.damping = gains.Number("damping", p.damping);
    if (!(p.k_position > 0 && p.k_orientation >= 0 && p.k_null >= 0 && p.damping >= 0)) {
      gains.Fail("position", "position must be > 0, the other gains >= 0");
    }
    gains.Finish();
    p.max_speed = r.Number("max_speed", p.max_speed);
    if (!(p.max_speed > 0)) r.Fail("max_speed", "must be > 0 m/s");
    MapReader box = r.Map("workspace");
    p.workspace_min = box.Numbers("min", p.workspace_min);
    p.workspace_max = box.Numbers("max", p.workspace_max);
    for (int i = 0; i < 3 && p.workspace_min.size() == 3 && p.workspace_max.size() == 3; ++i) {
      if (!(p.workspace_min[i] < p.workspace_max[i])) box.Fail("max", "must be > min in x, y and z");
    }
    if (p.workspace_min.size() != 3 || p.workspace_max.size() != 3) box.Fail("min", "min and max need 3 numbers (x, y, z), m, world frame");
    box.Finish();
    p.watchdog_periods = r.Integer("watchdog_periods", p.watchdog_periods);
    if (p.watchdog_periods < 0) r.Fail("watchdog_periods", "must be >= 0 (0: off)");
    p.owner_timeout_s = r.Number("owner_timeout", p.owner_timeout_s);
    if (!(p.owner_timeout_s > 0)) r.Fail("owner_timeout", "must be > 0 s");
  } else if (device.kind == "yoyo") {
    YoyoDeviceConfig& y = device.yoyo;
    y.slide = r.String("slide", y.slide);
    y.spin = r.String("spin", y.spin);
    y.centre = r.String("centre", y.centre);
    y.tension = r.Strings("tension", y.tension);
    if (y.tension.empty()) r.Fail("tension", "needs at least one tendonlimitfrc sensor");
    y.rate_hz = r.Number("rate", y.rate_hz);
    if (!(y.rate_hz >= 0)) r.Fail("rate", "must be >= 0 Hz (0: every control period)");
    y.noise = r.Number("noise", y.noise);
    if (!(y.noise >= 0)) r.Fail("noise", "must be >= 0 m");
  } else if (device.kind != "sim") {
    r.Fail("kind", "unknown device kind '" + device.kind + "' (known: arm, wrench, sim, camera, base, gripper, feet, imu, gaze, pose, point, yoyo)");
  }
  r.Finish();
  return device;
}

ImageOutputConfig ReadImageOutput(const std::string& file, const YAML::Node& node, const std::string& path) {
  MapReader r(file, node, path);
  ImageOutputConfig o;
  o.where = Where(file, node);
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
  o.video = r.String("video", o.video);
  if (!o.video.empty() && (o.video.find('/') != std::string::npos || o.video.size() < 5 ||
                           o.video.compare(o.video.size() - 4, 4, ".mp4") != 0)) {
    r.Fail("video", "must be a file name ending in .mp4, written in the output folder");
  }
  o.profile = r.String("profile", o.profile);
  if (o.profile != "fast" && o.profile != "quality") r.Fail("profile", "must be fast or quality");
  if (!o.png && !o.depth && !o.segmentation && o.video.empty()) r.Fail("png", "nothing to write: png, depth, segmentation and video are all off");
  r.Finish();
  return o;
}

ControllerConfig ReadController(MapReader r) {
  ControllerConfig c;
  c.where = Where(r.file(), r.node());
  c.type = r.String("type", c.type);
  if (c.type == "none") {
    r.Finish();
    return c;
  }
  if (c.type == "external") {
    c.command = r.Strings("command", {});
    if (c.command.empty() || c.command[0].empty()) r.Fail("command", "expected [PROGRAM, ARGUMENT, ...]");
    r.Finish();
    return c;
  }
  c.arm = r.String("arm");
  c.timing = r.String("timing", c.timing);
  if (c.timing != "quintic" && c.timing != "trapezoidal") r.Fail("timing", "must be quintic or trapezoidal");
  c.start_s = r.Number("start", c.start_s);
  if (c.start_s < 0) r.Fail("start", "must be >= 0 s");
  c.base_body = r.String("base_body", c.base_body);
  c.tip_site = r.String("tip_site");
  const YAML::Node waypoints = r.Sequence("waypoints");
  if (waypoints.size() == 0) r.Fail("waypoints", "needs at least one waypoint");
  if (c.type == "task_space") {
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
  } else if (c.type == "joint_pd") {
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
    r.Fail("type", "unknown controller type '" + c.type + "' (known: none, joint_pd, task_space, external)");
  }
  r.Finish();
  return c;
}

CheckConfig ReadCheck(const std::string& file, const YAML::Node& node, const std::string& path) {
  MapReader r(file, node, path);
  CheckConfig c;
  c.where = Where(file, node);
  c.name = r.String("name");
  c.signal = r.String("signal");
  c.reduce = r.String("reduce", c.reduce);
  static const char* kReductions[] = {"max", "min", "mean", "rms", "final", "max_abs"};
  bool known = false;
  for (const char* k : kReductions) known = known || c.reduce == k;
  if (!known) r.Fail("reduce", "unknown reduction '" + c.reduce + "' (known: max, min, mean, rms, final, max_abs)");
  c.min = r.Number("min", c.min);
  c.max = r.Number("max", c.max);
  if (!r.Has("min") && !r.Has("max")) r.Fail("max", "a check needs a bound: min, max or both");
  c.from_s = r.Number("from", c.from_s);
  c.to_s = r.Number("to", c.to_s);
  if (c.to_s < c.from_s) r.Fail("to", "must be >= from");
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

Scenario LoadScenario(const std::string& path) {
  const YAML::Node root = LoadYamlFile(path);
  if (!root.IsMap()) throw InputError(path + ": a scenario must be a YAML mapping");
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
  s.duration_s = r.Number("duration");
  if (!(s.duration_s > 0)) r.Fail("duration", "must be > 0 s");
  s.control_period_s = r.Number("control_period", s.control_period_s);
  if (!(s.control_period_s > 0)) r.Fail("control_period", "must be > 0 s");
  const double seed = r.Number("seed", 1);
  if (seed < 0 || seed != std::floor(seed) || seed > 9007199254740992.0) r.Fail("seed", "must be a non-negative integer");
  s.seed = static_cast<std::uint64_t>(seed);
  s.clock = r.String("clock", s.clock);
  if (s.clock != "fast" && s.clock != "lockstep" && s.clock != "realtime") {
    r.Fail("clock", "unknown clock '" + s.clock + "' (known: fast, lockstep, realtime)");
  }
  MapReader lockstep = r.Map("lockstep");
  s.lockstep.timeout_s = lockstep.Number("timeout", s.lockstep.timeout_s);
  s.lockstep.start_timeout_s = lockstep.Number("start_timeout", s.lockstep.start_timeout_s);
  s.lockstep.on_timeout = lockstep.String("on_timeout", s.lockstep.on_timeout);
  s.lockstep.release_after = lockstep.Integer("release_after", s.lockstep.release_after);
  if (!(s.lockstep.timeout_s > 0)) lockstep.Fail("timeout", "must be > 0 s");
  if (!(s.lockstep.start_timeout_s > 0)) lockstep.Fail("start_timeout", "must be > 0 s");
  if (s.lockstep.on_timeout != "hold" && s.lockstep.on_timeout != "fail") {
    lockstep.Fail("on_timeout", "must be hold or fail");
  }
  if (s.lockstep.release_after < 1) lockstep.Fail("release_after", "must be >= 1");
  lockstep.Finish();
  MapReader realtime = r.Map("realtime");
  s.realtime.factor = realtime.Number("factor", s.realtime.factor);
  if (!(s.realtime.factor > 0 && s.realtime.factor <= 1000)) realtime.Fail("factor", "must be in (0, 1000]");
  realtime.Finish();
  s.keyframe = r.String("keyframe", "");
  if (r.Has("keyframe")) s.keyframe_where = Where(path, root["keyframe"]);
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
  s.outputs.log = outputs.Bool("log", s.outputs.log);
  const YAML::Node images = outputs.Sequence("images");
  for (std::size_t i = 0; i < images.size(); ++i) {
    s.outputs.images.push_back(ReadImageOutput(path, images[i], "outputs.images[" + std::to_string(i) + "]"));
  }
  const YAML::Node plots = outputs.Sequence("plots");
  for (std::size_t i = 0; i < plots.size(); ++i) {
    MapReader pr(path, plots[i], "outputs.plots[" + std::to_string(i) + "]");
    PlotConfig plot;
    plot.where = Where(path, plots[i]);
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
  outputs.Finish();
  const YAML::Node checks = r.Sequence("checks");
  for (std::size_t i = 0; i < checks.size(); ++i) {
    s.checks.push_back(ReadCheck(path, checks[i], "checks[" + std::to_string(i) + "]"));
  }
  r.Finish();
  return s;
}

}  // namespace vlab::lab
