// Reference data for the HOAP-3 model tests, typed from the sources, not from the MJCF:
//   - DATASHEET 3.2 (SL joint limits), 3.3 (link geometry), 3.4 (manufacturer mass
//     properties: right side, central inertia, SL product signs), 3.5 (FSR layout);
//   - the zero-pose link frames of jrl-umi3218/hoap3_description urdf/hoap3.urdf (joint
//     origins rpy/xyz, axes, limits), in which DATASHEET 3.4 gives COMs and inertias.
// The SL joint angle (the robot's servo interface) is sign * the URDF joint angle; the
// signs follow from the SL limits (SensorOffset.cf) against the URDF limits where those
// are asymmetric, and from the UC3M encoder relation signs (hoap3_structure.m) where they
// are symmetric (RL/LL_J5, RL/LL_J6, RA/LA_J3); the wrist and head servos take the URDF's.
#pragma once

#include <array>

namespace vlab::models::testing {

constexpr double kHalfPi = 1.57079632679;

/// One URDF joint: the child link frame relative to its parent at zero angle.
struct UrdfJoint {
  const char* child;
  const char* parent;
  std::array<double, 3> rpy;   ///< fixed-axis roll, pitch, yaw, rad
  std::array<double, 3> xyz;   ///< m, parent frame
  std::array<double, 3> axis;  ///< child frame ({0,0,0}: fixed joint)
  double lower, upper;         ///< URDF limits, rad
  const char* sl_joint;        ///< SL joint name ("" for fixed joints)
  double sign;                 ///< SL angle = sign * URDF angle
  const char* body;            ///< model body that carries the child link ("" if none)
};

// base_link -> WAIST is the root: rpy (pi/2, 0, 0) turns WAIST's y axis up.
inline constexpr std::array<double, 3> kWaistRpy = {kHalfPi, 0, 0};

inline constexpr UrdfJoint kUrdfJoints[] = {
    {"CHEST", "WAIST", {-kHalfPi, 0, 0}, {0, 0, 0}, {0, 1, 0}, 0.0, 0.610865, "B_J", 1, "hoap3_chest"},
    {"H_PAN", "CHEST", {0, 0, 0}, {-0.035, 0, 0.125}, {0, 0, 1}, -1.047198, 1.047198, "H_J1", 1, "hoap3_neck"},
    {"H_TILT", "H_PAN", {-kHalfPi, 0, 0}, {0.015, 0, 0.103}, {0, 0, -1}, -0.785398, 0.261799, "H_J2", 1, "hoap3_head"},
    {"H_ROLL", "H_TILT", {0, 0, 0}, {0, 0, 0}, {-1, 0, 0}, -0.261799, 0.261799, "H_J3", 1, "hoap3_head"},
    {"REYE", "H_ROLL", {0, 0, 0}, {0.05, 0.004, -0.03}, {0, 0, 0}, 0, 0, "", 0, ""},
    {"LEYE", "H_ROLL", {0, 0, 0}, {0.05, 0.004, 0.03}, {0, 0, 0}, 0, 0, "", 0, ""},
    {"R_SFE",
     "CHEST",
     {-kHalfPi, 0, 0},
     {-0.035, -0.111, 0.125},
     {0, 0, 1},
     -1.570796,
     2.443461,
     "RA_J1",
     1,
     "hoap3_r_shoulder"},
    {"R_SAA", "R_SFE", {kHalfPi, -kHalfPi, 0}, {0, 0, 0}, {0, 0, 1}, -1.570796, 0.0, "RA_J2", 1, "hoap3_r_upper_arm"},
    {"R_SHR",
     "R_SAA",
     {kHalfPi, -kHalfPi, 0},
     {0, -0.111, 0},
     {0, 0, 1},
     -1.570796,
     1.570796,
     "RA_J3",
     1,
     "hoap3_r_arm_yaw"},
    {"R_EB", "R_SHR", {kHalfPi, 0, 0}, {0, 0, 0}, {0, 0, 1}, -2.007129, 0.0, "RA_J4", -1, "hoap3_r_forearm"},
    {"R_WR", "R_EB", {kHalfPi, 0, 0}, {0, 0.0478, 0}, {0, 0, 1}, -1.047198, 1.047198, "RA_J5", 1, "hoap3_r_wrist"},
    {"L_SFE",
     "CHEST",
     {-kHalfPi, 0, 0},
     {-0.035, 0.111, 0.125},
     {0, 0, 1},
     -1.570796,
     2.443461,
     "LA_J1",
     -1,
     "hoap3_l_shoulder"},
    {"L_SAA", "L_SFE", {kHalfPi, -kHalfPi, 0}, {0, 0, 0}, {0, 0, 1}, 0.0, 1.570796, "LA_J2", 1, "hoap3_l_upper_arm"},
    {"L_SHR",
     "L_SAA",
     {kHalfPi, -kHalfPi, 0},
     {0, -0.111, 0},
     {0, 0, 1},
     -1.588250,
     1.588250,
     "LA_J3",
     1,
     "hoap3_l_arm_yaw"},
    {"L_EB", "L_SHR", {kHalfPi, 0, 0}, {0, 0, 0}, {0, 0, 1}, -2.007129, 0.0, "LA_J4", 1, "hoap3_l_forearm"},
    {"L_WR", "L_EB", {-kHalfPi, 0, 0}, {0, 0.0478, 0}, {0, 0, 1}, -1.570796, 1.570796, "LA_J5", 1, "hoap3_l_wrist"},
    {"R_LR",
     "WAIST",
     {-kHalfPi, kHalfPi, 0},
     {-0.035, -0.055, 0.039},
     {0, 0, 1},
     -1.570796,
     0.523599,
     "RL_J1",
     1,
     "hoap3_r_hip_yaw"},
    {"R_LAA",
     "R_LR",
     {kHalfPi, -kHalfPi, 0},
     {0, 0, 0},
     {0, 0, 1},
     -0.523599,
     0.349066,
     "RL_J2",
     1,
     "hoap3_r_hip_roll"},
    {"R_LFE", "R_LAA", {kHalfPi, 0, 0}, {0, 0, 0}, {0, 0, 1}, -1.396263, 1.221730, "RL_J3", -1, "hoap3_r_thigh"},
    {"R_KN", "R_LFE", {0, 0, 0}, {-0.105, 0, 0}, {0, 0, 1}, 0.087266, 2.268928, "RL_J4", 1, "hoap3_r_shank"},
    {"R_AFE", "R_KN", {0, 0, 0}, {-0.105, 0, 0}, {0, 0, 1}, -1.047198, 1.047198, "RL_J5", 1, "hoap3_r_ankle"},
    {"R_AAA", "R_AFE", {-kHalfPi, 0, 0}, {0, 0, 0}, {0, 0, 1}, -0.436332, 0.436332, "RL_J6", -1, "hoap3_r_foot"},
    {"L_LR",
     "WAIST",
     {-kHalfPi, kHalfPi, 0},
     {-0.035, -0.055, -0.039},
     {0, 0, 1},
     -0.523599,
     1.570796,
     "LL_J1",
     1,
     "hoap3_l_hip_yaw"},
    {"L_LAA",
     "L_LR",
     {kHalfPi, -kHalfPi, 0},
     {0, 0, 0},
     {0, 0, 1},
     -0.349066,
     0.523599,
     "LL_J2",
     1,
     "hoap3_l_hip_roll"},
    {"L_LFE", "L_LAA", {kHalfPi, 0, 0}, {0, 0, 0}, {0, 0, 1}, -1.396263, 1.221730, "LL_J3", 1, "hoap3_l_thigh"},
    {"L_KN", "L_LFE", {0, 0, 0}, {-0.105, 0, 0}, {0, 0, 1}, 0.087266, 2.268928, "LL_J4", -1, "hoap3_l_shank"},
    {"L_AFE", "L_KN", {0, 0, 0}, {-0.105, 0, 0}, {0, 0, 1}, -1.047198, 1.047198, "LL_J5", -1, "hoap3_l_ankle"},
    {"L_AAA", "L_AFE", {-kHalfPi, 0, 0}, {0, 0, 0}, {0, 0, 1}, -0.436332, 0.436332, "LL_J6", -1, "hoap3_l_foot"},
};

/// DATASHEET 3.2: SL limits, rad (right side, waist, head, wrists, grippers; the left side
/// is the mirror image, lower = -upper(right), upper = -lower(right)).
struct SlLimit {
  const char* joint;
  const char* mirror;  ///< left-side twin ("" if none)
  double lower, upper;
};
inline constexpr SlLimit kSlLimits[] = {
    {"RL_J1", "LL_J1", -1.57, 0.52}, {"RL_J2", "LL_J2", -0.52, 0.34}, {"RL_J3", "LL_J3", -1.22, 1.41},
    {"RL_J4", "LL_J4", 0.00, 2.25},  {"RL_J5", "LL_J5", -1.04, 1.04}, {"RL_J6", "LL_J6", -0.41, 0.41},
    {"RA_J1", "LA_J1", -1.57, 2.49}, {"RA_J2", "LA_J2", -1.65, 0.00}, {"RA_J3", "LA_J3", -1.57, 1.57},
    {"RA_J4", "LA_J4", 0.00, 1.98},  {"RA_J5", "LA_J5", -1.05, 1.05}, {"RA_J6", "LA_J6", -1.57, 1.57},
    {"B_J", "", 0.00, 1.55},         {"H_J1", "", -1.05, 1.05},       {"H_J2", "", -0.79, 0.26},
    {"H_J3", "", -0.26, 0.26},
};

/// DATASHEET 3.4: manufacturer mass properties in the URDF link frame (right side).
struct LinkMass {
  const char* link;               ///< URDF link whose frame the numbers are in
  const char* body;               ///< model body (right side)
  const char* mirror;             ///< left-side model body ("" if none)
  double mass;                    ///< kg
  std::array<double, 3> com;      ///< m
  std::array<double, 6> inertia;  ///< Ixx Iyy Izz Ixy Ixz Iyz about the COM, kg m^2
};
inline constexpr LinkMass kLinkMasses[] = {
    {"R_LR",
     "hoap3_r_hip_yaw",
     "hoap3_l_hip_yaw",
     0.0587,
     {-0.003015, -0.002240, 0.033585},
     {5.983e-5, 4.320e-5, 2.958e-5, -4.1e-7, -5.70e-6, 2.94e-6}},
    {"R_LAA",
     "hoap3_r_hip_roll",
     "hoap3_l_hip_roll",
     0.210,
     {-0.002727, 0.001135, 0.002378},
     {6.941e-5, 5.871e-5, 5.474e-5, 8.9e-7, -4.5e-7, -5.1e-7}},
    {"R_LFE",
     "hoap3_r_thigh",
     "hoap3_l_thigh",
     0.519,
     {-0.069821, 0.006165, -0.003264},
     {3.334e-4, 7.154e-4, 6.697e-4, 1.047e-5, -2.862e-5, 1.853e-5}},
    {"R_KN",
     "hoap3_r_shank",
     "hoap3_l_shank",
     0.328,
     {-0.050852, 0.005368, -0.004697},
     {2.140e-4, 3.347e-4, 2.735e-4, 2.631e-5, 1.527e-5, 9.48e-6}},
    {"R_AFE",
     "hoap3_r_ankle",
     "hoap3_l_ankle",
     0.195,
     {0.002937, 0.003668, -0.001337},
     {6.355e-5, 5.298e-5, 5.279e-5, -3.0e-7, 5.9e-7, 9.5e-7}},
    {"R_AAA",
     "hoap3_r_foot",
     "hoap3_l_foot",
     0.154,
     {-0.029224, 0.003242, 0.008276},
     {2.193e-4, 1.783e-4, 8.203e-5, -3.30e-6, -1.634e-5, 3.48e-6}},
    {"R_SFE",
     "hoap3_r_shoulder",
     "hoap3_l_shoulder",
     0.210,
     {0.000083, 0.006668, 0.006348},
     {8.667e-5, 6.700e-5, 7.296e-5, -7e-8, 5.2e-7, -3.25e-6}},
    {"R_SAA",
     "hoap3_r_upper_arm",
     "hoap3_l_upper_arm",
     0.234,
     {-0.000658, -0.046385, -0.003774},
     {1.902e-4, 9.556e-5, 1.669e-4, -4.38e-6, 1.9e-7, -1.095e-5}},
    {"R_SHR",
     "hoap3_r_arm_yaw",
     "hoap3_l_arm_yaw",
     0.1965,
     {-0.002722, -0.001603, -0.002204},
     {6.500e-5, 5.291e-5, 6.807e-5, 1.2e-7, -1.21e-6, -6.0e-7}},
    // forearm incl. wrist and hand: compared with the forearm + wrist + finger subtree
    {"R_EB",
     "hoap3_r_forearm",
     "hoap3_l_forearm",
     0.216,
     {0.001002, 0.066422, -0.000616},
     {3.606e-4, 1.034e-4, 3.366e-4, 4.5e-7, -9.0e-7, -2.205e-5}},
    {"CHEST",
     "hoap3_chest",
     "",
     3.26,
     {-0.049489, 0.000893, 0.084174},
     {1.2195e-2, 1.7564e-2, 1.5671e-2, -2.955e-4, -6.840e-4, -1.458e-4}},
    {"WAIST",
     "hoap3_pelvis",
     "",
     0.417,
     {-0.032271, 0.011138, -0.000329},
     {6.608e-4, 6.421e-4, 1.702e-4, -6.75e-6, -4.93e-6, 1.52e-6}},
    {"H_PAN",
     "hoap3_neck",
     "",
     0.071,
     {0.005397, -0.001581, 0.056403},
     {6.906e-5, 6.412e-5, 3.335e-5, -1.09e-6, 9.84e-6, -5.09e-6}},
    {"H_ROLL",
     "hoap3_head",
     "",
     0.412,
     {-0.001040, -0.005180, 0.000018},
     {5.524e-4, 7.321e-4, 6.821e-4, -7.77e-6, -3.18e-6, -4.6e-7}},
};

/// DATASHEET 3.4 total (sum of the manufacturer link masses), kg.
inline constexpr double kTotalMass = 8.802;

/// DATASHEET 3.3 link geometry, m.
inline constexpr double kHipLateral = 0.039, kWaistToHipZ = 0.055, kWaistToHipX = 0.035;
inline constexpr double kThigh = 0.105, kShank = 0.105, kAnkleToSole = 0.040;
inline constexpr double kSoleBack = -0.040, kSoleFront = 0.068, kSoleOuter = 0.0415, kSoleInner = 0.0315;
inline constexpr double kChestHeight = 0.125, kShoulderLateral = 0.111, kUpperArm = 0.111;
inline constexpr double kNeck = 0.103, kHeadOffset = 0.015, kEyeLateral = 0.030, kEyeForward = 0.05;
inline constexpr std::array<double, 3> kImuInPelvis = {-0.0325, 0, 0.1095};

/// DATASHEET 3.5 FSR layout (hoap3_read_sensors sensors.h), mm: column spacing LX,
/// row spacing LY, ZMP origin offsets MX (right foot / left foot) and MY.
inline constexpr double kFsrLx = 47.0, kFsrLy = 83.0, kFsrMxRight = 18.5, kFsrMxLeft = 28.5, kFsrMy = 27.5;

}  // namespace vlab::models::testing
