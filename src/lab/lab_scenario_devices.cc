#include "lab/lab_scenario_devices.h"

#include "lab/lab_yaml.h"

namespace vlab::lab {

DeviceConfig ReadDevice(const std::string& file, const YAML::Node& node, const std::string& path) {
  MapReader r(file, node, path);
  DeviceConfig device;
  device.where = YamlWhere(file, node);
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

}  // namespace vlab::lab
