// Tests `vlab view --arm` (src/view/view_program.cc): the view of a robot
// that is not simulated by the lab. vlab-kinsim serves a PA10 arm device
// holding a pose (no commands); vlab view subscribes to it and computes the
// poses of scenes/pa10.xml's bodies from its joint states by MuJoCo
// kinematics, at --rate 20. A WebSocket client of the page checks that
//   - every frame carries each body's pose equal, as float32, to the pose
//     mj_kinematics gives here for the arm's joint angles (read from the arm
//     device itself);
//   - frames are 1 / 20 s apart in the arm's time, up to one of its periods
//     (100 Hz: a frame is the first state at or after its time);
//   - with --plot ARM.q.S1,ARM.q.E1, the /plot channel's samples carry the
//     arm's joint angles as the device sends them (float64, exactly), at the
//     same rate.
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include "bridge/bridge_client.h"
#include "scene/scene_geometry.h"
#include "test_process.h"
#include "view_clients.h"

namespace vlab {
namespace {

using testing::TestProcess;

int PortOf(const std::string& line, const std::string& label) {
  const std::size_t at = line.find(label);
  const std::size_t colon = at == std::string::npos ? at : line.find(':', at + label.size());
  return colon == std::string::npos ? 0 : std::atoi(line.c_str() + colon + 1);
}

TEST(ArmViewTest, PosesFromAnArmDevicesJointStatesByKinematics) {
  TestProcess kinsim(
      {VLAB_BINARY_DIR "/vlab-kinsim", "--port", "0", "--rate", "100", "--initial", "0.3,0.5,-0.2,1.0,0.4,1.2,-0.6"});
  const int arm_port = PortOf(kinsim.start_line(), " on 127.0.0.1");
  ASSERT_GT(arm_port, 0) << kinsim.start_line();
  const std::string arm = "127.0.0.1:" + std::to_string(arm_port);
  // the arm's joint angles, from the device
  bridge::Arm client = bridge::Arm::Connect("127.0.0.1", arm_port, 5.0);
  const bridge::Arm::State state = client.Read(5.0);
  const std::string plots = client.name() + ".q.S1," + client.name() + ".q.E1";
  TestProcess view({VLAB_BINARY_DIR "/vlab", "view", "--arm", arm, "--model", "scenes/pa10.xml", "--rate", "20",
                    "--plot", plots, "--http", "0", "-q"});
  const int http_port = PortOf(view.start_line(), "http://127.0.0.1");
  ASSERT_GT(http_port, 0) << view.start_line() << view.output();
  // the bodies' poses by kinematics, here
  char error[1000] = "";
  mjModel* m = mj_loadXML(VLAB_SOURCE_DIR "/scenes/pa10.xml", nullptr, error, sizeof(error));
  ASSERT_NE(m, nullptr) << error;
  mjData* d = mj_makeData(m);
  for (int i = 0; i < client.joints(); ++i) {
    d->qpos[m->jnt_qposadr[mj_name2id(m, mjOBJ_JOINT, client.joint_names()[i].c_str())]] = state.q[i];
  }
  mj_kinematics(m, d);
  const std::vector<int> bodies = scene::SceneBodies(m);
  std::vector<double> want(7 * bodies.size());
  scene::ScenePoses(*d, bodies, want.data());
  mj_deleteData(d);
  mj_deleteModel(m);

  view::view_test::WsClient ws(http_port, view::view_test::ViewerOptions("/ws"));
  std::vector<double> times;
  for (int k = 0; k < 6; ++k) {
    const std::string f = ws.Read();
    ASSERT_EQ(f.size(), 16 + 28 * bodies.size());
    double t = 0;
    std::memcpy(&t, f.data(), 8);
    times.push_back(t);
    for (std::size_t i = 0; i < want.size(); ++i) {
      float v = 0;
      std::memcpy(&v, f.data() + 16 + 4 * i, 4);
      ASSERT_EQ(v, static_cast<float>(want[i])) << "body " << i / 7 << " value " << i % 7;
    }
  }
  for (std::size_t k = 2; k < times.size(); ++k) {  // the first may be a newest-wins leftover
    EXPECT_GE(times[k] - times[k - 1], 0.05 - 1e-9);
    EXPECT_LE(times[k] - times[k - 1], 0.05 + 0.01 + 1e-9);
  }

  // the plot channel: S1 and E1 as the arm sends them
  view::view_test::WsClient plot(http_port, view::view_test::ViewerOptions("/plot"));
  std::vector<double> plot_times;
  for (int k = 0; k < 5; ++k) {
    const std::string p = plot.Read();
    ASSERT_EQ(p.size(), 32u);
    double v[4];
    std::memcpy(v, p.data(), 32);
    plot_times.push_back(v[0]);
    EXPECT_EQ(v[2], state.q[0]) << "S1";
    EXPECT_EQ(v[3], state.q[3]) << "E1";
  }
  for (std::size_t k = 2; k < plot_times.size(); ++k) {
    EXPECT_GE(plot_times[k] - plot_times[k - 1], 0.05 - 1e-9);
    EXPECT_LE(plot_times[k] - plot_times[k - 1], 0.05 + 0.01 + 1e-9);
  }
  view.Stop();
  kinsim.Stop();
}

}  // namespace
}  // namespace vlab
