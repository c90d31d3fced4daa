// The kinematic chain through which a task-space device (kinds point and
// tool) drives its arm device (device_arm_chain.cc): the chain from a base body
// to a site, the arm device it is bound to and how their joints map, and the
// resolved-rate controller (control/task_space.h) made at each reset.
//
// Ports (of a device built on it)
//   input   the chain's joint positions (rad) and velocities (rad/s), read out
//           of mjData (ReadArmChain), and the site's pose and velocity
//           (ReadSiteMotion), world frame
//   output  to the arm, once per control period: a velocity command for every
//           arm joint (0 for arm joints outside the chain; DriveArm), or the
//           arm's hold mode (HoldArm, and DriveArm when the controller's
//           output or the command is not usable: never drift)
// Setup (MakeArmChain, BindArmChain, ResetArmChain) throws InputError
// naming the device; ReadArmChain, DriveArm, HoldArm and ReadSiteMotion never
// throw and never allocate (buffers are sized by MakeArmChain and BindArmChain).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>
#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>

#include "bridge/bridge_layouts.h"
#include "control/robot_model.h"
#include "control/task_space.h"
#include "lab/devices/device.h"
#include "lab/devices/device_arm.h"
#include "lab/run/lab_command_writer.h"

namespace vlab::lab {

/// The keys a task-space device shares: its arm, its chain and the resolved-rate
/// gains (scenario keys arm, site, base_body, gains: {position, orientation,
/// null_space, damping}).
struct ArmChainParams : DeviceParams {
  std::string arm;                  ///< the arm device it drives (a device of the same scenario)
  std::string site = "tool";        ///< the point or tool frame: an MJCF site at the end of the arm's chain
  std::string base_body = "world";  ///< the chain starts below this body
  double k_position = 20.0;         ///< position gain, 1/s
  double k_orientation = 20.0;      ///< orientation gain, 1/s
  double k_null = 1.0;              ///< null-space gain toward the start posture, 1/s
  double damping = 1e-3;            ///< DLS damping of the pseudo-inverse
  CommandInputConfig input;         ///< watchdog_periods, owner_timeout
};

/// Reads arm (required), site, base_body and the four gains of `gains` into
/// `params`; returns the `gains` map for the caller's own check of the gains and
/// its Finish. Throws InputError naming the file and key.
MapReader ReadArmChainParams(MapReader& r, ArmChainParams* params);

/// A device's chain and the arm it drives. Made by MakeArmChain; the arm bound by
/// BindArmChain; the controller made by ResetArmChain at each reset.
struct ArmChain {
  std::unique_ptr<control::RobotModel> model;                // base_body .. site
  int site = -1;                                             // MuJoCo id of the site
  SimArm* arm = nullptr;                                     // bound by BindArmChain
  std::vector<int> arm_index;                                // chain joint i is arm joint arm_index[i]
  std::unique_ptr<control::TaskSpaceController> controller;  // made by ResetArmChain
  Eigen::VectorXd q, qd;                                     // chain joints as last read, rad, rad/s
  bridge::ArmCommand velocity, hold;                         // what the arm is sent
  bool holding = true;  // the arm holds: before the first command, on the watchdog, after a reset
  bool resume = false;  // a command ended a hold: the next period starts the set-point from the site
};

/// The chain from params.base_body to params.site of `model`. Throws InputError
/// "WHO: robot model: no site 'x'" (`who`: the device's Device::who()).
ArmChain MakeArmChain(const mjModel* model, const ArmChainParams& params, const std::string& who);

/// Binds the chain to its arm: the device named params.arm among `devices`, which
/// must be an arm device, and maps every chain joint to its arm joint. Throws
/// InputError naming the device (`who`) when there is no such arm or a chain
/// joint is not one of its joints. (That the device is the arm's one driver is
/// the lab's claim table's to check: lab_command_writer.h.)
void BindArmChain(ArmChain& chain, const ArmChainParams& params, const std::vector<Device*>& devices,
                  const std::string& who);

/// Reads the chain's joint positions and velocities out of `d` into chain.q,
/// chain.qd and sets the chain's state to them. No allocation.
void ReadArmChain(ArmChain& chain, const mjData& d);

/// At a reset: makes the controller with the params' gains and puts the chain
/// in hold (ArmChain::holding). The null-space term keeps the posture of chain.q
/// (read it first: the start posture). Where the arm has velocity limits, the
/// controller scales its output uniformly below 0.999 x the slowest chain
/// joint's limit, so the arm never refuses it. Allocates: a reset, not the step
/// loop.
void ResetArmChain(ArmChain& chain, const ArmChainParams& params);

/// A command was accepted: the device leaves its hold (ArmChain::holding), and
/// when it was holding, the next BeginArmChainPeriod reports a resume.
void CommandArmChain(ArmChain& chain);

/// Starts a control period. Holding: the arm holds (HoldArm) and it returns
/// false. Otherwise it reads the chain (ReadArmChain), sets *resumed when this is
/// the first period after a hold (the set-point then starts from where the site
/// is) and returns true: the caller then computes its target and calls DriveArm.
bool BeginArmChainPeriod(ArmChain& chain, const mjData& d, bool* resumed);

/// One period's command: the controller's joint velocities toward `target` for
/// the chain state last read, sent to the arm; the arm holds instead when the
/// controller's output is not ok (non-finite state) or the arm refuses it.
void DriveArm(ArmChain& chain, const control::TaskSpaceTarget& target);

/// The arm holds its joints where they are (arm hold mode).
void HoldArm(ArmChain& chain);

/// A site's pose and velocity, world frame.
struct SiteMotion {
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();       // position, m
  Eigen::Matrix3d R_WS = Eigen::Matrix3d::Identity();  // orientation
  Eigen::Vector3d v_W = Eigen::Vector3d::Zero();       // linear velocity, m/s
  Eigen::Vector3d w_W = Eigen::Vector3d::Zero();       // angular velocity, rad/s
};

/// The chain site's pose and velocity in `d` (positions from the last kinematics).
SiteMotion ReadSiteMotion(const mjModel* model, const mjData& d, const ArmChain& chain);

/// The describe facts both devices give alike: the layout of `kind`, frame, arm,
/// site, status_bits, gains and watchdog_periods. The device adds its units and
/// limits.
nlohmann::json ArmChainFacts(const ArmChain& chain, const ArmChainParams& params, bridge::DeviceKind kind);

}  // namespace vlab::lab
