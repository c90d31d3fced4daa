// An identification spec (vlab identify SPEC.yaml): which model parameters to fit, to which
// recorded logs, by which residual. docs/identify.md, "Identify", lists every key.
//
// The spec is read and checked on its own here (types, ranges, unknown keys); its names are
// bound to the scenario's model and to the logs' columns later (identify_problem.h). Every
// error is an InputError naming the file, line and key path ("id.yaml:12:
// parameters[1].upper: must be greater than lower (2)").
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace vlab::identify {

/// What a parameter changes.
enum class TargetKind {
  kBodyMass,           ///< body NAME mass: the body's mass, its inertia scaled with it (kg)
  kBodyCom,            ///< body NAME com_x|com_y|com_z: its centre of mass, body frame (m)
  kBodyInertia,        ///< body NAME inertia_x|inertia_y|inertia_z: a principal moment about it (kg·m²)
  kJointDamping,       ///< joint NAME damping (N·m·s/rad, N·s/m)
  kJointArmature,      ///< joint NAME armature (kg·m², kg)
  kJointFrictionLoss,  ///< joint NAME frictionloss (N·m, N)
  kColumnBias,         ///< column NAME bias: the sensor reads true + bias (the column's unit)
  kColumnGain,         ///< column NAME gain: the sensor reads gain · true (1)
  kColumnDelay,        ///< column NAME delay: the sensor reads the true value of this long ago (s)
  kServoBandwidth,     ///< servo DEVICE bandwidth: the arm's servo.bandwidth_hz (Hz)
  kServoDampingRatio,  ///< servo DEVICE damping_ratio: the arm's servo.damping_ratio (1)
  kPayloadMass,        ///< payload BODY mass: a point mass rigidly added to BODY (kg)
  kPayloadCom,         ///< payload BODY com_x|com_y|com_z: where it is, BODY's frame (m)
};

/// "body NAME mass", ...: the words of a target, for messages and outputs (`axis`: 0, 1, 2
/// for com_x, com_y, com_z).
std::string TargetText(TargetKind kind, const std::string& element, int axis);

/// The same for targets without an axis.
std::string TargetText(TargetKind kind, const std::string& element);

/// One parameter of the fit.
struct ParameterSpec {
  std::string name;  ///< unique, as written
  TargetKind kind = TargetKind::kBodyMass;
  std::string element;  ///< body or joint name, log column, or arm device
  int axis = 0;         ///< com_x, com_y, com_z (inertia_x, ...): 0, 1, 2
  bool has_nominal = false;
  double nominal = 0;  ///< the starting value (default: the model's; bias 0, gain 1)
  double lower = 0;    ///< bounds of the fitted value, lower < upper
  double upper = 0;
  bool frozen = false;  ///< kept at the nominal value
  std::string where;    ///< "FILE:LINE: parameters[i]" for messages
};

/// Log columns in the residual: a name, or a pattern with '*' (any characters); or a column
/// derived from others (`norm:`), named by `pattern`.
struct ColumnSpec {
  std::string pattern;
  double weight = 1;  ///< residual = weight · (model − measured): 1/σ of the column's noise
  /// A derived column: the Euclidean norm of these columns (each a name the replay predicts),
  /// or with `rate` of their change from the row before, per second. Phase-free: the norm of a
  /// vector turning at a steady rate, or of its rate when a constant part is added, does not
  /// depend on where it points (the PowerBall's rotating couple, docs/identify.md).
  std::vector<std::string> norm;
  bool rate = false;
  /// Rows only within these [from, to] spans of a log's time (s) enter the residual; none: all
  /// (a derived rate's norm is biased by the noise's where the signal is below it).
  std::vector<std::pair<double, double>> spans;
  std::string where;
};

/// Where the fit starts (`first_estimate:`).
enum class FirstEstimate {
  kLinear,   ///< the linear inverse-dynamics estimate (identify_linear.h) where it applies, else nominal
  kNominal,  ///< the parameters' nominal values
};

struct Spec {
  std::string file;                 ///< the spec as given
  std::string scenario;             ///< resolved relative to the spec file
  std::vector<std::string> sets;    ///< `set:` KEY=VALUE overrides of the scenario
  std::vector<std::string> logs;    ///< log.csv files (a run folder is its log.csv)
  std::vector<ColumnSpec> columns;  ///< at least one
  double window_s = 0.2;            ///< multiple-shooting window, s
  /// Windows only within these [from, to] spans of each log's time (s); none: the whole log.
  std::vector<std::pair<double, double>> spans;
  /// A counter device's speed column (`NAME.rpm`) that sets the start of the scene's joints
  /// outside the arms: their velocities in the scenario's initial state, scaled by the
  /// counter's speed at the window's start over its joint's initial speed (a body whose motion
  /// is one mode scaled by its speed: the PowerBall's rolling rotor). Empty: those joints start
  /// at rest in the initial state's positions.
  std::string start_speed;
  /// With start_speed: each window's replay first runs this long (s) from its start state with
  /// the first row's inputs held, so that the state the log lacks settles on the model's own
  /// dynamics; the rest of the scene's motion is then scaled back to the start speed.
  double run_in_s = 0;
  /// How the recorded inputs are replayed: "torque" (each joint's recorded torque) or
  /// "reference" (the arms' recorded commands through their servos).
  std::string input = "torque";
  /// input: reference with arms that sense their joints through encoders (the arm key
  /// `sensing`): false, the replayed servo reads the counts as the lab's does (the log to the
  /// bit, but the rollout is then a step function of the parameters); true (`servo_sensing:
  /// exact`), it reads the exact joint state, smooth in the parameters, the counts' rounding
  /// left as noise.
  bool servo_sensing_exact = false;
  std::vector<ParameterSpec> parameters;  ///< at least one, names unique
  int max_iterations = 50;                ///< Ceres iterations, 1..1000
  /// The Jacobian's central-difference step, relative to each parameter's scale (its nominal):
  /// small for smooth replays; larger where contacts make a replay rough at fine scales (the
  /// PowerBall's rolling tips: 1e-2), so that the difference measures the trend, not the grain.
  double jacobian_step = 1e-4;
  /// Rows on each side of a window's first row that its start state is smoothed over (a
  /// quadratic least-squares fit of each q and qd, evaluated at the row; 0: the row as
  /// recorded): the measurement noise of the start state, carried through the whole window,
  /// is cut about 3.5-fold at 10 (docs/identify.md).
  int start_smoothing = 10;
  /// Windows in contact are left out (`contacts: skip`, the default: contact forces are no
  /// fitted parameter, and a contact's stiffness turns noise in the start state into large
  /// residuals): a recorded state of the window in contact, or the nominal model's replay
  /// making contact. `keep`: every window is fitted.
  bool skip_contacts = true;
  FirstEstimate first_estimate = FirstEstimate::kLinear;
  /// A wrench column's rows within this long of a window's start are left out of the residual:
  /// the replay's JR3 filter starts settled on the model's load there, not in the state the
  /// load's history left it in. Negative (the default): the selected filter's settling time
  /// (its step response within 1e-3 of the step from then on).
  double wrench_settle_s = -1;
  std::string where_window, where_input, where_wrench_settle, where_start_speed;
};

/// Reads and checks a spec file. Throws InputError naming the file, line and key.
Spec LoadSpec(const std::string& path);

/// True when `name` matches `pattern` ('*': any run of characters).
bool MatchColumn(const std::string& pattern, const std::string& name);

}  // namespace vlab::identify
