// Reads a kinematic arm from an MJCF scene: joint names and position ranges
// only (no masses, no motors, no dynamics).
#pragma once

#include <string>
#include <vector>

#include "kinsim/kinsim.h"

namespace vlab::kinsim {

/// The PA10's joints in wire order and its "ready" pose (rad) from scenes/pa10.xml.
const std::vector<std::string>& Pa10Joints();
const std::vector<double>& Pa10ReadyPose();
/// Choreonoid's PA10 jointVelocityRange: 180 deg/s = pi rad/s.
inline constexpr double kPa10VelocityMax = 3.14159265358979323846;

/// Builds a KinArmConfig from the hinge or slide joints `joints` of the MJCF
/// file `scene` (loaded with vlab::LoadModel): their ranges become the position
/// limits (rad or m, as compiled). velocity_max holds one value for every joint
/// or one per joint; initial one value per joint. Throws vlab::InputError naming
/// the scene and the joint when the file does not load, a joint is missing, is
/// not a hinge or slide, or has no range. The result is validated by
/// KinArm::Create, not here.
KinArmConfig ArmFromScene(const std::string& name, const std::string& scene, const std::vector<std::string>& joints,
                          const std::vector<double>& velocity_max, const std::vector<double>& initial);

}  // namespace vlab::kinsim
