// Tests the feet device's support columns (src/lab/devices/device_sensors.cc with
// `pads` and `weight_of`) and the support polygon (src/lab/devices/support_polygon.cc)
// against closed forms:
//   - a block resting on four pads with its COM off centre: the FSR sum is its
//     weight m g, the centre of pressure is the COM's ground projection (moment
//     balance), its margin the distance from the COM to the nearest side of the
//     pads' rectangle;
//   - one pad raised off the floor: the support polygon is the triangle of the
//     three others, and the margin the distance to its diagonal;
//   - no pad in contact: no CoP (NaN), sum error -1;
//   - hulls and signed distances of squares, segments and points;
//   - bad configuration names the file, the line and the key.
// The wire state stays the sensor values; the support columns are log-only.
#include <cmath>
#include <functional>
#include <string>

#include <gtest/gtest.h>

#include "core/core_errors.h"
#include "core/core_mujoco.h"
#include "lab/devices/device_kinds.h"
#include "lab/devices/device_sensors.h"
#include "lab/devices/support_polygon.h"
#include "lab/run/lab_runner.h"
#include "mujoco_fixture.h"
#include "test_util.h"

namespace vlab::lab::feet_device_test {
namespace {

constexpr double kA = 0.10, kB = 0.08;  // pads at (+-kA, +-kB) from the block's origin, m
constexpr double kMass = 4.0, kG = 9.81;

// A 4 kg block on four massless pads (radius 10 mm, 50 mm below its origin), COM at
// (cx, cy) in the block frame; pad 4 (at +kA, -kB) raised by `raise` m.
std::string BlockXml(double cx, double cy, double raise = 0.0, double height = 0.0601) {
  const std::string c = std::to_string(cx) + " " + std::to_string(cy);
  const std::string z4 = std::to_string(-0.05 + raise);
  return R"(<mujoco>
  <option timestep="0.001" gravity="0 0 -9.81"/>
  <worldbody>
    <geom name="floor" type="plane" size="2 2 0.1"/>
    <body name="block" pos="0 0 )" +
         std::to_string(height) + R"(">
      <freejoint/>
      <inertial pos=")" +
         c + R"( 0" mass="4" diaginertia="0.02 0.02 0.03"/>
      <geom type="box" size="0.12 0.1 0.03" contype="0" conaffinity="0"/>
      <geom type="sphere" size="0.01" pos=" 0.1  0.08 -0.05"/>
      <geom type="sphere" size="0.01" pos="-0.1  0.08 -0.05"/>
      <geom type="sphere" size="0.01" pos="-0.1 -0.08 -0.05"/>
      <geom type="sphere" size="0.01" pos=" 0.1 -0.08 )" +
         z4 + R"("/>
      <site name="p1" type="sphere" size="0.015" pos=" 0.1  0.08 -0.05"/>
      <site name="p2" type="sphere" size="0.015" pos="-0.1  0.08 -0.05"/>
      <site name="p3" type="sphere" size="0.015" pos="-0.1 -0.08 -0.05"/>
      <site name="p4" type="sphere" size="0.015" pos=" 0.1 -0.08 )" +
         z4 + R"("/>
    </body>
  </worldbody>
  <sensor> <touch name="t1" site="p1"/> <touch name="t2" site="p2"/> <touch name="t3" site="p3"/> <touch name="t4" site="p4"/> </sensor>
</mujoco>)";
}

DeviceConfig FeetConfig() {
  DeviceConfig c;
  c.name = "feet";
  c.kind = bridge::DeviceKind::kFeet;
  c.where = "feet.yaml:3";
  c.EditParams<SensorParams>().sensors = {"t1", "t2", "t3", "t4"};
  c.EditParams<SensorParams>().pads = {"p1", "p2", "p3", "p4"};
  c.EditParams<SensorParams>().weight_of = "block";
  return c;
}

class FeetDeviceTest : public test::MujocoTest {
 protected:
  // Lets the block settle for `seconds`, samples the device, returns its log row.
  std::vector<double> SettledRow(const std::string& xml, double seconds = 2.0, std::vector<double>* state = nullptr) {
    mjModel* model = LoadModelFromString("block.xml", xml);
    mjData* data = MakeData(model);
    std::unique_ptr<Device> feet = MakeDevice({model, 0.002, 1, ""}, FeetConfig());
    for (int k = 0; k < std::lround(seconds / 0.001); ++k) mj_step(model, data);
    feet->Sample(*data, data->time);
    std::vector<double> row(feet->ColumnCount());
    feet->Row(*data, row.data());
    if (state) feet->State(state);
    return row;
  }
};

TEST_F(FeetDeviceTest, ColumnsAreLogOnlyAndTheWireKeepsTheSensorValues) {
  mjModel* model = LoadModelFromString("block.xml", BlockXml(0, 0));
  std::unique_ptr<Device> feet = MakeDevice({model, 0.002, 1, ""}, FeetConfig());
  EXPECT_EQ(feet->Columns(),
            (std::vector<std::string>{"feet.t1", "feet.t2", "feet.t3", "feet.t4", "feet.sum", "feet.sum_error",
                                      "feet.cop_x", "feet.cop_y", "feet.cop_margin"}));
  EXPECT_EQ(feet->ColumnCount(), 9);
  DeviceConfig weight_only = FeetConfig();
  weight_only.EditParams<SensorParams>().pads.clear();
  EXPECT_EQ(MakeDevice({model, 0.002, 1, ""}, weight_only)->ColumnCount(), 6);  // values, sum, sum_error
  DeviceConfig plain = FeetConfig();
  plain.EditParams<SensorParams>().pads.clear();
  plain.EditParams<SensorParams>().weight_of.clear();
  EXPECT_EQ(MakeDevice({model, 0.002, 1, ""}, plain)->ColumnCount(), 4);
  std::vector<double> state;
  SettledRow(BlockXml(0, 0), 0.5, &state);
  EXPECT_EQ(state.size(), 4u);
}

TEST_F(FeetDeviceTest, CopIsTheComProjectionOnFourPads) {
  const double cx = 0.03, cy = -0.02;
  const std::vector<double> row = SettledRow(BlockXml(cx, cy));
  EXPECT_NEAR(row[4], kMass * kG, 1e-3 * kMass * kG);  // sum = m g
  EXPECT_NEAR(row[5], 0.0, 1e-3);                      // sum error
  EXPECT_NEAR(row[6], cx, 2e-4);                       // CoP = COM projection
  EXPECT_NEAR(row[7], cy, 2e-4);
  // nearest side of the 0.2 x 0.16 m rectangle: min(kA -+ cx, kB -+ cy) = kB + cy
  EXPECT_NEAR(row[8], std::min({kA - cx, kA + cx, kB - cy, kB + cy}), 2e-4);
  EXPECT_NEAR(row[8], 0.06, 2e-4);
}

TEST_F(FeetDeviceTest, ARaisedPadLeavesATriangle) {
  const double cx = -0.03, cy = 0.03;
  const std::vector<double> row = SettledRow(BlockXml(cx, cy, 0.005));
  EXPECT_EQ(row[3], 0.0);  // pad 4 off the floor
  EXPECT_NEAR(row[4], kMass * kG, 1e-3 * kMass * kG);
  EXPECT_NEAR(row[6], cx, 2e-4);
  EXPECT_NEAR(row[7], cy, 2e-4);
  // triangle (kA, kB), (-kA, kB), (-kA, -kB): sides x = -kA, y = kB and the diagonal
  // through the origin, whose inward normal is (-kB, kA) / |(kA, kB)|
  const double diagonal = (kA * cy - kB * cx) / std::hypot(kA, kB);
  EXPECT_NEAR(row[8], std::min({cx + kA, kB - cy, diagonal}), 2e-4);
  EXPECT_NEAR(row[8], diagonal, 2e-4);  // the diagonal is the nearest side here
}

TEST_F(FeetDeviceTest, NoContactGivesNoCop) {
  const std::vector<double> row = SettledRow(BlockXml(0, 0, 0, 0.5), 0.01);  // still falling
  EXPECT_EQ(row[4], 0.0);
  EXPECT_EQ(row[5], -1.0);
  EXPECT_TRUE(std::isnan(row[6]) && std::isnan(row[7]) && std::isnan(row[8]));
}

TEST(SupportPolygonTest, HullAndSignedDistance) {
  // unit square with a point inside and one on an edge: four corners, counter-clockwise
  std::vector<Eigen::Vector2d> points = {{1, 1}, {0, 0}, {0.5, 0.5}, {1, 0}, {0, 1}, {0.5, 0}, {1, 1}};
  std::vector<Eigen::Vector2d> hull;
  ConvexHull(points, &hull);
  ASSERT_EQ(hull.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    const Eigen::Vector2d a = hull[i], b = hull[(i + 1) % 4], c = hull[(i + 2) % 4];
    EXPECT_GT((b - a).x() * (c - b).y() - (b - a).y() * (c - b).x(), 0);  // left turns
  }
  EXPECT_NEAR(SignedDistanceToHull(hull, {0.5, 0.5}), 0.5, 1e-15);
  EXPECT_NEAR(SignedDistanceToHull(hull, {0.2, 0.6}), 0.2, 1e-15);
  EXPECT_NEAR(SignedDistanceToHull(hull, {1.5, 0.5}), -0.5, 1e-15);         // beside an edge
  EXPECT_NEAR(SignedDistanceToHull(hull, {2, 2}), -std::sqrt(2.0), 1e-15);  // beyond a corner
  EXPECT_EQ(SignedDistanceToHull(hull, {1, 0.3}), 0.0);                     // on an edge
  // collinear points: a segment, which has no inside
  points = {{0, 0}, {2, 0}, {1, 0}};
  ConvexHull(points, &hull);
  ASSERT_EQ(hull.size(), 2u);
  EXPECT_NEAR(SignedDistanceToHull(hull, {1, 0.25}), -0.25, 1e-15);
  EXPECT_NEAR(SignedDistanceToHull(hull, {3, 0}), -1.0, 1e-15);
  EXPECT_EQ(SignedDistanceToHull(hull, {1.5, 0}), 0.0);
  points = {{1, 1}, {1, 1}};
  ConvexHull(points, &hull);
  ASSERT_EQ(hull.size(), 1u);
  EXPECT_NEAR(SignedDistanceToHull(hull, {4, 5}), -5.0, 1e-15);
  points.clear();
  ConvexHull(points, &hull);
  EXPECT_TRUE(std::isnan(SignedDistanceToHull(hull, {0, 0})));
}

// A scenario's feet device end to end: keys, log columns and checks on them.
class FeetScenarioTest : public ::testing::Test {
 protected:
  void SetUp() override { vlab::testing::WriteFile(dir_ / "block.xml", BlockXml(0.03, -0.02)); }
  // line 4 is the feet device's
  std::string Write(const std::string& device, const std::string& checks = "") {
    vlab::testing::WriteFile(dir_ / "feet.yaml", "scene: block.xml\nduration: 1.0\ndevices:\n  - " + device + "\n" +
                                                     (checks.empty() ? "" : "checks:\n" + checks));
    return dir_ / "feet.yaml";
  }
  static std::string Error(const std::function<void()>& f) {
    try {
      f();
    } catch (const InputError& e) {
      return e.what();
    }
    return "no error";
  }
  vlab::testing::TempDir dir_;
};

TEST_F(FeetScenarioTest, RunsWithChecksOnTheSupportColumns) {
  const std::string file =
      Write("{name: feet, kind: feet, sensors: [t1, t2, t3, t4], pads: [p1, p2, p3, p4], weight_of: block}",
            "  - {name: weight, signal: feet.sum_error, reduce: max_abs, max: 0.002, from: 0.5}\n"
            "  - {name: margin, signal: feet.cop_margin, reduce: final, min: 0.0598, max: 0.0602}\n");
  std::unique_ptr<Lab> lab = Lab::Create(LoadScenario(file));
  const RunResult r = lab->Run(RunOptions{});
  EXPECT_EQ(r.exit_code, 0) << r.failure;
}

TEST_F(FeetScenarioTest, BadKeysNameTheFileLineAndKey) {
  const std::string feet = "{name: feet, kind: feet, sensors: [t1, t2, t3, t4], ";
  std::string e = Error([&] { LoadScenario(Write(feet + "pads: [p1, p2, p3]}")); });
  EXPECT_NE(e.find("feet.yaml:4: devices[0].pads: needs one site per sensor (4)"), std::string::npos) << e;
  e = Error([&] { LoadScenario(Write(feet + "contact_threshold: -1}")); });
  EXPECT_NE(e.find("feet.yaml:4: devices[0].contact_threshold"), std::string::npos) << e;
  e = Error([&] { LoadScenario(Write("{name: imu, kind: imu, sensors: [t1], pads: [p1]}")); });
  EXPECT_NE(e.find("feet.yaml:4: devices[0].pads: unknown key"), std::string::npos) << e;
  e = Error([&] { Lab::Create(LoadScenario(Write(feet + "pads: [p1, p2, nope, p4]}"))); });
  EXPECT_NE(e.find("feet.yaml:4: device 'feet': pads: the scene has no site 'nope'"), std::string::npos) << e;
  e = Error([&] { Lab::Create(LoadScenario(Write(feet + "weight_of: robot}"))); });
  EXPECT_NE(e.find("feet.yaml:4: device 'feet': weight_of: the scene has no body 'robot'"), std::string::npos) << e;
}

}  // namespace
}  // namespace vlab::lab::feet_device_test
