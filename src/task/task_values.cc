#include "task/task_values.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include <lua.hpp>

#include "task/task_lua.h"
#include "task/task_units.h"

namespace vlab::task {

namespace {

constexpr const char* kVec3 = "vlab.vec3";
constexpr const char* kQuat = "vlab.quat";
constexpr const char* kFrame = "vlab.frame";

template <class T>
T* New(lua_State* L, const char* type) {
  void* p = lua_newuserdatauv(L, sizeof(T), 0);
  T* value = new (p) T();
  luaL_setmetatable(L, type);
  return value;
}

double Num(lua_State* L, int i, const char* what) {
  if (!lua_isnumber(L, i)) {
    ScriptError(L, "%s: argument %d must be a number, got %s", what, i, luaL_typename(L, i));
  }
  const double v = lua_tonumber(L, i);
  if (!std::isfinite(v)) ScriptError(L, "%s: argument %d is not finite", what, i);
  return v;
}

// "%.6g", without "-0"
std::string Fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", std::abs(v) < 5e-13 ? 0.0 : v);
  return b;
}

std::string Triple(const Eigen::Vector3d& v) { return "(" + Fmt(v.x()) + ", " + Fmt(v.y()) + ", " + Fmt(v.z()) + ")"; }

Eigen::Vector3d Axis(char c) {
  switch (c) {
    case 'x':
    case 'X':
      return Eigen::Vector3d::UnitX();
    case 'y':
    case 'Y':
      return Eigen::Vector3d::UnitY();
    default:
      return Eigen::Vector3d::UnitZ();
  }
}

double Wrap(double a) {
  while (a > M_PI) a -= 2 * M_PI;
  while (a <= -M_PI) a += 2 * M_PI;
  return a;
}

// ---- vec3
int Vec3New(lua_State* L) {
  PushVec3(L, {Num(L, 1, "vec3"), Num(L, 2, "vec3"), Num(L, 3, "vec3")});
  return 1;
}

int Vec3Index(lua_State* L) {
  const Eigen::Vector3d& v = *ToVec3(L, 1);
  const char* key = luaL_checkstring(L, 2);
  if (key[0] && !key[1] && key[0] >= 'x' && key[0] <= 'z') {
    lua_pushnumber(L, v[key[0] - 'x']);
    return 1;
  }
  luaL_getmetatable(L, kVec3);
  lua_getfield(L, -1, key);
  if (lua_isnil(L, -1)) ScriptError(L, "vec3 has no field '%s' (x, y, z, norm, dot, cross, normalized)", key);
  return 1;
}

int Vec3Add(lua_State* L) {
  PushVec3(L, CheckVec3(L, 1, "vec3 +") + CheckVec3(L, 2, "vec3 +"));
  return 1;
}
int Vec3Sub(lua_State* L) {
  PushVec3(L, CheckVec3(L, 1, "vec3 -") - CheckVec3(L, 2, "vec3 -"));
  return 1;
}
int Vec3Unm(lua_State* L) {
  PushVec3(L, -CheckVec3(L, 1, "vec3 -"));
  return 1;
}
int Vec3Mul(lua_State* L) {
  if (lua_isnumber(L, 1)) {
    PushVec3(L, lua_tonumber(L, 1) * CheckVec3(L, 2, "vec3 *"));
  } else {
    PushVec3(L, CheckVec3(L, 1, "vec3 *") * Num(L, 2, "vec3 *"));
  }
  return 1;
}
int Vec3Div(lua_State* L) {
  PushVec3(L, CheckVec3(L, 1, "vec3 /") / Num(L, 2, "vec3 /"));
  return 1;
}
int Vec3Eq(lua_State* L) {
  const Eigen::Vector3d* a = ToVec3(L, 1);
  const Eigen::Vector3d* b = ToVec3(L, 2);
  lua_pushboolean(L, a && b && *a == *b);
  return 1;
}
int Vec3Norm(lua_State* L) {
  lua_pushnumber(L, CheckVec3(L, 1, "vec3:norm").norm());
  return 1;
}
int Vec3Dot(lua_State* L) {
  lua_pushnumber(L, CheckVec3(L, 1, "vec3:dot").dot(CheckVec3(L, 2, "vec3:dot")));
  return 1;
}
int Vec3Cross(lua_State* L) {
  PushVec3(L, CheckVec3(L, 1, "vec3:cross").cross(CheckVec3(L, 2, "vec3:cross")));
  return 1;
}
int Vec3Normalized(lua_State* L) {
  const Eigen::Vector3d& v = CheckVec3(L, 1, "vec3:normalized");
  if (v.norm() < 1e-12) ScriptError(L, "vec3:normalized: the vector is zero");
  PushVec3(L, v.normalized());
  return 1;
}
int Vec3String(lua_State* L) {
  lua_pushstring(L, ("vec3" + Triple(*ToVec3(L, 1))).c_str());
  return 1;
}

// ---- quat
int QuatNew(lua_State* L) {
  Eigen::Quaterniond q(Num(L, 1, "quat"), Num(L, 2, "quat"), Num(L, 3, "quat"), Num(L, 4, "quat"));
  if (q.norm() < 1e-9) ScriptError(L, "quat: (w, x, y, z) = 0 is not a rotation");
  PushQuat(L, q);
  return 1;
}
Eigen::Quaterniond& CheckQuat(lua_State* L, int i, const char* what) {
  Eigen::Quaterniond* q = ToQuat(L, i);
  if (!q) ScriptError(L, "%s: argument %d must be a quat, got %s", what, i, luaL_typename(L, i));
  return *q;
}
int QuatIndex(lua_State* L) {
  const Eigen::Quaterniond& q = *ToQuat(L, 1);
  const char* key = luaL_checkstring(L, 2);
  if (!std::strcmp(key, "w")) {
    lua_pushnumber(L, q.w());
    return 1;
  }
  if (!std::strcmp(key, "x")) {
    lua_pushnumber(L, q.x());
    return 1;
  }
  if (!std::strcmp(key, "y")) {
    lua_pushnumber(L, q.y());
    return 1;
  }
  if (!std::strcmp(key, "z")) {
    lua_pushnumber(L, q.z());
    return 1;
  }
  luaL_getmetatable(L, kQuat);
  lua_getfield(L, -1, key);
  if (lua_isnil(L, -1)) ScriptError(L, "quat has no field '%s' (w, x, y, z, inv, slerp, angle, rpy, euler)", key);
  return 1;
}
int QuatMul(lua_State* L) {
  const Eigen::Quaterniond& a = CheckQuat(L, 1, "quat *");
  if (const Eigen::Vector3d* v = ToVec3(L, 2)) {
    PushVec3(L, a * *v);
  } else {
    PushQuat(L, a * CheckQuat(L, 2, "quat *"));
  }
  return 1;
}
int QuatInv(lua_State* L) {
  PushQuat(L, CheckQuat(L, 1, "quat:inv").conjugate());
  return 1;
}
int QuatSlerp(lua_State* L) {
  const Eigen::Quaterniond& a = CheckQuat(L, 1, "quat:slerp");
  const Eigen::Quaterniond& b = CheckQuat(L, 2, "quat:slerp");
  PushQuat(L, a.slerp(Num(L, 3, "quat:slerp"), b));
  return 1;
}
int QuatAngle(lua_State* L) {  // angle to another rotation (or of this one), deg
  const Eigen::Quaterniond& a = CheckQuat(L, 1, "quat:angle");
  const Eigen::Quaterniond b = lua_isnoneornil(L, 2) ? Eigen::Quaterniond::Identity() : CheckQuat(L, 2, "quat:angle");
  lua_pushnumber(L, a.angularDistance(b) / kDeg);
  return 1;
}
int PushAngles(lua_State* L, const Eigen::Vector3d& a) {
  for (int i = 0; i < 3; ++i) lua_pushnumber(L, a[i] / kDeg);
  return 3;
}
int QuatRpy(lua_State* L) { return PushAngles(L, EulerAngles("xyz", CheckQuat(L, 1, "quat:rpy"))); }
int QuatEuler(lua_State* L) {
  const Eigen::Quaterniond& q = CheckQuat(L, 1, "quat:euler");
  const char* convention = luaL_checkstring(L, 2);
  Eigen::Vector3d angles;
  char error[256] = "";
  try {
    angles = EulerAngles(convention, q);
  } catch (const std::invalid_argument& e) {
    std::snprintf(error, sizeof error, "%s", e.what());
  }
  if (error[0]) ScriptError(L, "quat:euler: %s", error);
  return PushAngles(L, angles);
}
int QuatString(lua_State* L) {
  const Eigen::Quaterniond& q = *ToQuat(L, 1);
  {
    const std::string s = "quat(" + Fmt(q.w()) + ", " + Fmt(q.x()) + ", " + Fmt(q.y()) + ", " + Fmt(q.z()) + ")";
    lua_pushlstring(L, s.data(), s.size());
  }
  return 1;
}

// ---- frame
Frame Rotation(const Eigen::Quaterniond& q) {
  Frame f;
  f.q = q.normalized();
  return f;
}

int FrameNew(lua_State* L) {
  Frame f;
  const int n = lua_gettop(L);
  int i = 1;
  if (n >= 3 && lua_isnumber(L, 1)) {
    f.p = {Num(L, 1, "frame"), Num(L, 2, "frame"), Num(L, 3, "frame")};
    i = 4;
  } else if (n >= 1 && ToVec3(L, 1)) {
    f.p = *ToVec3(L, 1);
    i = 2;
  }
  if (i <= n) {
    if (const Eigen::Quaterniond* q = ToQuat(L, i)) {
      f.q = *q;
    } else if (const Frame* r = ToFrame(L, i)) {
      f.q = r->q;
    } else {
      ScriptError(L, "frame: argument %d must be a quat or a frame (its rotation), got %s", i, luaL_typename(L, i));
    }
    ++i;
  }
  if (i <= n) {
    ScriptError(L, "frame: expected (x, y, z [, rotation]), (vec3 [, rotation]) or (rotation), got %d arguments", n);
  }
  PushFrame(L, f);
  return 1;
}
int Trans(lua_State* L) {
  Frame f;
  f.p = {Num(L, 1, "trans"), Num(L, 2, "trans"), Num(L, 3, "trans")};
  PushFrame(L, f);
  return 1;
}
int Rpy(lua_State* L) {
  PushFrame(L,
            Rotation(EulerRotation("xyz", Num(L, 1, "rpy") * kDeg, Num(L, 2, "rpy") * kDeg, Num(L, 3, "rpy") * kDeg)));
  return 1;
}
int Euler(lua_State* L) {
  const char* convention = luaL_checkstring(L, 1);
  const double a = Num(L, 2, "euler") * kDeg, b = Num(L, 3, "euler") * kDeg, c = Num(L, 4, "euler") * kDeg;
  Frame f;
  char error[256] = "";
  try {
    f = Rotation(EulerRotation(convention, a, b, c));
  } catch (const std::invalid_argument& e) {
    std::snprintf(error, sizeof error, "%s", e.what());
  }
  if (error[0]) ScriptError(L, "euler: %s", error);
  PushFrame(L, f);
  return 1;
}
template <char A>
int RotAxis(lua_State* L) {
  const char name[] = {'r', 'o', 't', A, 0};
  PushFrame(L, Rotation(Eigen::Quaterniond(Eigen::AngleAxisd(Num(L, 1, name) * kDeg, Axis(A)))));
  return 1;
}
int AngleAxis(lua_State* L) {
  const double angle = Num(L, 1, "angleaxis") * kDeg;
  const Eigen::Vector3d& axis = CheckVec3(L, 2, "angleaxis");
  if (axis.norm() < 1e-12) ScriptError(L, "angleaxis: the axis is zero");
  PushFrame(L, Rotation(Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis.normalized()))));
  return 1;
}
int Rotm(lua_State* L) {
  luaL_checktype(L, 1, LUA_TTABLE);
  Eigen::Matrix3d R;
  for (int r = 0; r < 3; ++r) {
    if (lua_rawgeti(L, 1, r + 1) != LUA_TTABLE) ScriptError(L, "rotm: row %d must be a table of 3 numbers", r + 1);
    for (int c = 0; c < 3; ++c) {
      lua_rawgeti(L, -1, c + 1);
      if (!lua_isnumber(L, -1)) ScriptError(L, "rotm: element (%d, %d) must be a number", r + 1, c + 1);
      R(r, c) = lua_tonumber(L, -1);
      lua_pop(L, 1);
    }
    lua_pop(L, 1);
  }
  const double orth = (R * R.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (!(orth < 1e-6) || !(std::abs(R.determinant() - 1.0) < 1e-6)) {
    ScriptError(L, "rotm: not a rotation matrix (|R R^T - I| = %g, det = %g; tolerance 1e-6)", orth, R.determinant());
  }
  PushFrame(L, Rotation(Eigen::Quaterniond(R)));
  return 1;
}
int FrameIndex(lua_State* L) {
  const Frame& f = *ToFrame(L, 1);
  const char* key = luaL_checkstring(L, 2);
  if (!std::strcmp(key, "pos")) {
    PushVec3(L, f.p);
    return 1;
  }
  if (!std::strcmp(key, "rot")) {
    PushQuat(L, f.q);
    return 1;
  }
  if (key[0] >= 'x' && key[0] <= 'z' && !key[1]) {
    lua_pushnumber(L, f.p[key[0] - 'x']);
    return 1;
  }
  luaL_getmetatable(L, kFrame);
  lua_getfield(L, -1, key);
  if (lua_isnil(L, -1)) ScriptError(L, "frame has no field '%s' (pos, rot, x, y, z, inv, rpy, euler, matrix)", key);
  return 1;
}
int FrameMul(lua_State* L) {
  const Frame& a = CheckFrame(L, 1, "frame *");
  if (const Eigen::Vector3d* v = ToVec3(L, 2)) {
    PushVec3(L, a.p + a.q * *v);
    return 1;
  }
  const Frame& b = CheckFrame(L, 2, "frame *");
  Frame c;
  c.p = a.p + a.q * b.p;
  c.q = (a.q * b.q).normalized();
  PushFrame(L, c);
  return 1;
}
int FrameInv(lua_State* L) {
  const Frame& a = CheckFrame(L, 1, "frame:inv");
  Frame c;
  c.q = a.q.conjugate();
  c.p = -(c.q * a.p);
  PushFrame(L, c);
  return 1;
}
int FrameRpy(lua_State* L) { return PushAngles(L, EulerAngles("xyz", CheckFrame(L, 1, "frame:rpy").q)); }
int FrameEuler(lua_State* L) {
  const Frame& f = CheckFrame(L, 1, "frame:euler");
  const char* convention = luaL_checkstring(L, 2);
  Eigen::Vector3d angles;
  char error[256] = "";
  try {
    angles = EulerAngles(convention, f.q);
  } catch (const std::invalid_argument& e) {
    std::snprintf(error, sizeof error, "%s", e.what());
  }
  if (error[0]) ScriptError(L, "frame:euler: %s", error);
  return PushAngles(L, angles);
}
int FrameMatrix(lua_State* L) {  // rows of the rotation matrix, as rotm takes them
  const Eigen::Matrix3d R = CheckFrame(L, 1, "frame:matrix").q.toRotationMatrix();
  lua_createtable(L, 3, 0);
  for (int r = 0; r < 3; ++r) {
    lua_createtable(L, 3, 0);
    for (int c = 0; c < 3; ++c) {
      lua_pushnumber(L, R(r, c));
      lua_rawseti(L, -2, c + 1);
    }
    lua_rawseti(L, -2, r + 1);
  }
  return 1;
}
int FrameString(lua_State* L) {
  lua_pushstring(L, FormatFrame(*ToFrame(L, 1)).c_str());
  return 1;
}

void Metatable(lua_State* L, const char* type, const luaL_Reg* methods) {
  luaL_newmetatable(L, type);
  luaL_setfuncs(L, methods, 0);
  lua_pushstring(L, "locked");
  lua_setfield(L, -2, "__metatable");
  lua_pop(L, 1);
}

}  // namespace

Eigen::Quaterniond EulerRotation(const std::string& c, double a, double b, double g) {
  const bool upper = c.size() == 3 && std::isupper(static_cast<unsigned char>(c[0]));
  bool ok = c.size() == 3 && c[0] != c[1] && c[1] != c[2] && c[1] != 0;
  for (char ch : c) {
    const char l = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    ok = ok && (l == 'x' || l == 'y' || l == 'z') && (std::isupper(static_cast<unsigned char>(ch)) != 0) == upper;
  }
  if (!ok) {
    throw std::invalid_argument("unknown Euler convention '" + c +
                                "' (three of x, y, z, no two neighbours alike; upper case intrinsic, lower case "
                                "extrinsic: e.g. \"ZYZ\", \"ZYX\", \"xyz\")");
  }
  const Eigen::AngleAxisd r0(a, Axis(c[0])), r1(b, Axis(c[1])), r2(g, Axis(c[2]));
  // intrinsic: R = R0 R1 R2; extrinsic: each later rotation about the fixed axes: R = R2 R1 R0
  return upper ? Eigen::Quaterniond(r0 * r1 * r2) : Eigen::Quaterniond(r2 * r1 * r0);
}

Eigen::Vector3d EulerAngles(const std::string& c, const Eigen::Quaterniond& q) {
  EulerRotation(c, 0, 0, 0);  // validates
  const bool upper = std::isupper(static_cast<unsigned char>(c[0])) != 0;
  // an extrinsic sequence abc is the intrinsic sequence CBA with the angles reversed
  const std::string in = upper ? c : std::string{c[2], c[1], c[0]};
  auto index = [](char ch) { return std::tolower(static_cast<unsigned char>(ch)) - 'x'; };
  Eigen::Vector3d e = q.normalized().toRotationMatrix().eulerAngles(index(in[0]), index(in[1]), index(in[2]));
  // the other solution when the middle angle is outside the conventional range
  const bool proper = index(in[0]) == index(in[2]);
  const bool in_range = proper ? (e[1] >= 0 && e[1] <= M_PI) : (std::abs(e[1]) <= M_PI / 2);
  if (!in_range) e = {e[0] + M_PI, proper ? -e[1] : M_PI - e[1], e[2] + M_PI};
  e = {Wrap(e[0]), proper ? e[1] : Wrap(e[1]), Wrap(e[2])};
  return upper ? e : Eigen::Vector3d(e[2], e[1], e[0]);
}

std::string FormatFrame(const Frame& f) {
  const Eigen::Vector3d rpy = EulerAngles("xyz", f.q) / kDeg;
  return "frame(pos = " + Triple(f.p) + " m, rpy = " + Triple(rpy) + " deg)";
}

void PushVec3(lua_State* L, const Eigen::Vector3d& v) { *New<Eigen::Vector3d>(L, kVec3) = v; }
void PushQuat(lua_State* L, const Eigen::Quaterniond& q) { *New<Eigen::Quaterniond>(L, kQuat) = q.normalized(); }
void PushFrame(lua_State* L, const Frame& f) {
  Frame* out = New<Frame>(L, kFrame);
  out->p = f.p;
  out->q = f.q.normalized();
}
Eigen::Vector3d* ToVec3(lua_State* L, int i) { return static_cast<Eigen::Vector3d*>(luaL_testudata(L, i, kVec3)); }
Eigen::Quaterniond* ToQuat(lua_State* L, int i) {
  return static_cast<Eigen::Quaterniond*>(luaL_testudata(L, i, kQuat));
}
Frame* ToFrame(lua_State* L, int i) { return static_cast<Frame*>(luaL_testudata(L, i, kFrame)); }

const Frame& CheckFrame(lua_State* L, int i, const char* what) {
  const Frame* f = ToFrame(L, i);
  if (!f) ScriptError(L, "%s: argument %d must be a frame, got %s", what, i, luaL_typename(L, i));
  return *f;
}
const Eigen::Vector3d& CheckVec3(lua_State* L, int i, const char* what) {
  const Eigen::Vector3d* v = ToVec3(L, i);
  if (!v) ScriptError(L, "%s: argument %d must be a vec3, got %s", what, i, luaL_typename(L, i));
  return *v;
}

void OpenValues(lua_State* L) {
  static const luaL_Reg vec3[] = {{"__index", Vec3Index}, {"__add", Vec3Add},         {"__sub", Vec3Sub},
                                  {"__unm", Vec3Unm},     {"__mul", Vec3Mul},         {"__div", Vec3Div},
                                  {"__eq", Vec3Eq},       {"__tostring", Vec3String}, {"norm", Vec3Norm},
                                  {"dot", Vec3Dot},       {"cross", Vec3Cross},       {"normalized", Vec3Normalized},
                                  {nullptr, nullptr}};
  static const luaL_Reg quat[] = {{"__index", QuatIndex}, {"__mul", QuatMul},   {"__tostring", QuatString},
                                  {"inv", QuatInv},       {"slerp", QuatSlerp}, {"angle", QuatAngle},
                                  {"rpy", QuatRpy},       {"euler", QuatEuler}, {nullptr, nullptr}};
  static const luaL_Reg frame[] = {{"__index", FrameIndex}, {"__mul", FrameMul}, {"__tostring", FrameString},
                                   {"inv", FrameInv},       {"rpy", FrameRpy},   {"euler", FrameEuler},
                                   {"matrix", FrameMatrix}, {nullptr, nullptr}};
  Metatable(L, kVec3, vec3);
  Metatable(L, kQuat, quat);
  Metatable(L, kFrame, frame);
  static const luaL_Reg globals[] = {{"vec3", Vec3New},        {"quat", QuatNew},      {"frame", FrameNew},
                                     {"trans", Trans},         {"rpy", Rpy},           {"euler", Euler},
                                     {"rotx", RotAxis<'x'>},   {"roty", RotAxis<'y'>}, {"rotz", RotAxis<'z'>},
                                     {"angleaxis", AngleAxis}, {"rotm", Rotm},         {nullptr, nullptr}};
  lua_pushglobaltable(L);
  luaL_setfuncs(L, globals, 0);
  lua_pop(L, 1);
}

}  // namespace vlab::task
