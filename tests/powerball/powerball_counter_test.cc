// The counter device's PowerBall truth columns (`powerball: true`, device_counter.cc):
// the names, the values against the closed forms of a rolling rotor, and the error on a
// scene without a ball.
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/core_errors.h"
#include "lab/run/lab_runner.h"
#include "lab/scenario/lab_scenario.h"
#include "test_util.h"

namespace vlab::lab {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::string Scenario(const std::string& scene, const std::string& extra) {
  return "scene: " + scene + "\nduration: 0.2\ncontrol_period: 0.001\nclock: fast\n" + extra +
         "devices:\n  - {name: pb, kind: counter, joint: pb_spin, rate: 10, resolution: 10, powerball: true}\n";
}

std::vector<std::string> Split(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream in(line);
  for (std::string field; std::getline(in, field, ',');) fields.push_back(field);
  return fields;
}

// the gimbal scene's keyframe: the rotor rolling at 2,000 rpm, shell free (no torque on the
// gimbal). After 0.2 s: spin 2,000 rpm, nu = (r/R) omega = 9.308 rad/s, slip 0.0015 (the
// tilted ring's share), couple I_s omega nu = 0.0390 N m (mjcf/powerball/README.md)
TEST(PowerballCounter, LogsTheBallsTruthBesideTheReading) {
  vlab::testing::TempDir dir;
  vlab::testing::WriteFile(
      dir / "s.yaml",
      Scenario(std::string(VLAB_SOURCE_DIR) + "/mjcf/powerball/powerball_gimbal.xml", "keyframe: spin2000\n"));
  std::unique_ptr<Lab> lab = Lab::Create(LoadScenario(dir / "s.yaml"));
  RunOptions options;
  options.out_dir = dir / "out";
  lab->Run(options);
  std::stringstream log(vlab::testing::ReadFile(dir / "out/log.csv"));
  std::string header, row, last;
  std::getline(log, header);
  while (std::getline(log, row)) last = row;
  const std::vector<std::string> names = Split(header);
  const std::vector<std::string> values = Split(last);
  ASSERT_EQ(names.size(), values.size());
  auto column = [&](const std::string& name) -> double {
    for (size_t i = 0; i < names.size(); ++i) {
      if (names[i] == name) return std::stod(values[i]);
    }
    ADD_FAILURE() << "no column " << name << " in " << header;
    return NAN;
  };
  const double omega = 2000.0 * 2.0 * kPi / 60.0, nu = omega * 0.0012 / 0.027;
  EXPECT_NEAR(column("pb.spin_rpm"), 2000.0, 0.01 * 2000.0);
  EXPECT_NEAR(column("pb.rpm"), 2000.0, 0.01 * 2000.0 + 10.0);  // + the 10 rpm resolution
  EXPECT_NEAR(column("pb.precess_rate"), nu, 0.01 * nu);
  EXPECT_LT(column("pb.slip"), 0.01);
  EXPECT_NEAR(column("pb.moment"), 2e-5 * omega * nu, 0.05 * 2e-5 * omega * nu);
}

TEST(PowerballCounter, ASceneWithoutABallIsAnErrorNamingTheDevice) {
  vlab::testing::TempDir dir;
  vlab::testing::WriteFile(dir / "spin.xml", R"(<mujoco><option timestep="0.001"/><worldbody><body name="rotor">
    <joint name="pb_spin" type="hinge" axis="0 0 1"/><geom type="cylinder" size="0.05 0.01" mass="1"/>
    </body></worldbody></mujoco>)");
  vlab::testing::WriteFile(dir / "s.yaml", Scenario("spin.xml", ""));
  try {
    Lab::Create(LoadScenario(dir / "s.yaml"));
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("device 'pb'"), std::string::npos) << what;
    EXPECT_NE(what.find("pb_shell"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace vlab::lab
