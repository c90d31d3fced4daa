// Scenario files: what to simulate, for how long, with which devices,
// controller, outputs and checks.
//
// A scenario is a YAML document (see docs/scenarios.md for every key). Loading
// validates types and rejects unknown keys; binding names to MuJoCo elements
// happens later, when the lab is created from the scenario and its scene.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/core_clock.h"

namespace vlab::lab {

/// Joint servo of a simulated arm: the drive electronics between a command
/// and the motor torque (position and velocity modes).
struct ServoConfig {
  double bandwidth_hz = 10.0;  ///< closed-loop natural frequency of each joint servo
  double damping_ratio = 1.0;  ///< its damping ratio
};

struct ArmDeviceConfig {
  std::vector<std::string> joints;     ///< MJCF joint names, in device order
  std::vector<std::string> actuators;  ///< MJCF motor actuators (torque), default: joint names
  std::vector<double> initial;         ///< initial joint positions, rad (default: qpos0)
  std::vector<double> max_velocity;    ///< |qd| limits of velocity commands, rad/s (empty: none)
  ServoConfig servo;
  int watchdog_periods = 3;            ///< hold after this many periods without a command (0: off)
  double owner_timeout_s = 1.0;        ///< a silent owner gives the command input up after this
  bool log_following_error = false;    ///< log NAME.following_error: max |q_ref - q| of the servo, rad
};

struct WrenchDeviceConfig {
  std::string site;           ///< sensor site (documentation; frames come from the sensors)
  std::string force_sensor;   ///< MJCF force sensor at the site
  std::string torque_sensor;  ///< MJCF torque sensor at the site
  std::string model = "67M25A";
  std::vector<double> full_scale;  ///< 6 values, N and N·m; empty: the model's defaults
  int filter = 4;
  bool noise = true;
  bool bias = true;
  bool quantization = true;
};

/// A simulated webcam: an MJCF camera rendered offscreen at the camera's own
/// frame rate, through a lens and sensor model (sensors/sensor_camera.h).
struct CameraDeviceConfig {
  std::string camera;            ///< MJCF camera name
  int width = 640;               ///< pixels (at most the scene's offscreen buffer)
  int height = 480;
  double fps = 30.0;             ///< frame rate, independent of the control rate
  double exposure_s = 0.0;       ///< exposure time (0: instantaneous); the frame is stamped at its middle
  double latency_s = 0.03;       ///< from the exposure stamp to delivery
  std::vector<double> distortion;  ///< k1, k2, p1, p2 (Brown-Conrady); empty: none
  double noise = 0.0;            ///< pixel noise standard deviation, 8-bit grey levels
  std::string encoding = "jpeg";  ///< jpeg | raw (frames on the wire)
  int jpeg_quality = 90;         ///< 1-100
  std::string profile = "fast";  ///< fast | quality
};

/// A device that reads MJCF sensors as they are (kinds feet and imu).
struct SensorDeviceConfig {
  std::vector<std::string> sensors;  ///< MJCF sensors, in payload order
  double noise = 0.0;                ///< Gaussian noise std added to every value (sensor units; 0: none)
  // feet only: log columns of the whole support (not on the wire)
  std::vector<std::string> pads;     ///< one MJCF site per sensor: where it presses (empty: no CoP columns)
  std::string weight_of;             ///< body whose subtree weight the sum is compared with ("": none)
  double contact_threshold = 0.0;    ///< N: a pad reading more than this is in contact
};

/// A parallel gripper (kind gripper): an opening servo and a grip-force drive
/// on one tendon, and a touch sensor per pad (mjcf/gripper's names by default).
struct GripperDeviceConfig {
  std::string servo = "gripper";              ///< position actuator of the opening tendon (ctrl: opening, m)
  std::string force_actuator = "gripper_force";  ///< force actuator of the same tendon (ctrl: N, negative closes)
  std::vector<std::string> touch = {"gripper_touch_left", "gripper_touch_right"};  ///< pad touch sensors
  double max_speed = 0.083;       ///< m/s: opening set-points ramp at this speed (PG 70: 83 mm/s)
  double grasp_force = 2.0;       ///< N on every pad (and the jaws at rest) for "grasped"
  int watchdog_periods = 3;       ///< hold after this many periods without a command (0: off)
  double owner_timeout_s = 1.0;
};

/// A tracked frame (kind pose), like a motion-capture system's rigid body:
/// an MJCF site's pose in the frame of a body, and its distance to a target.
struct PoseDeviceConfig {
  std::string site;                  ///< the tracked site
  std::string relative_to = "world";  ///< the body whose frame the pose is given in
  std::string target;                ///< a site whose distance is logged ("": none)
};

/// A holonomic mobile base (kind base): planar x, y, yaw joints driven by
/// velocity actuators, commanded in the base or the world frame.
struct BaseDeviceConfig {
  std::vector<std::string> joints;     ///< world x, world y (slide) and yaw (hinge) joints
  std::vector<std::string> actuators;  ///< velocity actuators of those joints (default: the joint names)
  std::vector<double> max_velocity = {1.0, 1.0, 2.0};      ///< vx, vy (m/s), wz (rad/s)
  std::vector<double> max_acceleration = {1.0, 1.0, 2.0};  ///< m/s^2, m/s^2, rad/s^2
  bool odometry_drift = false;  ///< seeded odometry errors (scale and yaw-rate bias)
  double drift_scale = 0.01;    ///< std of the odometry's scale errors (fraction)
  double drift_yaw_rate = 0.002;  ///< std of the odometry's yaw-rate bias, rad/s
  int watchdog_periods = 3;     ///< stop after this many periods without a command (0: off)
  double owner_timeout_s = 1.0;
};

/// A ground-truth gaze probe (kind gaze): where a target lies relative to an
/// MJCF camera's optical axis and in its pinhole image (no lens distortion).
struct GazeDeviceConfig {
  std::string camera;  ///< MJCF camera name
  std::string target;  ///< MJCF site or body name (a site wins when both exist)
  int width = 640;     ///< image size for the intrinsics, pixels (fx = fy = (height/2) / tan(fovy/2))
  int height = 480;
};

/// A task-space interface to an arm's tool (kind point), like a robot
/// controller's Cartesian position input: a commanded point [x, y, z] that the
/// device turns into joint velocity commands for its arm every control period
/// (src/lab/lab_point_device.cc).
struct PointDeviceConfig {
  std::string arm;                  ///< the arm device it drives (a device of the same scenario)
  std::string site = "tool";        ///< the point: an MJCF site at the end of the arm's chain
  std::string base_body = "world";  ///< the chain starts below this body
  double k_position = 20.0;         ///< position gain, 1/s
  double k_orientation = 20.0;      ///< orientation gain (the start orientation is kept), 1/s
  double k_null = 1.0;              ///< null-space gain toward the start posture, 1/s
  double damping = 1e-3;            ///< DLS damping of the pseudo-inverse
  double max_speed = 1.0;           ///< m/s: the set-point ramps toward each command at most this fast
  /// Workspace box, world frame, m: commands outside [min, max] are refused (limits).
  std::vector<double> workspace_min = {-std::numeric_limits<double>::infinity(),
                                       -std::numeric_limits<double>::infinity(),
                                       -std::numeric_limits<double>::infinity()};
  std::vector<double> workspace_max = {std::numeric_limits<double>::infinity(),
                                       std::numeric_limits<double>::infinity(),
                                       std::numeric_limits<double>::infinity()};
  int watchdog_periods = 3;         ///< hold after this many periods without a command (0: off)
  double owner_timeout_s = 1.0;
};

/// The yo-yo of mjcf/yoyo measured (kind yoyo): its centre, vertical speed,
/// string tension and spin, optionally at a camera's rate and with noise
/// (src/lab/lab_yoyo_device.cc). Defaults: the model's names.
struct YoyoDeviceConfig {
  std::string slide = "yoyo_drop";   ///< slide joint d: the centre's distance below the hand, m
  std::string spin = "yoyo_spin";    ///< hinge joint of the spin
  std::string centre = "yoyo_centre";  ///< site at the yo-yo's centre
  std::vector<std::string> tension = {"yoyo_string_plus_force", "yoyo_string_minus_force"};  ///< tendonlimitfrc sensors, summed
  double rate_hz = 0.0;  ///< sample-and-hold rate of the measurement, Hz (0: every control period)
  double noise = 0.0;    ///< Gaussian noise std on the position x, y, z, m (seeded)
};

struct DeviceConfig {
  std::string name;
  std::string kind;  ///< arm, wrench, sim, camera, base, feet or imu
  std::string where;  ///< "FILE:LINE" for messages about binding
  int port = 0;       ///< UDP port under `vlab serve` (0: not served)
  ArmDeviceConfig arm;
  WrenchDeviceConfig wrench;
  CameraDeviceConfig camera;
  SensorDeviceConfig sensors;
  BaseDeviceConfig base;
  GripperDeviceConfig gripper;
  PoseDeviceConfig pose;
  GazeDeviceConfig gaze;
  PointDeviceConfig point;
  YoyoDeviceConfig yoyo;
};

struct CartesianWaypoint {
  Eigen::Vector3d position_W = Eigen::Vector3d::Zero();  ///< m
  Eigen::Quaterniond orientation_W = Eigen::Quaterniond::Identity();
  double duration_s = 1.0;  ///< time to reach this waypoint from the previous one
};

struct JointWaypoint {
  std::vector<double> q;  ///< rad
  double duration_s = 1.0;
};

struct ControllerConfig {
  std::string type = "none";  ///< none | joint_pd | task_space | external
  std::string arm;            ///< arm device it commands
  std::string where;
  std::string base_body = "world";  ///< chain from this body ...
  std::string tip_site;             ///< ... to this site
  // task_space
  double k_position = 20.0;     ///< 1/s
  double k_orientation = 20.0;  ///< 1/s
  double k_null = 1.0;          ///< 1/s
  double damping = 1e-3;        ///< DLS damping of the pseudo-inverse
  std::vector<CartesianWaypoint> cartesian;
  // joint_pd
  std::vector<double> kp, kd;  ///< N·m/rad, N·m·s/rad (empty: from bandwidth_hz)
  double pd_bandwidth_hz = 5.0;  ///< default gains: kp = H_ii w², kd = 2 H_ii w at the start pose
  std::vector<JointWaypoint> joint;
  // external: a program `vlab run` starts, with {DEVICE}, {bin}, {scenario_dir}
  // and {duration} expanded (lab_external.h); `vlab serve` does not start it
  std::vector<std::string> command;
  // joint_pd and task_space
  std::string timing = "quintic";  ///< quintic | trapezoidal
  double start_s = 0.0;            ///< hold until this time, then follow the path
};

/// A pass/fail rule over one logged signal.
struct CheckConfig {
  std::string name;
  std::string signal;          ///< a log column name
  std::string reduce = "max";  ///< max | min | mean | rms | final | max_abs
  double min = -std::numeric_limits<double>::infinity();  ///< value must be >= min
  double max = std::numeric_limits<double>::infinity();   ///< value must be <= max
  double from_s = 0.0;
  double to_s = std::numeric_limits<double>::infinity();
  std::string where;
};

/// Images of one MJCF camera written into the output folder during a run.
struct ImageOutputConfig {
  std::string camera;            ///< MJCF camera name
  double every_s = 0.1;          ///< one frame every this many simulated seconds (from t = 0)
  int width = 640;               ///< pixels (at most the scene's offscreen buffer)
  int height = 480;
  bool png = true;               ///< CAMERA/rgb_NNNNNN.png
  bool depth = false;            ///< CAMERA/depth_NNNNNN.png: 16-bit, millimetres
  bool segmentation = false;     ///< CAMERA/seg_NNNNNN.png: 16-bit, geom id + 1 (0: background)
  std::string video;             ///< MP4 file name in the output folder ("": none)
  std::string profile = "quality";  ///< fast | quality
  std::string where;
};

/// A line plot (PNG) drawn from a CSV file of the output folder after the run.
struct PlotConfig {
  std::string file;              ///< PNG file name in the output folder
  std::string csv = "log.csv";   ///< CSV in the output folder (log.csv, or a file an external controller wrote)
  std::string x = "time";        ///< column of the horizontal axis
  std::vector<std::string> y;    ///< columns drawn against it, one line each
  std::string title;
  std::string ylabel;
  std::string where;
};

struct OutputsConfig {
  bool log = true;  ///< write log.csv
  std::vector<ImageOutputConfig> images;
  std::vector<PlotConfig> plots;
};

struct Scenario {
  std::string file;        ///< path as given
  std::string name;        ///< output folder name (default: file stem)
  std::string description;
  std::string scene;       ///< MJCF path, resolved relative to the scenario file
  double duration_s = 1.0;
  double control_period_s = 0.002;
  std::uint64_t seed = 1;
  ClockMode clock = ClockMode::kFast;
  LockstepConfig lockstep;
  RealtimeConfig realtime;
  std::vector<std::string> allow_warnings;
  std::string keyframe;        ///< scene keyframe every reset starts from ("": the model's qpos0)
  std::string keyframe_where;  ///< "FILE:LINE" of the keyframe key, for messages
  std::vector<DeviceConfig> devices;
  ControllerConfig controller;
  OutputsConfig outputs;
  std::vector<CheckConfig> checks;
};

/// Resolves a scenario argument: PATH, or PATH.yaml when PATH does not exist.
std::string ResolveScenarioPath(const std::string& arg);

/// The scenario's clock, run in `mode`.
ClockConfig ScenarioClock(const Scenario& scenario, ClockMode mode);

/// Loads and validates a scenario file. Throws InputError naming the file, the
/// line and the key.
Scenario LoadScenario(const std::string& path);

}  // namespace vlab::lab
