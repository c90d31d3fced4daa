// Tests bridge/bridge_layouts.cc: the table of wire layouts. The describe
// layouts are compared with the lists the devices sent before the table
// existed, written out here by hand: the table must not change a byte on the
// wire. The page (docs/protocol.md) is checked by protocol_doc_test.cc.
#include "bridge/bridge_layouts.h"

#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bridge/bridge_yoyo.h"

namespace vlab::bridge::layouts_test {
namespace {

using nlohmann::json;

// compile-time indices of fixed layouts
static_assert(StateIndex(DeviceKind::kGripper, "grasped") == 4);
static_assert(CommandIndex(DeviceKind::kBase, "wz") == 3);
static_assert(StateIndex(DeviceKind::kArm, "status") == 0);
static_assert(StateIndex(DeviceKind::kArm, "q") == 1, "the first group starts at a fixed index");
static_assert(StateIndex(DeviceKind::kYoyo, "string_force") == 5);
static_assert(ValueCount(LayoutOf(DeviceKind::kArm).state, 7) == 22);
static_assert(FindKindLayout("pose")->kind == DeviceKind::kPose);
static_assert(FindKindLayout(0) == nullptr && FindKindLayout(kMaxDeviceKind + 1) == nullptr);

std::string ThrownBy(void (*f)()) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(nothing thrown)";
}

TEST(LayoutsTest, KindNamesAndCodesGoBothWays) {
  // the published codes: a kind's code never changes
  const char* names[] = {"arm",   "wrench", "sim",  "camera", "markers", "base",  "gripper", "feet", "imu",
                         "point", "yoyo",   "gaze", "pose",   "counter", "scene", "word",    "tool"};
  for (int kind = 1; kind <= static_cast<int>(std::size(names)); ++kind) {
    EXPECT_STREQ(KindName(kind), names[kind - 1]);
    EXPECT_EQ(KindFromName(names[kind - 1]), kind);
  }
  // every kind of the table, published or new, goes both ways
  for (int kind = 1; kind <= kMaxDeviceKind; ++kind) EXPECT_EQ(KindFromName(KindName(kind)), kind) << kind;
  EXPECT_STREQ(KindName(0), "unknown");
  EXPECT_STREQ(KindName(kMaxDeviceKind + 1), "unknown");
  EXPECT_EQ(KindFromName("unknown"), 0);
  EXPECT_EQ(KindFromName("Arm"), 0);
  EXPECT_EQ(KindFromName(""), 0);
}

TEST(LayoutsTest, UnknownOrUnfixedFieldsThrowNamingTheKindAndField) {
  EXPECT_EQ(ThrownBy([] { StateIndex(DeviceKind::kGripper, "grip"); }), "gripper: no state field 'grip'");
  EXPECT_EQ(ThrownBy([] { CommandIndex(DeviceKind::kYoyo, "x"); }), "yoyo: no command field 'x'");
  EXPECT_NE(ThrownBy([] { StateIndex(DeviceKind::kArm, "qd"); }).find("arm: state field 'qd' has no fixed index"),
            std::string::npos);
  EXPECT_EQ(
      ThrownBy([] { LayoutOf(static_cast<DeviceKind>(kMaxDeviceKind + 1)); }),
      "device kind " + std::to_string(kMaxDeviceKind + 1) + " is not one of 1.." + std::to_string(kMaxDeviceKind));
  EXPECT_EQ(StateLength(DeviceKind::kPose), 7);
  EXPECT_EQ(CommandLength(DeviceKind::kWrench), 0);
  EXPECT_NE(ThrownBy([] { StateLength(DeviceKind::kFeet); }).find("feet: the state length depends on the device"),
            std::string::npos);
  EXPECT_NE(ThrownBy([] { StateLength(DeviceKind::kCamera); }).find("camera: not a float64 layout"), std::string::npos);
}

// what each device kind's describe reply said before the table
TEST(LayoutsTest, DescribeLayoutsAreTheOnesOnTheWire) {
  const json none = json::array();
  const std::vector<std::pair<DeviceKind, json>> fixed = {
      {DeviceKind::kWrench,
       {{"state", {"Fx", "Fy", "Fz", "Mx", "My", "Mz", "filter", "saturated"}}, {"command", none}}},
      {DeviceKind::kSim,
       {{"state",
         {"sim_time", "mode", "clock", "periods", "refused_packets", "missed_deadlines", "realtime_factor",
          "max_lateness"}},
        {"command", {"op", "arg"}}}},
      {DeviceKind::kBase,
       {{"state", {"status", "x", "y", "yaw", "vx", "vy", "wz"}}, {"command", {"frame", "vx", "vy", "wz"}}}},
      {DeviceKind::kGripper,
       {{"state", {"status", "opening", "opening_velocity", "force", "grasped"}}, {"command", {"mode", "value"}}}},
      {DeviceKind::kPoint, {{"state", {"status", "x", "y", "z", "vx", "vy", "vz"}}, {"command", {"x", "y", "z"}}}},
      {DeviceKind::kYoyo, {{"state", {"status", "x", "y", "z", "vz", "string_force", "spin"}}, {"command", none}}},
      {DeviceKind::kGaze, {{"state", {"error_deg", "u", "v", "visible"}}, {"command", none}}},
      {DeviceKind::kPose, {{"state", {"x", "y", "z", "qw", "qx", "qy", "qz"}}, {"command", none}}},
  };
  for (const auto& [kind, layout] : fixed) EXPECT_EQ(LayoutJson(kind), layout) << KindName(static_cast<int>(kind));
  EXPECT_EQ(LayoutJson(DeviceKind::kArm, 7),
            json({{"state", {"status", "q[7]", "qd[7]", "tau[7]"}}, {"command", {"mode", "value[7]"}}}));
  EXPECT_EQ(LayoutJson(DeviceKind::kArm, 1).dump(),
            R"({"command":["mode","value[1]"],"state":["status","q[1]","qd[1]","tau[1]"]})");
  const std::vector<std::string> imu = {"gyro.x", "gyro.y", "gyro.z", "accel.x", "accel.y", "accel.z"};
  EXPECT_EQ(LayoutJson(DeviceKind::kImu, imu), json({{"state", imu}, {"command", none}}));
  const std::vector<std::string> feet = {"rf_fr", "rf_fl"};
  EXPECT_EQ(LayoutJson(DeviceKind::kFeet, feet).dump(), R"({"command":[],"state":["rf_fr","rf_fl"]})");
}

TEST(LayoutsTest, LayoutJsonRefusesTheWrongOverload) {
  EXPECT_NE(ThrownBy([] { LayoutJson(DeviceKind::kArm); })
                .find("arm: the layout depends on the device; give its "
                      "joint count"),
            std::string::npos);
  EXPECT_NE(ThrownBy([] { LayoutJson(DeviceKind::kFeet); }).find("give its sensor value names"), std::string::npos);
  EXPECT_EQ(ThrownBy([] { LayoutJson(DeviceKind::kArm, 0); }), "arm: 0 joints");
  EXPECT_EQ(ThrownBy([] { LayoutJson(DeviceKind::kBase, 3); }), "base: no per-joint layout");
  EXPECT_EQ(ThrownBy([] { LayoutJson(DeviceKind::kArm, std::vector<std::string>{"a"}); }), "arm: no per-sensor layout");
  EXPECT_EQ(ThrownBy([] { LayoutJson(DeviceKind::kImu, std::vector<std::string>{}); }), "imu: no sensor values");
  EXPECT_NE(ThrownBy([] { LayoutJson(DeviceKind::kMarkers); }).find("markers: not a float64 layout"),
            std::string::npos);
}

TEST(LayoutsTest, TheYoyoNameArraysAreTheTables) {
  const json point = LayoutJson(DeviceKind::kPoint), yoyo = LayoutJson(DeviceKind::kYoyo);
  EXPECT_EQ(json(kPointStateLayout), point["state"]);
  EXPECT_EQ(json(kPointCommandLayout), point["command"]);
  EXPECT_EQ(json(kYoyoStateLayout), yoyo["state"]);
}

TEST(LayoutsTest, EveryFloat64KindHasAStateAndEveryFieldAUnitString) {
  for (const KindLayout& k : kKindLayouts) {
    EXPECT_EQ(k.float64, !k.state.empty()) << k.name;
    for (FieldList fields : {k.state, k.command}) {
      for (const LayoutField& f : fields) {
        EXPECT_NE(f.unit, nullptr) << k.name << "." << f.name;
        EXPECT_NE(std::string(f.meaning), "") << k.name << "." << f.name;
      }
    }
  }
}

}  // namespace
}  // namespace vlab::bridge::layouts_test
