// Value types of the task language: vec3, quat and frame, as Lua userdata
// backed by Eigen.
//
//   vec3(x, y, z)                 a point or direction, m
//   quat(w, x, y, z)              a rotation (normalised on construction)
//   frame(...)                    a pose: position (m) and rotation
//
// Constructors (angles in degrees): trans(x, y, z), rpy(r, p, y) (about the
// fixed x, y, z axes: R = Rz(y) Ry(p) Rx(r), as the scenario files' rpy_deg),
// euler("ZYZ", a, b, c) (any of the 12 conventions; upper case: intrinsic,
// rotating axes; lower case: extrinsic, fixed axes), rotx/roty/rotz(deg),
// angleaxis(deg, vec3), rotm{{...}, {...}, {...}} (rows of a rotation matrix).
// Operators: frame * frame composes, frame * vec3 transforms a point,
// quat * quat composes, quat * vec3 rotates; :inv() inverts. Printing gives
// "frame(pos = (0.5, 0, 0.4) m, rpy = (180, 0, 90) deg)".
//
// Errors are Lua errors naming the function and the argument ("rotm: row 2
// is not orthonormal ...").
#pragma once

#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

struct lua_State;

namespace vlab::task {

/// A pose: position p (m) and unit quaternion q, both in the parent frame.
struct Frame {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
};

/// Registers the types and constructors as globals of `L`.
void OpenValues(lua_State* L);

/// Pushes a value. The quaternion is normalised.
void PushVec3(lua_State* L, const Eigen::Vector3d& v);
void PushQuat(lua_State* L, const Eigen::Quaterniond& q);
void PushFrame(lua_State* L, const Frame& f);
/// The value at `index`, or nullptr when it is not of that type.
Eigen::Vector3d* ToVec3(lua_State* L, int index);
Eigen::Quaterniond* ToQuat(lua_State* L, int index);
Frame* ToFrame(lua_State* L, int index);
/// The value at `index` or a Lua error naming `what` and the type found.
const Frame& CheckFrame(lua_State* L, int index, const char* what);
const Eigen::Vector3d& CheckVec3(lua_State* L, int index, const char* what);

/// Rotation of Euler angles (rad) in `convention`: three of the letters
/// x, y, z (all upper case: intrinsic, about the rotating axes; all lower
/// case: extrinsic, about the fixed axes), no two neighbours alike. Throws
/// std::invalid_argument naming the convention when it is not one of the 12.
Eigen::Quaterniond EulerRotation(const std::string& convention, double a, double b, double c);
/// The angles (rad) of `q` in `convention`, the inverse of EulerRotation:
/// the second angle in [0, π] (proper Euler) or [−π/2, π/2] (Tait–Bryan).
Eigen::Vector3d EulerAngles(const std::string& convention, const Eigen::Quaterniond& q);

/// "frame(pos = (x, y, z) m, rpy = (r, p, y) deg)" with 6 significant digits.
std::string FormatFrame(const Frame& f);

}  // namespace vlab::task
