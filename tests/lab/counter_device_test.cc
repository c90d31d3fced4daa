// Tests the speed counter (src/lab/devices/device_counter.cc) against closed
// forms on a free rotor (a hinge with no gravity, damping or friction):
//   - at constant spin ω the turns are floor(ω t / 2π) and every reading is
//     ω · 60 / 2π rpm, whatever the gate;
//   - under a constant torque τ on the rotor's inertia I (α = τ / I) a
//     gate-time counter reads the mean speed over its gate: with MuJoCo's
//     semi-implicit Euler step h the speed after step i is ω0 + i α h, so a gate
//     of N steps that starts at speed ω_s reads ω_s + α h (N + 1) / 2, i.e. the
//     speed half a gate before its end plus α h / 2;
//   - readings are held between gates and rounded to the resolution;
// then its scenario keys and its errors.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "bridge/bridge_layouts.h"
#include "core/core_errors.h"
#include "lab/devices/device_counter.h"
#include "lab/devices/device_kinds.h"
#include "lab/scenario/lab_scenario.h"
#include "mujoco_fixture.h"
#include "test_util.h"

namespace vlab::lab::counter_device_test {
namespace {

constexpr double kRpm = 60.0 / (2.0 * M_PI);  // rpm per rad/s
constexpr double kStep = 0.001;               // s, the model's timestep
constexpr double kInertia = 2e-5;             // kg m², the rotor about its axle

// the counter's state payload (docs/protocol.md)
constexpr int kRevolutions = bridge::StateIndex(bridge::DeviceKind::kCounter, "revolutions");
constexpr int kReading = bridge::StateIndex(bridge::DeviceKind::kCounter, "rpm");

// a rotor on a hinge about z, a torque motor on it, and a slide joint
constexpr const char* kXml = R"(
<mujoco>
  <option timestep="0.001" gravity="0 0 0" integrator="Euler"/>
  <worldbody>
    <body name="rotor">
      <joint name="spin" type="hinge" axis="0 0 1" damping="0" frictionloss="0"/>
      <inertial pos="0 0 0" mass="0.06" diaginertia="1e-5 1e-5 2e-5"/>
    </body>
    <body name="slider" pos="1 0 0">
      <joint name="slide" type="slide" axis="1 0 0"/>
      <inertial pos="0 0 0" mass="1" diaginertia="0.01 0.01 0.01"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="torque" joint="spin" gear="1"/>
  </actuator>
</mujoco>)";

DeviceConfig Counter(double rate_hz = 0, double resolution = 0, const std::string& joint = "spin") {
  DeviceConfig c;
  c.name = "rpm";
  c.kind = bridge::DeviceKind::kCounter;
  c.where = "test.yaml:1";
  CounterParams& p = c.EditParams<CounterParams>();
  p.joint = joint;
  p.rate_hz = rate_hz;
  p.resolution = resolution;
  return c;
}

class CounterTest : public test::MujocoTest {
 protected:
  // the rotor at `omega` rad/s under `torque` N m, the counter reset, control period `period`
  void Start(const DeviceConfig& c, double omega, double torque = 0, double period = 0.01) {
    m_ = LoadModelFromString("counter.xml", kXml);
    d_ = MakeData(m_);
    period_ = period;
    d_->qvel[0] = omega;
    d_->ctrl[0] = torque;
    mj_forward(m_, d_);
    counter_ = MakeDevice({m_, period, 1, "counter.xml"}, c);
    counter_->Reset(*d_);
  }
  // one control period; returns the state [revolutions, rpm] at its end
  std::vector<double> Period() {
    for (int i = 0; i < std::lround(period_ / kStep); ++i) mj_step(m_, d_);
    counter_->Sample(*d_, d_->time);
    std::vector<double> state;
    counter_->State(&state);
    return state;
  }

  mjModel* m_ = nullptr;
  mjData* d_ = nullptr;
  double period_ = 0.01;
  std::unique_ptr<Device> counter_;
};

TEST_F(CounterTest, ConstantSpinCountsTurnsAndReadsItsSpeed) {
  // 1990 rpm: 199/600 turn per period, so no period ends on a whole turn within 600 periods
  const double omega = 1990 / kRpm;
  Start(Counter(), omega);
  for (int k = 1; k <= 200; ++k) {
    const std::vector<double> s = Period();
    ASSERT_EQ(s.size(), 2u);
    EXPECT_EQ(s[kRevolutions], std::floor(k * 199.0 / 600.0)) << "period " << k;
    EXPECT_NEAR(s[kReading], 1990.0, 1e-6) << "period " << k;
  }
  // 1990 rpm for 2.01 s: 66.67 turns
  EXPECT_EQ(Period()[kRevolutions], 66.0);
}

TEST_F(CounterTest, BackwardsSpinCountsNegativeTurns) {
  Start(Counter(), -2 * M_PI);  // one turn per second, backwards
  std::vector<double> s = Period();
  EXPECT_EQ(s[kRevolutions], -1.0);  // 0.01 turn backwards is in turn -1
  EXPECT_NEAR(s[kReading], -60.0, 1e-6);
  for (int k = 0; k < 99; ++k) s = Period();
  EXPECT_NEAR(s[kRevolutions], -1.0, 1.0);  // exactly one turn: -1 or -2 by rounding of the angle
}

TEST_F(CounterTest, AGateReadsTheMeanSpeedOverItAndHoldsIt) {
  const double alpha = 0.02 / kInertia;  // rad/s² under 0.02 N m
  const double omega0 = 1000 / kRpm;
  Start(Counter(/*rate_hz=*/10), omega0, 0.02);  // gate 0.1 s = 10 periods = 100 steps
  double held = 0;
  for (int k = 1; k <= 50; ++k) {
    const std::vector<double> s = Period();
    if (k % 10 != 0) {
      EXPECT_EQ(s[kReading], held) << "period " << k << ": a reading is held until the next gate ends";
      continue;
    }
    const int n = 100;  // steps per gate
    const double gate_start_speed = omega0 + alpha * kStep * (k - 10) * 10;
    const double expected = (gate_start_speed + alpha * kStep * (n + 1) / 2.0) * kRpm;
    EXPECT_NEAR(s[kReading], expected, 1e-6 * expected) << "period " << k;
    // the speed half a gate ago, within α h / 2
    EXPECT_NEAR(s[kReading], (omega0 + alpha * (k * 0.01 - 0.05)) * kRpm, alpha * kStep * kRpm) << "period " << k;
    EXPECT_GT(s[kReading], held);
    held = s[kReading];
  }
}

TEST_F(CounterTest, ReadingsAreRoundedToTheResolution) {
  const double omega = 1234.0 / kRpm;
  Start(Counter(0, 10), omega);
  const std::vector<double> s = Period();
  EXPECT_DOUBLE_EQ(s[kReading], 1230.0);
  std::vector<std::string> expected{"rpm.revolutions", "rpm.rpm", "rpm.true_rpm"};
  EXPECT_EQ(counter_->Columns(), expected);
  std::vector<double> row(3);
  counter_->Row(*d_, row.data());
  EXPECT_DOUBLE_EQ(row[1], 1230.0);
  EXPECT_NEAR(row[2], 1234.0, 1e-9);  // ground truth, not rounded
}

TEST_F(CounterTest, BindingErrorsNameTheDeviceAndTheJoint) {
  m_ = LoadModelFromString("counter.xml", kXml);
  auto error = [&](const DeviceConfig& c, double period = 0.01) {
    try {
      MakeDevice({m_, period, 1, "counter.xml"}, c);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error(Counter(0, 0, "axle")), "test.yaml:1: device 'rpm': the scene has no joint 'axle'");
  EXPECT_EQ(error(Counter(0, 0, "slide")), "test.yaml:1: device 'rpm': joint 'slide' is not a hinge");
  EXPECT_NE(error(Counter(200)).find("rate 200 Hz is faster than the control rate (100 Hz)"), std::string::npos);
  EXPECT_EQ(error(Counter(100)), "no error");
}

TEST(CounterScenario, KeysAreReadAndCheckedByTheKindsReader) {
  vlab::testing::TempDir dir;
  vlab::testing::WriteFile(dir / "counter.xml", kXml);
  const std::string head = "scene: counter.xml\nduration: 0.1\ncontrol_period: 0.01\ndevices:\n";
  auto load = [&](const std::string& device) {
    vlab::testing::WriteFile(dir / "s.yaml", head + "  - " + device + "\n");
    return LoadScenario(dir / "s.yaml");
  };
  const Scenario s = load("{name: rpm, kind: counter, joint: spin, rate: 50, resolution: 10}");
  ASSERT_EQ(s.devices.size(), 1u);
  EXPECT_EQ(s.devices[0].kind, bridge::DeviceKind::kCounter);
  EXPECT_EQ(s.devices[0].ParamsAs<CounterParams>().joint, "spin");
  EXPECT_EQ(s.devices[0].ParamsAs<CounterParams>().rate_hz, 50);
  EXPECT_EQ(s.devices[0].ParamsAs<CounterParams>().resolution, 10);
  auto error = [&](const std::string& device) {
    try {
      load(device);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error("{name: rpm, kind: counter}").find("joint"), std::string::npos);
  EXPECT_NE(error("{name: rpm, kind: counter, joint: spin, rate: -1}").find("rate: must be >= 0 Hz"),
            std::string::npos);
  EXPECT_NE(error("{name: rpm, kind: counter, joint: spin, gate: 1}").find("gate: unknown key"), std::string::npos);
}

}  // namespace
}  // namespace vlab::lab::counter_device_test
