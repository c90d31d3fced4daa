// An identification problem bound to its scenario's model and its logs: the parameters as
// model fields, the recorded inputs and measurements, and the multiple-shooting windows,
// each replayed by a rollout.
//
// A window is `rows` consecutive log rows after a first row. Its rollout starts from the
// recorded state of the first row (every arm joint's q and qd; the rest of the scene in the
// scenario's initial state), applies each later row's recorded inputs over the physics steps
// of that row's period, and predicts the fitted columns at each row. The inputs (spec
// `input`): `torque`, the recorded joint torques (a torque command is held over its period:
// the arm device's `NAME.tau.JOINT` of the row that ends it); `reference`, the arms' recorded
// commands (`NAME.cmd_mode`, `NAME.cmd.JOINT`) taken by each arm device's own servo
// (lab::SimArm, one per arm and workspace, bound to the workspace's model), which then acts
// at every physics step as in the lab (identify_servo.cc). The predicted columns: the arms'
// q and qd (and their torques under `reference`), and a wrench device's columns: the model's
// force/torque sensors fed, after every physics step, to the same JR3 model the device runs
// (its filter at its internal rate; no noise, bias or rounding), its filter settled on the
// model's load at the window's start and its first rows (the filter's settling time) left out
// of the residual; a counter device's speed (`NAME.rpm`): the turns of its joint over each
// gate, as the device counts them (its gates from time 0; no rounding), left out until the
// first gate that starts within the window has ended; a derived column (spec `norm:`): the
// norm of other predicted columns, or of their rates. Residual = weight · (predicted −
// measured).
//
// The scene's joints outside the arms start in the scenario's initial state: at rest, or with
// the spec's `start_speed`, at its velocities scaled by a counter's speed at the window's start
// (the counter's readings about it, fitted by a quadratic in time). Windows lie within the
// spec's `spans`.
//
// Threads: a Problem is immutable once made; Rollout may run on many threads at once, each
// with its own Workspace.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/core_mujoco.h"
#include "identify/identify_spec.h"
#include "lab/devices/device_arm.h"
#include "sensors/sensor_wrench.h"

namespace vlab::lab {
struct Scenario;
}
namespace vlab::scene {
struct CsvTable;
}

namespace vlab::identify {

/// A parameter bound to the model or a log column.
struct BoundParameter {
  ParameterSpec spec;
  int index = -1;                  ///< body id, dof address, or fitted column
  double nominal = 0;              ///< the starting value (spec's, else the model's; bias 0, gain 1)
  double scale = 1;                ///< the fit works on value / scale: |nominal|, or the larger |bound| when 0
  double mass0 = 0;                ///< body mass: the model's mass ...
  double inertia0[3] = {0, 0, 0};  ///< ... and principal inertia, scaled together
};

/// A body whose inertial the parameters change: its own mass and centre of mass, and a
/// payload (a point mass rigidly attached) combined with it.
struct BodyEdit {
  int body = -1;
  int mass = -1;                      ///< parameter index of `body NAME mass`, -1: none
  int com[3] = {-1, -1, -1};          ///< of `body NAME com_x|y|z`
  int inertia[3] = {-1, -1, -1};      ///< of `body NAME inertia_x|y|z`
  int payload_mass = -1;              ///< of `payload NAME mass`
  int payload_com[3] = {-1, -1, -1};  ///< of `payload NAME com_x|y|z` (none: 0)
  double mass0 = 0, ipos0[3] = {0, 0, 0}, inertia0[3] = {0, 0, 0}, iquat0[4] = {1, 0, 0, 0};  ///< the model's
};

/// Combines a body's inertial (mass, centre of mass `ipos`, principal inertia about it along
/// the axes `iquat`, MuJoCo's body_* fields) with a point mass `payload_mass` at `payload_com`
/// (the body's frame): the mass sum, the combined centre of mass, both inertias moved to it
/// (parallel axes) and re-diagonalised. A payload mass of 0 leaves the fields as they are.
void AddPointMass(double payload_mass, const double payload_com[3], double* mass, double ipos[3], double inertia[3],
                  double iquat[4]);

/// A wrench device's sensors and JR3 model (its own, without noise, bias and rounding).
struct WrenchSensor {
  std::string device;
  int force_adr = -1, torque_adr = -1;  ///< sensordata addresses
  std::shared_ptr<const sensors::WrenchSensorModel> model;
};

/// A counter device: the joint whose turns it counts over each gate.
struct CounterSensor {
  std::string device;
  int qpos = -1, dof = -1;
  double gate_s = 0;
};

/// A rollout's own model and data (one per thread).
struct Workspace {
  ModelPtr model;
  DataPtr data;
  std::vector<double> applied;                     ///< the parameter values `model` holds now
  int contacts = 0;                                ///< the most contacts at any step of the last rollout
  std::vector<double> trace;                       ///< delayed columns: value and rate at each row of the window
  std::vector<double> parts;                       ///< derived columns: their parts' values at each row
  std::vector<sensors::WrenchSensorState> wrench;  ///< one per wrench device
  /// input: reference: each arm device's servo, bound to `model` (its gains made for `applied`)
  std::vector<std::unique_ptr<lab::SimArm>> arms;
  bridge::ArmCommand command;  ///< scratch: a recorded command
};

class Problem {
 public:
  /// Loads the scenario (with the spec's `set:` overrides) and its scene, reads the logs,
  /// binds parameters and columns and cuts the windows. Throws InputError naming the spec
  /// entry, log file or column at fault. The windows' nominal replays made while cutting them
  /// (`skip_contacts`, `start_speed`) run on `threads` threads.
  static std::unique_ptr<Problem> Create(const Spec& spec, int threads = 1);

  const Spec& spec() const { return spec_; }
  const mjModel* model() const { return model_.get(); }
  /// The scenario's MJCF file (resolved), after the spec's `set:` overrides.
  const std::string& scene() const { return scene_; }
  const std::vector<BoundParameter>& parameters() const { return parameters_; }
  /// The fitted columns, in residual order within a row.
  const std::vector<std::string>& columns() const { return column_names_; }
  int window_count() const { return static_cast<int>(windows_.size()); }
  /// Residuals of window w (rows · columns) and where they start in the whole vector.
  int window_residuals(int w) const;
  int window_offset(int w) const;
  int residual_count() const { return residual_count_; }
  /// Log rows no window covers (the tail shorter than a window), summed over the logs.
  int rows_left_out() const { return rows_left_out_; }
  /// Windows left out because their nominal replay made contact (Spec::skip_contacts).
  int windows_in_contact() const { return windows_in_contact_; }
  /// Residuals held at 0, summed over the windows: a wrench column's rows within its filter's
  /// settling time of a window's start (their filter state is not known), a counter's rows
  /// before its first reading whose gate lies within the window.
  int residuals_left_out() const;
  /// Window states profiled out of the residuals, one degree of freedom each: with the spec's
  /// start_speed, each window's start speed.
  int window_nuisances() const;
  /// fn(w, workspace) for every window w, on `threads` threads, each with its own workspace
  /// (fn must write only what belongs to w); an exception fn throws is rethrown once all have
  /// ended, the lowest window's.
  void ForEachWindow(int threads, const std::function<void(int w, Workspace& ws)>& fn) const;
  /// Rows at a window's start whose wrench residuals are left out (Spec::wrench_settle_s).
  int wrench_settle_rows() const { return wrench_settle_rows_; }

  /// A workspace for Rollout: a copy of the model and data for it.
  Workspace MakeWorkspace() const;
  /// Sets `values` (one per parameter, in the spec's units) in ws.model and recomputes the
  /// model's derived constants (mj_setConst); a no-op when it holds them already.
  void Apply(const std::vector<double>& values, Workspace& ws) const;
  /// Sets the model fields of `values` in `m` (a model of the same scene): Apply without the
  /// derived constants, for writing the fitted scene.
  void SetModel(const std::vector<double>& values, mjModel* m) const;
  /// Replays window w with `values`: residuals into r (window_residuals(w) of them) and,
  /// unless null, the predicted column values (the sensor's bias, gain and delay applied; NaN where the
  /// model has none: a counter's rows before the first gate the window saw whole).
  /// False when the simulation diverged (MuJoCo's bad qpos/qvel/qacc).
  bool Rollout(int w, const std::vector<double>& values, Workspace& ws, double* r, double* predicted) const;

  /// Log file, time and measured value of each residual of window w, for plots.
  struct Sample {
    int log = 0;
    double time_s = 0;
  };
  Sample WindowRow(int w, int k) const;
  double Measured(int w, int k, int column) const;
  double Weight(int column) const { return weights_[column]; }
  const std::vector<std::string>& log_files() const { return spec_.logs; }

  /// An arm joint the logs record: its device, MJCF name and addresses in the model.
  struct Joint {
    std::string device, name;
    int qpos = -1, dof = -1, actuator = -1;
  };
  /// Read-only views for the linear first estimate (identify_linear.h): the arm joints in
  /// the logs' order, each log's q, qd and tau (rows x joints, as recorded), the logs' row
  /// period (s) and the scenario's initial qpos (the joints outside the arms).
  const std::vector<Joint>& joints() const { return joints_; }
  int log_count() const { return static_cast<int>(logs_.size()); }
  const Eigen::MatrixXd& log_q(int log) const { return logs_[log].q; }
  const Eigen::MatrixXd& log_qd(int log) const { return logs_[log].qd; }
  const Eigen::MatrixXd& log_tau(int log) const { return logs_[log].tau; }
  double row_period() const { return steps_per_row_ * model_->opt.timestep; }
  const std::vector<double>& initial_qpos() const { return qpos_init_; }

 private:
  struct Column {
    int joint = 0;  ///< -1: a wrench device's, a counter's or a derived column
    bool velocity = false;
    int wrench = -1, axis = 0;             ///< wrench device (wrenches_) and axis (Fx .. Mz)
    int counter = -1;                      ///< counter device (counters_): its speed, rpm
    int bias = -1, gain = -1, delay = -1;  ///< parameters transforming it, -1: none
    bool torque = false;                   ///< the joint's applied torque (input: reference)
    /// a derived column: the norm of these (plain columns), or with `rate` of their rates;
    /// their values at each row are in Workspace::parts from `part` on
    std::vector<Column> parts;
    std::vector<std::string> part_names;
    bool rate = false;
    int part = 0;
    std::vector<std::pair<double, double>> spans;  ///< rows in the residual (none: all)
    bool Counts(double time_s) const;              ///< a row at this time is in the residual
    bool settles() const;                          ///< a wrench column, or one derived from one
  };
  /// An arm device: its config (a SimArm per workspace is made from it) and its joints.
  struct Arm {
    lab::DeviceConfig config;
    int first = 0, joints = 0;         ///< its joints in joints_
    int bandwidth = -1, damping = -1;  ///< servo gain parameters, -1: the config's
  };
  struct Log {
    std::vector<double> time;
    Eigen::MatrixXd q, qd, tau;  ///< rows x joints
    Eigen::MatrixXd measured;    ///< rows x fitted columns
    /// input: reference: the command in force over the period ending at each row: its mode
    /// (bridge::ArmMode, rows x arms) and value (rows x joints); the servo's position reference
    /// at each row (rows x joints: hold and position, the logged value; velocity, integrated
    /// from the last one; NaN after torque mode, where the reference follows the joint)
    Eigen::MatrixXd mode, command, reference;
    /// each counter's readings: at each row, the row of the reading in force and the row its
    /// gate began (-1: the device's start, before its first reading)
    std::vector<std::vector<int>> reading, gate;
    std::vector<double> start_speed;  ///< spec start_speed: the counter's speed column
  };
  struct Window {
    int log = 0, first = 0, rows = 0, offset = 0;
    /// the measured q and qd about the first row, per joint: a + b x + c x² at x rows after it
    /// (smoothed), so that a delayed sensor's start value can be read ahead
    Eigen::MatrixXd q0, qd0;  ///< joints x 3 (a, b, c)
    double speed_ratio = 0;   ///< spec start_speed: the counter's speed at the start over its initial speed
    /// spec start_speed: each residual's change per rpm of start speed (at the nominal values),
    /// along which the start speed is profiled out of the window's residuals (Rollout)
    std::vector<double> speed_gain;
    int left_out = 0;  ///< residuals held at 0
  };

  Problem() = default;
  void BindJoints(const lab::Scenario& scenario);
  void BindWrenches(const lab::Scenario& scenario);
  void BindCounters(const lab::Scenario& scenario);
  void CheckInertias() const;
  void BindColumns();
  void BindParameters();
  void ReadLogs();
  void CutWindows();
  // a window's row k (1..rows) of column c enters the residual (else it is held at 0)
  bool Counted(const Window& win, const Column& c, int k) const;
  std::vector<double> NominalValues() const;
  void StartSpeedGains(int threads);
  // Rollout's replay, from the start speed `speed_ratio` (spec start_speed), nothing profiled
  bool Replay(int w, const std::vector<double>& values, double speed_ratio, Workspace& ws, double* r,
              double* predicted) const;
  void ReadCounterGates(Log* log) const;
  double StartSpeed(const Log& log, int row, double from, double to) const;
  // a plain column's value now: a joint's or servo's, a wrench device's axis, a counter's angle
  double ColumnValue(const Column& c, const Workspace& ws) const;
  void SkipContactWindows(int threads);
  // the true start state of a joint from the measured fit (a, b, c), the sensor transforms undone
  double TrueState(const Eigen::MatrixXd& fit, int joint, bool velocity, const std::vector<double>& values) const;
  // input: reference (identify_servo.cc): the recorded commands of a log; the servos' gains for
  // `values` (at the scenario's initial state, as the arm's Start makes them); a window's
  // servo state from its first row; a row's commands taken; one physics step with the servos
  // `steps`: physics steps a row (the log's period, checked); `log` holds its q already
  void ReadCommands(const scene::CsvTable& table, const std::string& file, int steps, Log* log) const;
  void TuneServos(const std::vector<double>& values, Workspace& ws) const;
  void StartServos(const Window& win, Workspace& ws) const;
  void CommandServos(const Log& log, int row, Workspace& ws, int only = -1) const;
  void StepWithServos(Workspace& ws) const;

  Spec spec_;
  ModelPtr model_;
  std::string scene_;
  std::vector<double> qpos_init_;  ///< the scenario's initial qpos
  std::vector<double> qvel_init_;  ///< and qvel
  int steps_per_row_ = 1;
  bool reference_ = false;  ///< input: reference
  std::uint64_t seed_ = 1;  ///< the scenario's (the arm devices' contexts)
  std::vector<Joint> joints_;
  std::vector<Arm> arms_;
  std::vector<WrenchSensor> wrenches_;
  std::vector<CounterSensor> counters_;
  int start_counter_ = -1;     ///< spec start_speed: its counter (counters_)
  double start_speed0_ = 0;    ///< its joint's speed in the initial state, rpm
  int part_count_ = 0;         ///< derived columns' parts, in all
  std::vector<bool> arm_dof_;  ///< per dof: an arm joint's
  int run_in_steps_ = 0;       ///< spec run_in, in physics steps
  std::vector<BodyEdit> bodies_;
  int wrench_columns_ = 0;      ///< fitted columns of wrench devices (or derived from them)
  int wrench_settle_rows_ = 0;  ///< their rows left out at a window's start
  std::vector<Column> columns_;
  std::vector<std::string> column_names_;
  std::vector<double> weights_;
  std::vector<BoundParameter> parameters_;
  std::vector<Log> logs_;
  std::vector<Window> windows_;
  int residual_count_ = 0;
  int rows_left_out_ = 0;
  int windows_in_contact_ = 0;
};

}  // namespace vlab::identify
