// One robot program's private state inside the runtime (not a public header):
// its Lua state and coroutine, its robot (arm channel, chain, motion planner,
// the running plan) and the blackboard it shares with the other programs.
#pragma once

#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "control/robot_model.h"
#include "task/task_channel.h"
#include "task/task_motion.h"
#include "task/task_runtime.h"
#include "task/task_sandbox.h"
#include "task/task_values.h"

struct lua_State;

namespace vlab::task {

/// A value of the blackboard, copied in and out by value.
struct SharedValue {
  enum Type { kNumber, kString, kBoolean, kVec3, kQuat, kFrame } type = kNumber;
  double number = 0;
  std::string text;
  Frame frame;  ///< kFrame; kVec3 uses frame.p, kQuat frame.q
};

/// What every program of a runtime shares.
struct Blackboard {
  std::map<std::string, SharedValue> values;
  std::map<std::string, long> signals;  ///< raised and not yet taken
  std::set<std::string> robots;         ///< every program's robot, by name
  std::set<std::string> stops;          ///< robots whose running move stop(name) asked to halt
};

/// Force mode of a robot (force_mode ... end_force_mode; task_force.cc): along each held
/// axis of the task frame the commanded tool position is an admittance, moved each period
/// at v = clamp(k (F_target - F), +-v_max) (its change limited to a_max per second); along
/// the free axes it follows the running move's path, or rests where the path ended.
struct ForceMode {
  bool on = false;
  bool held[3] = {false, false, false};                ///< task axes x, y, z held
  Eigen::Vector3d target_N = Eigen::Vector3d::Zero();  ///< force the tool exerts on the world, task axes
  Eigen::Matrix3d R_WT = Eigen::Matrix3d::Identity();  ///< task frame axes (columns) in the world
  Eigen::Vector3d c_m = Eigen::Vector3d::Zero();       ///< commanded position along each task axis, m
  Eigen::Vector3d v_mps = Eigen::Vector3d::Zero();     ///< the admittance's speed along each axis
  double v_max_mps = 0, a_max_mps2 = 0, gain_mps_per_N = 0, period_s = 0;
  Channel* wrench = nullptr;
  Eigen::Vector3d bias_N = Eigen::Vector3d::Zero();   ///< sensor frame: its reading at the start
  Eigen::Vector3d force_T = Eigen::Vector3d::Zero();  ///< the last force measured, task axes, N
  Frame nominal_W;    ///< the path's pose of the last period (the move's sample, or where it rests)
  std::string fault;  ///< a period's IK failed: the force mode ended, the script's next wait raises it
};

/// The robot a program commands.
struct Robot {
  Channel* arm = nullptr;
  std::unique_ptr<control::RobotModel> model;
  std::unique_ptr<MotionPlanner> planner;
  std::vector<int> arm_index;  ///< chain joint i is arm joint arm_index[i]
  int arm_dof = 0;
  std::vector<double> state;      ///< the arm's newest state payload
  Eigen::VectorXd q_meas, q_ref;  ///< chain joints, rad
  Eigen::VectorXd q_ref_before;   ///< the reference of the period before q_ref's (empty: none yet)
  std::vector<double> command;    ///< [mode, arm joints...]
  bool started = false;           ///< q_ref set from a first state
  Frame base_W;                   ///< world <- the script's base frame
  MotionLimits limits;
  // the running move
  Plan plan;
  std::size_t next = 0;
  bool moving = false;
  std::string outcome = "done";  ///< of the last move: "done", "contact" or "stopped"
  long sent_cap = -1;            ///< samples the move had handed out when stop() halted it (-1: not stopped)
  // blending (movel's r, blend()): the running move may be left for the next at sample
  // blend_at (-1: it runs to its end), where the tool is within blend_radius of its target
  double blend_setting_m = 0;  ///< blend(r)
  long blend_at = -1;
  double blend_radius_m = 0;
  Eigen::Vector3d blend_corner_W = Eigen::Vector3d::Zero();
  double segment_m = 0;  ///< length of the running move's straight segment
  // guards of the running move (task_force.cc): the force's change (its norm, or its
  // component along guard_dir_W when that is not zero), the torque's change
  Channel* guard = nullptr;
  double guard_force_N = 0;
  Eigen::Vector3d guard_bias_N = Eigen::Vector3d::Zero();
  Eigen::Vector3d guard_dir_W = Eigen::Vector3d::Zero();  ///< unit; the force the tool exerts on the world
  double guard_torque_Nm = 0;
  Eigen::Vector3d guard_torque_bias_Nm = Eigen::Vector3d::Zero();
  Channel* default_wrench = nullptr;
  ForceMode force;
  Channel* zero_wrench = nullptr;                    ///< force_zero(): the device zeroed, and its zero
  Eigen::Vector3d zero_N = Eigen::Vector3d::Zero();  ///< (sensor frame, N)
  std::vector<double> reading;                       ///< a wrench reading (kept: no allocation per period)
  Eigen::VectorXd zero_qd;                           ///< joint speeds of kinematics-only evaluations
  // the planned tool position of the log, and the q_ref it belongs to
  Eigen::Vector3d tool_ref_W = Eigen::Vector3d::Zero();
  Eigen::VectorXd tool_ref_q;
};

struct Program {
  ProgramConfig config;
  std::string label;  ///< robot name, or the script's file name
  int index = 0;
  SandboxConfig sandbox;
  lua_State* L = nullptr;
  lua_State* co = nullptr;
  bool ended = false;
  int failed_line = 0;  ///< the script line of its error (>= 1) once it failed; 0 otherwise
  double t_s = 0;       ///< simulated time of the current period
  double period_s = 0.002;
  bool markers_hold = true;      ///< RuntimeConfig::markers_hold
  double markers_wait_s = 10.0;  ///< RuntimeConfig::markers_wait_s
  std::unique_ptr<Robot> robot;  ///< null for a program without a robot
  Devices* devices = nullptr;
  Blackboard* board = nullptr;
  std::map<std::string, std::vector<double>> device_commands;  ///< re-sent every period
};

/// Registers the robot and device functions and runs the prelude (wait,
/// blocking moves) in the program's state.
void OpenApi(Program* program);

/// Registers device(), the markers functions the prelude wraps, signal and
/// the `shared` blackboard proxy (task_api_io.cc); before the prelude runs.
void OpenIo(lua_State* L);

/// Registers fk, ik and reachable (task_api_query.cc): kinematics queries
/// that never move the robot.
void OpenQueries(lua_State* L);

/// Registers payload() (task_payload.cc): the robot arm's load at its flange.
void OpenPayload(lua_State* L);

/// Registers _servoj (task_api_servo.cc), which the prelude's servoj wraps: a
/// streamed joint reference, checked against the joints' limits.
void OpenServo(lua_State* L);

/// Starts `plan` as the robot's running move (no blend, guard or trigger).
void StartPlan(Robot* robot, Plan plan);

/// The program of a Lua state (set by OpenApi).
Program* ProgramOf(lua_State* L);

/// The next joint reference of the program's robot: advances the running
/// plan, stops it when its guard trips; in force mode, AdvanceForceMode. The
/// reference before it is kept (q_ref_before). Never throws.
void AdvanceMotion(Robot* robot);

/// The guard of the running move that has tripped this period ("contact" for
/// the force, "torque"), or null. Never throws.
const char* GuardTripped(Robot* robot);

/// One period of force mode: the running move's next sample (or the pose
/// where its path rests), moved along each held axis by the admittance, to
/// joints by Newton steps from the last reference. A pose the IK cannot reach
/// ends the force mode and the move, with ForceMode::fault set. Never throws.
void AdvanceForceMode(Robot* robot);

/// The force (N) the tool exerts on the world, world axes, from a wrench
/// reading's force `f_sensor` less `bias` (sensor frame, whose axes are taken
/// as the tip site's at the measured joints).
Eigen::Vector3d ExertedForce_W(Robot* robot, const Eigen::Vector3d& f_sensor, const Eigen::Vector3d& bias);

/// Registers force_mode's and search's functions and the move options' guard
/// parser (task_api_force.cc).
void OpenForce(lua_State* L);

/// Checks the guard options of a move at stack index `options` (force, dir,
/// torque, wrench, stop_if) before it is planned: script errors name `what`
/// and the option.
void CheckGuards(lua_State* L, Robot& r, int options, const char* what);
/// Sets the running move's guards from its (checked) options; stop_if is the
/// prelude's.
void SetGuards(lua_State* L, Robot& r, int options, const char* what);

/// Halts the robot's running move on its own path (stop(name)): the rest of
/// the plan is followed at a rate that falls from one sample per period to
/// zero as fast as every joint's acceleration limit allows (the rate's fall
/// adds |v_j|·δ/T to joint j's deceleration, the plan's own acceleration
/// counted in), so the tool stays on the planned path and stops short of the
/// plan's end (or at it, when that is nearer). The move's outcome is
/// "stopped". Nothing when no move runs. Never throws.
void StopMotion(Robot* robot, double period_s);

}  // namespace vlab::task
