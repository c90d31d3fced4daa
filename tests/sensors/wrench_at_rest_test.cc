// JR3 model fed by MuJoCo force/torque sensors: a known tool at rest must read m g and r x m g.
#include <cmath>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <Eigen/Geometry>

#include "mujoco_fixture.h"
#include "sensors/sensor_wrench.h"

namespace vlab::sensors {
namespace {

constexpr double kGravity = 9.81;
constexpr double kToolMass = 1.5;                   // kg
const Eigen::Vector3d kToolCom(0.02, 0.01, -0.03);  // m, in the sensor (site) frame

// sensor body welded to the world with orientation axis-angle (axis, degrees); the tool is
// welded below it, its frame = the site frame, so its inertial pos is the COM offset r
std::string SceneXml(const Eigen::Vector3d& axis, double angle_deg) {
  std::ostringstream xml;
  xml << "<mujoco model='jr3_at_rest'>\n"
      << "  <option timestep='0.001' gravity='0 0 " << -kGravity << "'/>\n"
      << "  <worldbody>\n"
      << "    <body name='jr3_body' pos='0 0 1' axisangle='" << axis.x() << " " << axis.y() << " " << axis.z() << " "
      << angle_deg << "'>\n"
      << "      <geom type='cylinder' size='0.0335 0.0125' mass='0.17'/>\n"
      << "      <body name='tool' pos='0 0 -0.0125'>\n"
      << "        <site name='jr3'/>\n"
      << "        <inertial pos='" << kToolCom.x() << " " << kToolCom.y() << " " << kToolCom.z() << "' mass='"
      << kToolMass << "' diaginertia='0.004 0.003 0.002'/>\n"
      << "      </body>\n"
      << "    </body>\n"
      << "  </worldbody>\n"
      << "  <sensor>\n"
      << "    <force name='jr3_force' site='jr3'/>\n"
      << "    <torque name='jr3_torque' site='jr3'/>\n"
      << "  </sensor>\n"
      << "</mujoco>\n";
  return xml.str();
}

class WrenchSensorAtRestTest : public vlab::test::MujocoTest {
 protected:
  void CheckAtRest(const Eigen::Vector3d& axis, double angle_deg);
};

// Steps the scene 1 s at 1 ms, feeding the negated MuJoCo sensor values to the JR3 model with
// the default noise, bias and quantisation, and compares filter4 with the analytic load.
void WrenchSensorAtRestTest::CheckAtRest(const Eigen::Vector3d& axis, double angle_deg) {
  SCOPED_TRACE("sensor orientation: axis (" + std::to_string(axis.x()) + ", " + std::to_string(axis.y()) + ", " +
               std::to_string(axis.z()) + ") angle " + std::to_string(angle_deg) + " deg");
  const mjModel* model = LoadModelFromString("jr3_at_rest.xml", SceneXml(axis, angle_deg));
  mjData* data = MakeData(model);
  const int force_adr = model->sensor_adr[mj_name2id(model, mjOBJ_SENSOR, "jr3_force")];
  const int torque_adr = model->sensor_adr[mj_name2id(model, mjOBJ_SENSOR, "jr3_torque")];

  WrenchSensorConfig config;  // 67M25A, filter 4, noise + bias + quantisation on
  config.seed = 7;
  const auto sensor = WrenchSensorModel::Create(config);
  WrenchSensorState state;
  Reset(*sensor, state);
  WrenchReading reading;
  for (int step = 0; step < 1000; ++step) {
    mj_step(model, data);
    const Wrench load = LoadFromMujocoSensor(data->sensordata + force_adr, data->sensordata + torque_adr);
    reading = Update(*sensor, state, load, model->opt.timestep);
    ASSERT_EQ(reading.status, WrenchStatus::kOk);
  }
  EXPECT_FALSE(state.saturated_latched);

  // analytic load on the sensor: F = m g expressed in the sensor frame, M = r x F
  const Eigen::Matrix3d R_world_sensor =
      Eigen::AngleAxisd(angle_deg * 3.14159265358979323846 / 180.0, axis.normalized()).toRotationMatrix();
  const Eigen::Vector3d f_sensor_N = R_world_sensor.transpose() * Eigen::Vector3d(0.0, 0.0, -kToolMass * kGravity);
  const Eigen::Vector3d m_sensor_Nm = kToolCom.cross(f_sensor_N);
  Wrench expected;
  expected << f_sensor_N, m_sensor_Nm;

  // Bound per axis: the bias is N(0, bias_sigma) -> 4 sigma; filter4 noise is white noise
  // through a 2-pole Butterworth of noise bandwidth 1.111 fc4 = 8.68 Hz sampled at 8 kHz,
  // sigma4 = sigma0 sqrt(2 * 8.68 / 8000), times 1.2 for the earlier stages' aliasing -> 5
  // sigma; plus one lsb for the reported count rounding and the settled filter.
  const double noise_ratio = 1.2 * std::sqrt(2.0 * 1.1107 * 7.8125 / 8000.0);
  const Wrench bound = 4.0 * sensor->bias_sigma() + 5.0 * noise_ratio * sensor->noise_sigma() + sensor->lsb();
  for (int i = 0; i < 6; ++i) {
    EXPECT_NEAR(reading.wrench[i], expected[i], bound[i]) << "axis " << i;
  }
  EXPECT_EQ(reading.filter, 4);
}

TEST_F(WrenchSensorAtRestTest, ReadsToolWeightSensorZUp) { CheckAtRest(Eigen::Vector3d::UnitZ(), 0.0); }

TEST_F(WrenchSensorAtRestTest, ReadsToolWeightSensorRotated90AboutX) { CheckAtRest(Eigen::Vector3d::UnitX(), 90.0); }

TEST_F(WrenchSensorAtRestTest, ReadsToolWeightSensorTilted) { CheckAtRest(Eigen::Vector3d(1.0, 2.0, 0.5), 130.0); }

}  // namespace
}  // namespace vlab::sensors
