// The task language's value types: constructors against each other and
// against Eigen, composition, inverse, printing, and errors naming the line.
#include <cmath>
#include <string>

#include <gtest/gtest.h>
#include <lua.hpp>

#include "task/task_sandbox.h"
#include "task/task_units.h"
#include "task/task_values.h"

namespace vlab::task {
namespace {

class ValuesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    L_ = luaL_newstate();
    OpenSandbox(L_, &config_);
    OpenValues(L_);
  }
  void TearDown() override { lua_close(L_); }
  // runs `code` as the chunk "@values.lua"; returns "" or the error message
  std::string Run(const std::string& code) {
    if (luaL_loadbuffer(L_, code.data(), code.size(), "@values.lua") != LUA_OK || lua_pcall(L_, 0, 1, 0) != LUA_OK) {
      std::string e = lua_tostring(L_, -1);
      lua_pop(L_, 1);
      return e;
    }
    return "";
  }
  Frame ResultFrame() {
    const Frame* f = ToFrame(L_, -1);
    EXPECT_NE(f, nullptr);
    Frame out = f ? *f : Frame();
    lua_pop(L_, 1);
    return out;
  }
  SandboxConfig config_;
  lua_State* L_ = nullptr;
};

Eigen::Quaterniond Rot(char axis, double deg) {
  const Eigen::Vector3d a = axis == 'x'   ? Eigen::Vector3d::UnitX()
                            : axis == 'y' ? Eigen::Vector3d::UnitY()
                                          : Eigen::Vector3d::UnitZ();
  return Eigen::Quaterniond(Eigen::AngleAxisd(deg * kDeg, a));
}

TEST_F(ValuesTest, RpyIsFixedXyzAndMatchesEigen) {
  ASSERT_EQ(Run("return rpy(30, -20, 75)"), "");
  const Frame f = ResultFrame();
  // R = Rz(yaw) Ry(pitch) Rx(roll), the scenario files' rpy_deg
  const Eigen::Quaterniond want = Rot('z', 75) * Rot('y', -20) * Rot('x', 30);
  EXPECT_LT(f.q.angularDistance(want), 1e-12);
  // the same rotation as the intrinsic ZYX sequence (yaw, pitch, roll) and the extrinsic xyz one
  ASSERT_EQ(Run("return rpy(30, -20, 75) * euler('ZYX', 75, -20, 30):inv()"), "");
  EXPECT_LT(ResultFrame().q.angularDistance(Eigen::Quaterniond::Identity()), 1e-12);
  ASSERT_EQ(Run("return rpy(30, -20, 75) * euler('xyz', 30, -20, 75):inv()"), "");
  EXPECT_LT(ResultFrame().q.angularDistance(Eigen::Quaterniond::Identity()), 1e-12);
}

// all 12 conventions: intrinsic = product of axis rotations left to right,
// extrinsic = right to left; the angles read back give the same rotation
TEST_F(ValuesTest, EveryEulerConventionAgainstEigenAndBack) {
  const char* conventions[] = {"XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX", "XYX", "XZX", "YXY", "YZY", "ZXZ", "ZYZ"};
  const double a = 25, b = 50, c = -110;
  for (const char* upper : conventions) {
    std::string lower = upper;
    for (char& ch : lower) ch = static_cast<char>(std::tolower(ch));
    const Eigen::Quaterniond intrinsic =
        Rot(std::tolower(upper[0]), a) * Rot(std::tolower(upper[1]), b) * Rot(std::tolower(upper[2]), c);
    const Eigen::Quaterniond extrinsic =
        Rot(std::tolower(upper[2]), c) * Rot(std::tolower(upper[1]), b) * Rot(std::tolower(upper[0]), a);
    EXPECT_LT(EulerRotation(upper, a * kDeg, b * kDeg, c * kDeg).angularDistance(intrinsic), 1e-12) << upper;
    EXPECT_LT(EulerRotation(lower, a * kDeg, b * kDeg, c * kDeg).angularDistance(extrinsic), 1e-12) << lower;
    for (const std::string& conv : {std::string(upper), lower}) {
      const Eigen::Quaterniond q = EulerRotation(conv, a * kDeg, b * kDeg, c * kDeg);
      const Eigen::Vector3d e = EulerAngles(conv, q);
      EXPECT_LT(EulerRotation(conv, e[0], e[1], e[2]).angularDistance(q), 1e-9) << conv;
      // the middle angle in its conventional range
      const bool proper = conv[0] == conv[2];
      if (proper) {
        EXPECT_GE(e[1], 0) << conv;
      } else {
        EXPECT_LE(std::abs(e[1]), M_PI / 2 + 1e-12) << conv;
      }
    }
    // from the script, against Eigen's own angles of the same matrix
    const Eigen::Vector3d eigen = intrinsic.toRotationMatrix().eulerAngles(
        std::tolower(upper[0]) - 'x', std::tolower(upper[1]) - 'x', std::tolower(upper[2]) - 'x');
    ASSERT_EQ(Run(std::string("return euler('") + upper + "', " + std::to_string(eigen[0] / kDeg) + ", " +
                  std::to_string(eigen[1] / kDeg) + ", " + std::to_string(eigen[2] / kDeg) + ")"),
              "");
    EXPECT_LT(ResultFrame().q.angularDistance(intrinsic), 1e-6) << upper;  // angles printed to 1e-6 deg
  }
}

TEST_F(ValuesTest, QuatRotmAngleaxisAndRpyAgree) {
  // 90 deg about z, four ways
  ASSERT_EQ(Run("local a = frame(quat(math.sqrt(0.5), 0, 0, math.sqrt(0.5)))\n"
                "local b = rotm{{0, -1, 0}, {1, 0, 0}, {0, 0, 1}}\n"
                "local c = angleaxis(90, vec3(0, 0, 2))\n"
                "local d = rpy(0, 0, 90)\n"
                "assert(a.rot:angle(b.rot) < 1e-9 and a.rot:angle(c.rot) < 1e-9 and a.rot:angle(d.rot) < 1e-9)\n"
                "return rotz(90)"),
            "");
  EXPECT_LT(ResultFrame().q.angularDistance(Rot('z', 90)), 1e-12);
}

TEST_F(ValuesTest, ComposeInverseAndTransformMatchEigenIsometry) {
  ASSERT_EQ(Run("A = frame(0.1, -0.2, 0.3) * rpy(10, 20, 30)\n"
                "B = trans(0.5, 0, 0) * euler('ZYZ', 40, 50, 60)\n"
                "return A * B:inv()"),
            "");
  const Frame ab = ResultFrame();
  Eigen::Isometry3d A = Eigen::Isometry3d::Identity(), B = Eigen::Isometry3d::Identity();
  A.translate(Eigen::Vector3d(0.1, -0.2, 0.3)).rotate(Rot('z', 30) * Rot('y', 20) * Rot('x', 10));
  B.translate(Eigen::Vector3d(0.5, 0, 0)).rotate(Rot('z', 40) * Rot('y', 50) * Rot('z', 60));
  const Eigen::Isometry3d want = A * B.inverse();
  EXPECT_LT((ab.p - want.translation()).norm(), 1e-12);
  EXPECT_LT(ab.q.angularDistance(Eigen::Quaterniond(want.rotation())), 1e-12);
  ASSERT_EQ(Run("local p = A * vec3(1, 2, 3)\nreturn trans(p.x, p.y, p.z)"), "");
  EXPECT_LT((ResultFrame().p - A * Eigen::Vector3d(1, 2, 3)).norm(), 1e-12);
  ASSERT_EQ(Run("return A * A:inv()"), "");
  const Frame id = ResultFrame();
  EXPECT_LT(id.p.norm(), 1e-15);
  EXPECT_LT(id.q.angularDistance(Eigen::Quaterniond::Identity()), 1e-12);
}

TEST_F(ValuesTest, PrintingIsReadable) {
  ASSERT_EQ(Run("return tostring(frame(0.5, 0, 0.4) * rpy(180, 0, 90))"), "");
  // rpy of a half turn about x: roll 180 or -180, printed as Eigen's range gives it
  const std::string s = lua_tostring(L_, -1);
  lua_pop(L_, 1);
  EXPECT_EQ(s, "frame(pos = (0.5, 0, 0.4) m, rpy = (180, 0, 90) deg)");
  ASSERT_EQ(Run("return tostring(vec3(1, -2.5, 1e-3)) .. ' ' .. tostring(quat(1, 0, 0, 0))"), "");
  EXPECT_STREQ(lua_tostring(L_, -1), "vec3(1, -2.5, 0.001) quat(1, 0, 0, 0)");
  lua_pop(L_, 1);
}

TEST_F(ValuesTest, BadInputNamesTheLine) {
  EXPECT_EQ(Run("local ok = 1\nreturn rotm{{1, 0, 0}, {0, 2, 0}, {0, 0, 1}}"),
            "values.lua:2: rotm: not a rotation matrix (|R R^T - I| = 3, det = 2; tolerance 1e-6)");
  EXPECT_NE(Run("return euler('XXY', 1, 2, 3)").find("values.lua:1: euler: unknown Euler convention 'XXY'"),
            std::string::npos);
  EXPECT_EQ(Run("\n\nreturn frame(1, 2, 3) * 5"), "values.lua:3: frame *: argument 2 must be a frame, got number");
  EXPECT_EQ(Run("return vec3(1, 2)"), "values.lua:1: vec3: argument 3 must be a number, got no value");
}

}  // namespace
}  // namespace vlab::task
