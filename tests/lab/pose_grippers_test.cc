// The pose device's lab-only contact truth (device_pose.cc, key `grippers`): NAME.holders
// counts the grippers two of whose fingers (the child bodies of the gripper's body) touch the
// tracked site's body; NAME.free_time is how long that body has touched nothing. Two fixed
// "grippers" around a 50 mm cube: A's fingers on its +-y faces (0.5 mm into them), B's taller
// ones on its +-x faces; the cube is put where it touches both, one, only one finger of A, or
// nothing, and on the floor.
#include <gtest/gtest.h>

#include "core/core_errors.h"
#include "core/core_mujoco.h"
#include "lab/devices/device_kinds.h"
#include "lab/devices/device_pose.h"
#include "mujoco_fixture.h"

namespace vlab::lab::pose_grippers_test {
namespace {

constexpr const char* kXml = R"(
<mujoco>
  <option timestep="0.001"/>
  <worldbody>
    <geom name="floor" type="plane" size="2 2 0.1"/>
    <body name="cube" pos="0 0 1">
      <freejoint/>
      <geom type="box" size="0.025 0.025 0.025" mass="0.09"/>
      <site name="cube"/>
    </body>
    <body name="hand_a" pos="0 0 1">
      <body name="a_left" pos="0 0.0295 0"><geom type="box" size="0.01 0.005 0.01" mass="0.1"/></body>
      <body name="a_right" pos="0 -0.0295 0"><geom type="box" size="0.01 0.005 0.01" mass="0.1"/></body>
    </body>
    <body name="hand_b" pos="0 0 1.02">
      <body name="b_front" pos="0.0295 0 0"><geom type="box" size="0.005 0.01 0.03" mass="0.1"/></body>
      <body name="b_back" pos="-0.0295 0 0"><geom type="box" size="0.005 0.01 0.03" mass="0.1"/></body>
    </body>
    <body name="one_finger" pos="3 0 1">
      <body name="lonely" pos="0 0 0"><geom type="box" size="0.01 0.01 0.01" mass="0.1"/></body>
    </body>
  </worldbody>
</mujoco>)";

DeviceConfig Pose(std::vector<std::string> grippers) {
  DeviceConfig c;
  c.name = "cube";
  c.kind = bridge::DeviceKind::kPose;
  c.where = "test.yaml:1";
  PoseParams& p = c.EditParams<PoseParams>();
  p.site = "cube";
  p.grippers = std::move(grippers);
  return c;
}

class PoseGrippersTest : public test::MujocoTest {
 protected:
  void SetUp() override {
    m_ = LoadModelFromString("grippers.xml", kXml);
    d_ = MakeData(m_);
    device_ = MakeDevice({m_, 0.01, 1, "grippers.xml"}, Pose({"hand_a", "hand_b"}));
    mj_forward(m_, d_);
    device_->Reset(*d_);
  }
  // the cube's centre at (x, y, z); then the period's sample at time t: {holders, free_time}
  std::pair<double, double> At(double x, double y, double z, double t) {
    d_->qpos[0] = x, d_->qpos[1] = y, d_->qpos[2] = z;
    mj_forward(m_, d_);
    device_->Sample(*d_, t);
    std::vector<double> row(device_->ColumnCount());
    device_->Row(*d_, row.data());
    return {row[row.size() - 2], row.back()};
  }
  mjModel* m_ = nullptr;
  mjData* d_ = nullptr;
  std::unique_ptr<Device> device_;
};

TEST_F(PoseGrippersTest, Columns) {
  const std::vector<std::string> columns = device_->Columns();
  ASSERT_EQ(columns.size(), 7u);
  EXPECT_EQ(columns[5], "cube.holders");
  EXPECT_EQ(columns[6], "cube.free_time");
  EXPECT_EQ(device_->ColumnCount(), 7);
}

TEST_F(PoseGrippersTest, CountsTheGrippersThatHoldIt) {
  EXPECT_EQ(At(0, 0, 1, 0.01), std::make_pair(2.0, 0.0));       // between both pairs of fingers
  EXPECT_EQ(At(0, 0, 1.06, 0.02), std::make_pair(1.0, 0.0));    // above A's fingers: B's alone
  EXPECT_EQ(At(0, 0.003, 1, 0.03), std::make_pair(1.0, 0.0));   // 3 mm to +y: A's left finger only
  EXPECT_EQ(At(0, 0, 0.0249, 0.04), std::make_pair(0.0, 0.0));  // on the floor: held by none, touching
}

TEST_F(PoseGrippersTest, FreeTimeIsHowLongItTouchedNothing) {
  EXPECT_EQ(At(0, 0, 1, 0.01).second, 0.0);
  // in the air: the time since the last sample that saw it touch (t = 0.01 s)
  EXPECT_DOUBLE_EQ(At(0, 0, 1.5, 0.02).second, 0.01);
  EXPECT_DOUBLE_EQ(At(0, 0, 1.4, 0.30).second, 0.29);
  EXPECT_EQ(At(0, 0, 0.0249, 0.31).second, 0.0);  // landed
  EXPECT_DOUBLE_EQ(At(0, 0, 0.5, 0.35).second, 0.04);
}

TEST_F(PoseGrippersTest, AGripperNeedsTwoFingers) {
  try {
    MakeDevice({m_, 0.01, 1, "grippers.xml"}, Pose({"hand_a", "one_finger"}));
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("grippers: body 'one_finger' has 1 child bodies; a gripper needs two fingers"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(MakeDevice({m_, 0.01, 1, "grippers.xml"}, Pose({"no_such_body"})), InputError);
}

}  // namespace
}  // namespace vlab::lab::pose_grippers_test
