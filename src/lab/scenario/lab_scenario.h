// Scenario files: what to simulate, for how long, with which devices,
// controller, outputs and checks.
//
// A scenario is a YAML document (see docs/scenarios.md for every key). Loading
// validates types and rejects unknown keys; binding names to MuJoCo elements
// happens later, when the lab is created from the scenario and its scene.
#pragma once

#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "control/time_scaling.h"
#include "core/core_clock.h"
#include "lab/devices/device_config.h"
#include "lab/judge/lab_compare.h"
#include "lab/scenario/lab_randomize.h"
#include "render/renderer.h"

namespace vlab::lab {

/// The built-in controllers (the `controller.type` key).
enum class ControllerType { kNone, kJointPd, kTaskSpace, kExternal, kTask };
/// How a check reduces its signal to one value (the `reduce` key).
/// kMinOfWindowMax: the window [from, to] cut into consecutive windows of `window` s,
/// the maximum in each, then the smallest of those maxima (e.g. every swing reaches a
/// height); kMaxOfWindowMin likewise with minima and the largest of them. kRange: the
/// largest minus the smallest value in [from, to] (how far a held quantity wanders).
enum class Reduce { kMax, kMin, kMean, kRms, kFinal, kMaxAbs, kMinOfWindowMax, kMaxOfWindowMin, kRange };
/// "max", "min", "mean", "rms", "final", "max_abs", "min_of_window_max",
/// "max_of_window_min", "range"; and back (false for anything else).
const char* ReduceName(Reduce reduce);
bool ReduceFromName(const std::string& name, Reduce* reduce);
/// "none", "joint_pd", "task_space", "external", "task".
const char* ControllerTypeName(ControllerType type);

struct CartesianWaypoint {
  Eigen::Vector3d position_W = Eigen::Vector3d::Zero();  ///< m
  Eigen::Quaterniond orientation_W = Eigen::Quaterniond::Identity();
  double duration_s = 1.0;  ///< time to reach this waypoint from the previous one
};

struct JointWaypoint {
  std::vector<double> q;  ///< rad
  double duration_s = 1.0;
};

/// One robot program of a `task` controller (src/task/task_runtime.h).
struct TaskProgramEntry {
  std::string robot;                          ///< arm device it commands ("": none)
  std::string script;                         ///< .lua file, resolved relative to the scenario file
  std::string base_body = "world";            ///< chain from this body ...
  std::string tip_site;                       ///< ... to this site
  std::string wrench;                         ///< default wrench of guarded moves ("": the only one)
  std::string where;                          ///< "FILE:LINE" of the entry
  std::map<std::string, std::string> params;  ///< PARAMS of the script: NAME -> text as given
};

struct ControllerConfig {
  ControllerType type = ControllerType::kNone;
  std::string arm;  ///< arm device it commands
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
  std::vector<double> kp, kd;    ///< N·m/rad, N·m·s/rad (empty: from bandwidth_hz)
  double pd_bandwidth_hz = 5.0;  ///< default gains: kp = H_ii w², kd = 2 H_ii w at the start pose
  std::vector<JointWaypoint> joint;
  // external: a program `vlab run` starts, with {DEVICE}, {bin}, {scenario_dir}
  // and {duration} expanded (lab_external.h); `vlab serve` does not start it
  std::vector<std::string> command;
  /// SCHED_FIFO priority the program (and what it starts) runs at, when the
  /// user may have it; 0: normal priority
  int realtime_priority = 0;
  /// The run ends when the program exits with status 0 (lockstep: at the first period it
  /// left unanswered); false: its devices hold until the run's duration
  bool ends_run = false;
  // task: robot programs in the task language, resumed in this order each period
  std::vector<TaskProgramEntry> programs;
  long instruction_budget = 10'000'000;  ///< Lua VM instructions per resume
  /// markers devices the programs read (markers("NAME")): NAME -> "HOST:PORT"
  /// of a vision program running beside the lab
  std::map<std::string, std::string> markers;
  // joint_pd and task_space
  control::TimeScalingType timing = control::TimeScalingType::kQuintic;  ///< quintic | trapezoidal
  double start_s = 0.0;                                                  ///< hold until this time, then follow the path
};

/// A pass/fail rule over one logged signal.
struct CheckConfig {
  std::string name;
  std::string signal;  ///< a log column name
  Reduce reduce = Reduce::kMax;
  double min = -std::numeric_limits<double>::infinity();  ///< value must be >= min
  double max = std::numeric_limits<double>::infinity();   ///< value must be <= max
  double from_s = 0.0;
  double to_s = std::numeric_limits<double>::infinity();
  double window_s = 0.0;  ///< sub-window length, s (> 0 only for the *_of_window_* reductions)
  std::string where;
  /// A golden check (`golden:` key): the run's log.csv compared with this golden folder
  /// or log CSV (resolved) within `tolerances` (then a golden folder's own), over
  /// [from, to] (lab_compare.h). Its value is the worst divergence as a multiple of its
  /// tolerance (0: all within; inf: a missing column), bound max 1. "" for a signal check.
  std::string golden;
  std::vector<ColumnTolerance> tolerances;
};

/// Images of one MJCF camera written into the output folder during a run.
struct ImageOutputConfig {
  std::string camera;    ///< MJCF camera name
  double every_s = 0.1;  ///< one frame every this many simulated seconds (from t = 0)
  int width = 640;       ///< pixels (at most the scene's offscreen buffer)
  int height = 480;
  bool png = true;            ///< CAMERA/rgb_NNNNNN.png
  bool depth = false;         ///< CAMERA/depth_NNNNNN.png: 16-bit, millimetres
  bool segmentation = false;  ///< CAMERA/seg_NNNNNN.png: 16-bit, geom id + 1 (0: background)
  std::string video;          ///< MP4 file name in the output folder ("": none)
  render::Profile profile = render::Profile::kQuality;
  bool last = false;  ///< also a frame of the run's last state, when none fell on it
  std::string where;
};

/// A line plot (PNG) drawn from a CSV file of the output folder after the run.
struct PlotConfig {
  std::string file;             ///< PNG file name in the output folder
  std::string csv = "log.csv";  ///< CSV in the output folder (log.csv, or a file an external controller wrote)
  std::string x = "time";       ///< column of the horizontal axis
  std::vector<std::string> y;   ///< columns drawn against it, one line each
  std::string title;
  std::string ylabel;
  std::string where;
};

struct OutputsConfig {
  bool log = true;  ///< write the log (false: `log: false`)
  /// Its formats, each once, in the order given: "csv" (log.csv), "mat"
  /// (log.mat), "hdf5" (log.h5); `log: true` is csv alone.
  std::vector<std::string> log_formats = {"csv"};
  std::vector<ImageOutputConfig> images;
  std::vector<PlotConfig> plots;
  bool poses = false;         ///< record poses.bin + scene.json (lab_poses.h)
  double poses_rate_hz = 30;  ///< their frames per second (0: every control period)
  std::string poses_where;    ///< "FILE:LINE" of outputs.poses, for messages
};

struct Scenario {
  std::string file;  ///< path as given
  std::string name;  ///< output folder name (default: file stem)
  std::string description;
  std::string scene;  ///< MJCF path, resolved relative to the scenario file
  double duration_s = 1.0;
  double control_period_s = 0.002;
  std::uint64_t seed = 1;
  ClockMode clock = ClockMode::kFast;
  LockstepConfig lockstep;
  RealtimeConfig realtime;
  std::vector<std::string> allow_warnings;
  std::string keyframe;        ///< scene keyframe every reset starts from ("": the model's qpos0)
  std::string keyframe_where;  ///< "FILE:LINE" of the keyframe key, for messages
  std::string scene_where;     ///< "FILE:LINE" of the scene key, for messages
  /// free bodies placed at random from the seed at every reset (empty bodies: none)
  RandomizeConfig randomize;
  std::vector<DeviceConfig> devices;
  ControllerConfig controller;
  OutputsConfig outputs;
  std::vector<CheckConfig> checks;
  /// `--set KEY=VALUE` overrides applied to the file, in order (as given)
  std::vector<std::pair<std::string, std::string>> overrides;
  /// the file's YAML after the overrides, re-emitted (a run's record, lab_run_record.h)
  std::string resolved_yaml;
};

/// Resolves a scenario argument: PATH, or PATH.yaml when PATH does not exist.
std::string ResolveScenarioPath(const std::string& arg);

/// The longest run a scenario or `--duration` may ask for, s (about 11.6 days).
inline constexpr double kMaxDuration_s = 1e6;
/// The longest control period, s.
inline constexpr double kMaxControlPeriod_s = 10.0;
/// True for a duration a run can simulate: finite, > 0 and at most kMaxDuration_s.
inline bool ValidDuration(double duration_s) { return duration_s > 0 && duration_s <= kMaxDuration_s; }

/// The scenario's clock, run in `mode`.
ClockConfig ScenarioClock(const Scenario& scenario, ClockMode mode);

/// Loads and validates a scenario file. Throws InputError naming the file, the
/// line and the key.
Scenario LoadScenario(const std::string& path);

/// Loads a scenario with `--set KEY=VALUE` overrides applied to the file first
/// (lab_overrides.h): the same typing and errors as the file's own keys; an
/// error on an overridden key names the --set too.
Scenario LoadScenario(const std::string& path, const std::vector<std::string>& sets);

}  // namespace vlab::lab
