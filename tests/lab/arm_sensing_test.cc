// What the arm's drive senses (arm_sensing.h, the arm key `sensing`): positions
// in whole counts of the encoder resolution, velocities exact or the backward
// difference of the counts; on a slow ramp the sensed position steps by exactly
// one count and stays within half a count of the true one, and the difference's
// mean and standard deviation are the closed form's; the PD, the state and the
// log use the sensed values; bad keys are InputErrors naming the field.
#include "lab/devices/arm_sensing.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "arm_keys_error.h"
#include "core/core_errors.h"
#include "lab/devices/arm_servo_model.h"
#include "lab/devices/device_arm.h"
#include "lab/scenario/lab_scenario.h"
#include "mujoco_fixture.h"
#include "test_util.h"

namespace vlab::lab::arm_sensing_test {
namespace {

constexpr double kStep = 0.001;    // s: the PA10 scene's timestep
constexpr double kPeriod = 0.010;  // s: the control period (10 steps)
// the PA10's joint resolution: 360° / 819200 counts (mjcf/pa10/README.md)
const double kResolution = 2.0 * M_PI / 819200.0;
const std::vector<std::string> kJoints = {"S1", "S2", "S3", "E1", "E2", "W1", "W2"};

// the closed form of the backward difference at a constant speed v: (d/T) sqrt(f (1 - f))
double DifferenceSd(double v, double step, double d) {
  const double counts = v * step / d;
  const double f = counts - std::floor(counts);
  return d / step * std::sqrt(f * (1.0 - f));
}

struct Stats {
  double mean = 0, sd = 0;
};
Stats MeanSd(const std::vector<double>& x) {
  Stats s;
  for (double v : x) s.mean += v;
  s.mean /= static_cast<double>(x.size());
  for (double v : x) s.sd += (v - s.mean) * (v - s.mean);
  s.sd = std::sqrt(s.sd / static_cast<double>(x.size()));
  return s;
}

TEST(JointSensingTest, ExactRampGivesTheClosedForm) {
  // an exact ramp of 0.37 counts per step: the difference takes 0 or 1 count per step
  JointSensing sensing;
  SensingConfig config;
  config.resolution = {1e-4};
  config.velocity = SensingConfig::Velocity::kDifference;
  sensing.Configure(config, 1);
  const double v = 0.37 * 1e-4 / kStep;
  double q = 0.123, qd = v;
  sensing.Sense(&q, &qd, 0.0);
  EXPECT_EQ(sensing.qd()[0], 0.0);  // the first reading has no difference
  std::vector<double> velocities;
  for (int k = 1; k <= 20000; ++k) {
    q = 0.123 + v * k * kStep;
    sensing.Sense(&q, &qd, kStep);
    const double counts = sensing.qd()[0] * kStep / 1e-4;
    EXPECT_TRUE(std::abs(counts) < 1e-9 || std::abs(counts - 1) < 1e-9) << counts;
    EXPECT_LE(std::abs(sensing.q()[0] - q), 0.5e-4 + 1e-15);
    velocities.push_back(sensing.qd()[0]);
  }
  const Stats s = MeanSd(velocities);
  EXPECT_NEAR(s.mean, v, 1e-3 * v);
  EXPECT_NEAR(s.sd, DifferenceSd(v, kStep, 1e-4), 1e-3 * s.sd);
  EXPECT_NEAR(DifferenceSd(v, kStep, 1e-4), 0.1 * std::sqrt(0.37 * 0.63), 1e-12);
}

TEST(JointSensingTest, RoundsToTheNearestCount) {
  JointSensing sensing;
  SensingConfig config;
  config.resolution = {0.5, 2.0};
  sensing.Configure(config, 2);
  const double q[2] = {0.74, -2.9}, qd[2] = {1.5, -0.25};
  sensing.Sense(q, qd, kStep);
  EXPECT_EQ(sensing.q()[0], 0.5);   // 1.48 counts -> 1
  EXPECT_EQ(sensing.q()[1], -2.0);  // -1.45 counts -> -1
  EXPECT_EQ(sensing.qd()[0], 1.5);  // velocity: model, exact
  EXPECT_EQ(sensing.qd()[1], -0.25);
}

class ArmSensingTest : public test::MujocoTest {
 protected:
  void SetUp() override { model_ = LoadModel("scenes/pa10.xml"); }
  void Start(const SensingConfig& sensing) {
    DeviceConfig c;
    c.name = "pa10";
    c.where = "arm.yaml:9";
    auto& p = c.EditParams<ArmParams>();
    p.joints = p.actuators = kJoints;
    p.initial = {0, 0.523599, 0, 1.047198, 0, 1.570796, 0};  // ready: tool down
    p.sensing = sensing;
    p.servo.feedforward = feedforward_;
    arm_ = SimArm::Create({model_, kPeriod, 1, "pa10.xml"}, c);
    data_ = MakeData(model_);
    arm_->SetInitialState(*data_);
    mj_forward(model_, data_);
    arm_->Start(*data_);
    w2_ = model_->jnt_qposadr[mj_name2id(model_, mjOBJ_JOINT, "W2")];
  }
  // one physics step as the lab's run loop makes it
  void Step() {
    mj_step1(model_, data_);
    arm_->Actuate(*data_, kStep);
    mj_step2(model_, data_);
  }
  mjModel* model_ = nullptr;
  mjData* data_ = nullptr;
  std::unique_ptr<SimArm> arm_;
  ServoConfig::Feedforward feedforward_ = ServoConfig::Feedforward::kWorld;
  int w2_ = 0;
};

TEST_F(ArmSensingTest, SlowRampStepsByOneCountAndDifferencesMatchTheClosedForm) {
  SensingConfig sensing;
  sensing.resolution = {kResolution};
  sensing.velocity = SensingConfig::Velocity::kDifference;
  Start(sensing);
  // W2 in velocity mode at 3.3 counts per control period (0.33 per step), the others held
  const double v = 3.3 * kResolution / kPeriod;
  bridge::ArmCommand command;
  command.mode = bridge::ArmMode::kVelocity;
  command.value = Eigen::VectorXd::Zero(7);
  command.value[6] = v;
  ASSERT_TRUE(arm_->Command(command));
  std::vector<double> velocities;
  std::int64_t last = 0;
  double worst_error = 0;
  const int settle = 1000, steps = 6000;
  for (int k = 0; k < steps; ++k) {
    Step();
    if (k < settle) continue;
    // Actuate sensed the state before this step: compare with the true q then
    const double sensed = arm_->sensing().q()[6];
    const double counts = sensed / kResolution;
    ASSERT_NEAR(counts, std::round(counts), 1e-6) << "not a whole count at step " << k;
    const std::int64_t count = std::llround(counts);
    if (k > settle) {
      EXPECT_TRUE(count == last || count == last + 1) << "step " << k << ": " << last << " -> " << count;
    }
    last = count;
    velocities.push_back(arm_->sensing().qd()[6]);
    const double diff_counts = arm_->sensing().qd()[6] * kStep / kResolution;
    EXPECT_TRUE(std::abs(diff_counts) < 1e-6 || std::abs(diff_counts - 1) < 1e-6) << diff_counts;
    // the state the next Actuate will sense, read between steps as the lab's sample does
    arm_->Sample(*data_, data_->time);
    const double truth = data_->qpos[w2_];
    worst_error = std::max(worst_error, std::abs(arm_->state().q[6] - truth));
  }
  EXPECT_LE(worst_error, 0.5 * kResolution * (1 + 1e-9));
  EXPECT_GT(worst_error, 0.3 * kResolution);  // the quantisation is there
  const Stats s = MeanSd(velocities);
  EXPECT_NEAR(s.mean, v, 1e-3 * v);
  const double closed = DifferenceSd(v, kStep, kResolution);  // (d/T) sqrt(0.33 * 0.67)
  EXPECT_NEAR(s.sd, closed, 1e-3 * closed) << "mean " << s.mean << " v " << v;
  // the difference's noise is far above the speed itself: 0.47 d/T against 0.33 d/T
  EXPECT_GT(closed, v);
}

TEST_F(ArmSensingTest, StateAndLogReportTheSensedValues) {
  SensingConfig sensing;
  sensing.resolution = {1e-3};  // coarse: the rounding is plain to see
  Start(sensing);
  for (int k = 0; k < 50; ++k) Step();
  arm_->Sample(*data_, data_->time);
  std::vector<double> row(arm_->ColumnCount());
  arm_->Row(*data_, row.data());
  for (int i = 0; i < 7; ++i) {
    const int adr = model_->jnt_qposadr[mj_name2id(model_, mjOBJ_JOINT, kJoints[i].c_str())];
    const double expected = std::round(data_->qpos[adr] / 1e-3) * 1e-3;
    EXPECT_DOUBLE_EQ(arm_->state().q[i], expected);
    EXPECT_DOUBLE_EQ(row[i], expected);
    EXPECT_EQ(arm_->state().qd[i],
              data_->qvel[model_->jnt_dofadr[mj_name2id(model_, mjOBJ_JOINT, kJoints[i].c_str())]]);
    EXPECT_EQ(row[7 + i], arm_->state().qd[i]);
  }
  EXPECT_NE(arm_->state().q[1], data_->qpos[model_->jnt_qposadr[1]]);  // S2 at 0.523599: not a whole mrad
  // the describe reply tells a client the counts' size, one per joint
  const auto describe = nlohmann::json::parse(arm_->DescribeJson(bridge::DeviceDescription{}));
  EXPECT_EQ(describe.at("resolution"), std::vector<double>(7, 1e-3));
}

// The servo's own model runs at the joint state the drive reads, as a real controller's
// does: with coarse counts (0.02 rad) the first torque of a held arm at rest is the model's
// bias at the counted angles, not at the true ones (S2's gravity torque differs by about
// its gradient times the rounding).
TEST_F(ArmSensingTest, TheModelFeedForwardRunsAtTheCountedAngles) {
  SensingConfig sensing;
  sensing.resolution = {0.02};
  sensing.velocity = SensingConfig::Velocity::kModel;
  feedforward_ = ServoConfig::Feedforward::kModel;
  Start(sensing);
  Step();
  arm_->Sample(*data_, data_->time);
  std::vector<int> joint_ids;
  for (const std::string& j : kJoints) joint_ids.push_back(mj_name2id(model_, mjOBJ_JOINT, j.c_str()));
  std::unique_ptr<ArmServoModel> own = ArmServoModel::Create(*model_, joint_ids, {});
  own->Place(*data_);
  std::vector<double> counted(7), zero(7, 0.0), at_counts(7), at_truth(7);
  mjData* start = MakeData(model_);
  arm_->SetInitialState(*start);
  for (int i = 0; i < 7; ++i) counted[i] = std::round(start->qpos[joint_ids[i]] / 0.02) * 0.02;
  own->Bias(counted.data(), zero.data(), at_counts.data());
  mj_forward(model_, start);
  own->Bias(*start, at_truth.data());
  for (int i = 0; i < 7; ++i) {
    // at rest on its first reading: no position or velocity error, the feed-forward alone
    EXPECT_NEAR(arm_->state().tau[i], at_counts[i], 1e-9) << kJoints[i];
  }
  EXPECT_GT(std::abs(at_counts[1] - at_truth[1]), 0.05);  // S2: rounded by 0.0036 rad
}

TEST_F(ArmSensingTest, NoKeyIsExact) {
  Start({});
  EXPECT_FALSE(arm_->sensing().enabled());
  for (int k = 0; k < 50; ++k) Step();
  arm_->Sample(*data_, data_->time);
  std::vector<double> row(arm_->ColumnCount());
  arm_->Row(*data_, row.data());
  EXPECT_EQ(row[6], data_->qpos[w2_]);
  EXPECT_EQ(arm_->state().q[6], data_->qpos[w2_]);
  EXPECT_FALSE(nlohmann::json::parse(arm_->DescribeJson(bridge::DeviceDescription{})).contains("resolution"));
}

TEST(ArmSensingKeysTest, GoodKeysLoad) {
  EXPECT_EQ(ArmKeysError("    sensing: {resolution: 7.67e-6}\n"), "");
  EXPECT_EQ(ArmKeysError("    sensing: {resolution: [1e-5, 2e-5], velocity: difference}\n"), "");
  EXPECT_EQ(ArmKeysError("    sensing: {resolution: [1e-5], velocity: model}\n"), "");
}

TEST(ArmSensingKeysTest, BadKeysNameTheDeviceAndField) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"    sensing: {resolution: 0}\n", "devices[0].sensing.resolution: values must be > 0"},
      {"    sensing: {resolution: [1e-5, -1e-5]}\n", "devices[0].sensing.resolution: values must be > 0"},
      {"    sensing: {resolution: [1e-5, 1e-5, 1e-5]}\n",
       "devices[0].sensing.resolution: needs one value or one per joint (2), got 3"},
      {"    sensing: {resolution: []}\n", "devices[0].sensing.resolution: needs one value or one per joint"},
      {"    sensing: {resolution: .nan}\n", "devices[0].sensing.resolution: expected a finite number"},
      {"    sensing: {resolution: [1e-5, .nan]}\n", "devices[0].sensing.resolution[1]: expected a finite number"},
      {"    sensing: {resolution: fine}\n", "devices[0].sensing.resolution: expected a finite number"},
      {"    sensing: {velocity: difference}\n", "devices[0].sensing.resolution: required"},
      {"    sensing: {resolution: 1e-5, velocity: filtered}\n",
       "devices[0].sensing.velocity: must be model or difference, got 'filtered'"},
      {"    sensing: {resolution: 1e-5, velocty: model}\n", "devices[0].sensing.velocty: unknown key"},
      {"    sensing: 1e-5\n", "devices[0].sensing: expected a mapping"},
  };
  for (const auto& [keys, expected] : cases) {
    const std::string e = ArmKeysError(keys);
    EXPECT_NE(e.find(expected), std::string::npos) << keys << " -> " << e;
    EXPECT_NE(e.find("s.yaml:"), std::string::npos) << e;
  }
}

}  // namespace
}  // namespace vlab::lab::arm_sensing_test
