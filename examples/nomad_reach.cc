// nomad_reach: the PA10 on the Nomad XR4000 drives to a table and reaches a point
// on it. An external program that talks to the robot only through the vlab
// client library (an arm device and a base device); for its arithmetic it has
// its own kinematic model of the arm, loaded from the scene's MJCF.
//
//   nomad_reach --scene FILE.xml [--arm HOST:PORT] [--base HOST:PORT]
//               [--to X] [--target X,Y,Z] [--timeout S] [--quiet]
//
// Time is the states' simulated time from the first state's (lockstep or realtime):
//   0 .. 6 s     the base drives along world x from its start to X (--to, 2.25 m:
//                parked 5 cm before the table) on a quintic profile, world-frame
//                velocity commands with odometry feedback; the arm holds its
//                joints (position mode), so the tool keeps its pose on the base
//   6 .. 7 s     the base stands (zero velocity); the arm still holds
//   7 .. 11 s    the arm brings the tool tip to the target (--target, world, m;
//                default 2.85, 0, 0.73: 1 cm above the red disc on the table) on
//                a quintic straight line, keeping the tool's orientation, by
//                resolved-rate control in velocity mode, in the base's frame
//                from the odometry pose
//   11 s ..      the arm holds the target (velocity mode, feedback only)
// Every period it sends the base's command before the arm's (lockstep waits for
// both once the arm is owned). It ends when no state arrives for --timeout
// seconds (2 s: the run is over) or on SIGTERM / SIGINT, and prints the tool's
// last distance to the target by its own model: exit 0; 2 on a bridge error or
// bad arguments.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include <mujoco/mujoco.h>
#include <Eigen/Core>

#include "bridge/bridge_client.h"
#include "bridge/bridge_client_device.h"
#include "bridge/bridge_errors.h"
#include "bridge/bridge_layouts.h"
#include "bridge/bridge_program.h"
#include "control/robot_model.h"
#include "control/task_space.h"
#include "control/time_scaling.h"

namespace {

using Eigen::Vector3d;
using Eigen::VectorXd;
using vlab::bridge::Arm;
using vlab::bridge::ArmMode;
using vlab::bridge::Device;
using vlab::bridge::DeviceKind;

using vlab::bridge::program::kPoll_s;
using vlab::bridge::program::Stopped;

constexpr double kDrive_s = 6.0, kStand_s = 1.0, kReach_s = 4.0;
constexpr double kOdometryGain = 5.0;  // 1/s on the base's position error
// the base's odometry in its state (bridge/bridge_layouts.h)
constexpr int kBaseX = vlab::bridge::StateIndex(DeviceKind::kBase, "x");
constexpr int kBaseY = vlab::bridge::StateIndex(DeviceKind::kBase, "y");
constexpr int kBaseYaw = vlab::bridge::StateIndex(DeviceKind::kBase, "yaw");
constexpr double kWorldFrame = 1;  // the base command's frame: world

struct Options {
  std::string scene;
  std::string arm_host = "127.0.0.1", base_host = "127.0.0.1";
  int arm_port = 50040, base_port = 50041;
  double to_x = 2.25;
  Vector3d target{2.85, 0.0, 0.73};
  double timeout_s = 2.0;
  bool quiet = false;
};

bool ParseAddress(const std::string& text, std::string* host, int* port) {
  vlab::bridge::program::Address a;
  if (!vlab::bridge::program::ParseAddress(text, &a)) return false;
  *host = a.host;
  *port = a.port;
  return true;
}

bool Parse(int argc, char** argv, Options* o) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--quiet") {
      o->quiet = true;
      continue;
    }
    if (i + 1 >= argc) return false;
    const std::string value = argv[++i];
    if (arg == "--scene") {
      o->scene = value;
    } else if (arg == "--arm") {
      if (!ParseAddress(value, &o->arm_host, &o->arm_port)) return false;
    } else if (arg == "--base") {
      if (!ParseAddress(value, &o->base_host, &o->base_port)) return false;
    } else if (arg == "--to") {
      o->to_x = std::atof(value.c_str());
    } else if (arg == "--target") {
      if (std::sscanf(value.c_str(), "%lf,%lf,%lf", &o->target.x(), &o->target.y(), &o->target.z()) != 3) return false;
    } else if (arg == "--timeout") {
      o->timeout_s = std::atof(value.c_str());
    } else {
      return false;
    }
  }
  return !o->scene.empty() && o->timeout_s > 0;
}

// the next state after `seq` (blocks in slices; false: silence for timeout_s or a signal)
template <typename Client, typename State>
bool ReadAfter(Client& client, std::int64_t seq, double timeout_s, State* state) {
  for (double waited = 0; !Stopped() && waited < timeout_s; waited += kPoll_s) {
    try {
      *state = client.Read(kPoll_s);
      if (state->seq > seq) return true;
      waited = 0;
    } catch (const vlab::bridge::TimeoutError&) {
    }
  }
  return false;
}

// the scene's arm chain, from the base's mount plate to the tool site; its world
// is the base frame (the model's base joints stay at zero)
struct ArmModel {
  std::unique_ptr<mjModel, void (*)(mjModel*)> model{nullptr, mj_deleteModel};
  std::unique_ptr<vlab::control::RobotModel> chain;
  std::unique_ptr<vlab::control::TaskSpaceController> control;
};

ArmModel LoadArm(const std::string& scene, const VectorXd& q_rest) {
  ArmModel a;
  char error[512] = "";
  a.model.reset(mj_loadXML(scene.c_str(), nullptr, error, sizeof(error)));
  if (!a.model) throw std::runtime_error("scene '" + scene + "': " + error);
  a.chain = vlab::control::RobotModel::Create(a.model.get(), {"xr4000_mount", "tool"});
  vlab::control::TaskSpaceConfig config;
  config.q_rest = q_rest;
  a.control = vlab::control::TaskSpaceController::Create(config, *a.chain);
  return a;
}

int Run(const Options& o) {
  Device base = Device::Connect(DeviceKind::kBase, o.base_host, o.base_port, 1.0);
  Arm arm = Arm::Connect(o.arm_host, o.arm_port, 1.0);
  if (arm.joints() != 7)
    throw std::runtime_error(arm.Label() + " has " + std::to_string(arm.joints()) + " joints, not 7");
  Arm::State s = arm.Read(o.timeout_s);
  Device::State b;
  if (!ReadAfter(base, s.seq - 1, o.timeout_s, &b)) return 0;
  const double t0 = s.time;
  const VectorXd q_hold = s.q;
  const double x0 = b.values[kBaseX];
  ArmModel model = LoadArm(o.scene, q_hold);

  Vector3d p_start = Vector3d::Zero();                   // tool at the start of the reach, world
  Eigen::Matrix3d R_hold = Eigen::Matrix3d::Identity();  // tool orientation on the base
  double error = 0;
  for (;;) {
    const double t = s.time - t0;
    const double x = b.values[kBaseX], y = b.values[kBaseY], yaw = b.values[kBaseYaw];
    // the base: a quintic drive along x with odometry feedback, then stand
    double vx = 0, vy = 0, wz = 0;
    if (t < kDrive_s) {
      const vlab::control::ScalingSample ts = vlab::control::EvaluateTimeScaling({}, kDrive_s, t);
      vx = (o.to_x - x0) * ts.sd + kOdometryGain * (x0 + (o.to_x - x0) * ts.s - x);
    } else {
      vx = kOdometryGain * (o.to_x - x);
    }
    vy = -kOdometryGain * y;
    wz = -kOdometryGain * yaw;
    if (t >= kDrive_s + kStand_s) vx = vy = wz = 0;  // parked: the arm reaches from a still base
    base.WriteFields({{"frame", kWorldFrame},
                      {"vx", std::clamp(vx, -0.9, 0.9)},
                      {"vy", std::clamp(vy, -0.9, 0.9)},
                      {"wz", std::clamp(wz, -1.8, 1.8)}},
                     b.seq);

    // the arm: hold, then reach in the base's frame
    model.chain->SetState(s.q, VectorXd::Zero(7));
    const Eigen::Matrix3d R_WB = Eigen::AngleAxisd(yaw, Vector3d::UnitZ()).toRotationMatrix();
    const Vector3d p_target = R_WB.transpose() * (o.target - Vector3d(x, y, 0));
    const vlab::control::Pose tip = model.chain->TipPose();
    error = (tip.p_W - p_target).norm();
    if (t < kDrive_s + kStand_s) {
      arm.Write(ArmMode::kPosition, q_hold, s.seq);
      p_start = tip.p_W;
      R_hold = tip.R_W;
    } else {
      const vlab::control::ScalingSample ts = vlab::control::EvaluateTimeScaling({}, kReach_s, t - kDrive_s - kStand_s);
      vlab::control::TaskSpaceTarget target;
      target.pose.p_W = p_start + ts.s * (p_target - p_start);
      target.pose.R_W = R_hold;
      target.v_W = ts.sd * (p_target - p_start);
      arm.Write(ArmMode::kVelocity, model.control->Update(*model.chain, s.q, target).qd_cmd, s.seq);
    }
    // the next period: the arm's state, then the base's of the same period
    if (!ReadAfter(arm, s.seq, o.timeout_s, &s)) break;
    if (!ReadAfter(base, s.seq - 1, o.timeout_s, &b)) break;
  }
  if (!o.quiet) std::printf("tool to target (own model): %.6f m\n", error);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  if (!Parse(argc, argv, &options)) {
    std::fprintf(stderr,
                 "usage: %s --scene FILE.xml [--arm HOST:PORT] [--base HOST:PORT] [--to X] [--target X,Y,Z] "
                 "[--timeout S] [--quiet]\n",
                 argv[0]);
    return 2;
  }
  return vlab::bridge::program::Main("nomad_reach", [&] { return Run(options); });
}
