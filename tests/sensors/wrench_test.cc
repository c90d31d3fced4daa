// Tests for sensors/sensor_wrench: config validation, ADC, timing, determinism, input checks.
#include "sensors/sensor_wrench.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "sensors/wrench_reference.h"

namespace vlab::sensors {
namespace {

using wrench_testing::QuietConfig;

// expects Create to throw std::invalid_argument with `fragment` in the message
void ExpectConfigError(const WrenchSensorConfig& config, const std::string& fragment) {
  try {
    WrenchSensorModel::Create(config);
    FAIL() << "no exception, expected one naming: " << fragment;
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find(fragment), std::string::npos)
        << "message: " << error.what() << "\nexpected fragment: " << fragment;
  }
}

TEST(WrenchSensorConfigTest, RejectsBadFieldsNamingThem) {
  WrenchSensorConfig config;
  config.filter = 9;
  ExpectConfigError(config, "filter 9 out of range 0..6");
  config.filter = -1;
  ExpectConfigError(config, "filter -1 out of range 0..6");

  config = WrenchSensorConfig{};
  Wrench full_scale;
  full_scale << 100, 100, 0, 5, 5, 5;
  config.full_scale = full_scale;
  ExpectConfigError(config, "full_scale[2] must be > 0");
  (*config.full_scale)[2] = std::nan("");
  ExpectConfigError(config, "full_scale[2] must be > 0");

  config = WrenchSensorConfig{};
  config.model = "99X12Q";
  ExpectConfigError(config, "unknown model '99X12Q'");

  config = WrenchSensorConfig{};
  config.noise_sigma = Wrench::Constant(0.1);
  (*config.noise_sigma)[4] = -1.0;
  ExpectConfigError(config, "noise_sigma[4]");
  config = WrenchSensorConfig{};
  config.bias_sigma = Wrench::Constant(std::nan(""));
  ExpectConfigError(config, "bias_sigma[0]");

  config = WrenchSensorConfig{};
  config.sample_rate_hz = 0.0;
  ExpectConfigError(config, "sample_rate_hz");
}

TEST(WrenchSensorConfigTest, ResolvesDefaultsPerModel) {
  Wrench expected_67;
  expected_67 << 100, 100, 200, 5, 5, 5;
  const auto model = WrenchSensorModel::Create(WrenchSensorConfig{});
  EXPECT_EQ(model->full_scale(), expected_67);
  EXPECT_EQ(model->lsb(), expected_67 / 16384.0);
  EXPECT_EQ(model->noise_sigma(), expected_67 * 0.002);
  EXPECT_EQ(model->bias_sigma(), expected_67 * 0.0005);

  WrenchSensorConfig config;
  config.model = "85M35A";
  EXPECT_EQ(WrenchSensorModel::Create(config)->full_scale()[2], 800.0);
  config.model = "50M31A";
  EXPECT_EQ(WrenchSensorModel::Create(config)->full_scale()[3], 6.0);

  // an unknown name is a custom sensor when the full scale is given
  config.model = "custom";
  config.full_scale = Wrench::Constant(7.0);
  EXPECT_EQ(WrenchSensorModel::Create(config)->full_scale(), Wrench::Constant(7.0));

  // the stated cut-offs and rates
  const double cutoffs[] = {500.0, 125.0, 31.25, 7.8125, 1.953125, 0.48828125};
  for (int k = 1; k <= 6; ++k) {
    EXPECT_DOUBLE_EQ(model->stage(k).cutoff_hz, cutoffs[k - 1]) << "stage " << k;
    EXPECT_DOUBLE_EQ(model->stage(k).rate_hz, 8000.0 / std::pow(4.0, k - 1)) << "stage " << k;
  }
}

TEST(WrenchSensorTest, QuantisesFilter0ToFullScaleOver16384) {
  WrenchSensorConfig config = QuietConfig();
  config.enable_quantization = true;
  const auto model = WrenchSensorModel::Create(config);
  WrenchSensorState state;
  Reset(*model, state);
  Wrench input;
  input << 12.3456, -7.891, 150.0013, 0.1234, -4.99991, 2.5e-4;
  const WrenchReading reading = Update(*model, state, input, 0.001);
  EXPECT_EQ(reading.samples, 8u);
  EXPECT_FALSE(reading.saturated);
  const Wrench& fs = model->full_scale();
  for (int i = 0; i < 6; ++i) {
    const double expected = std::round(input[i] * 16384.0 / fs[i]) * fs[i] / 16384.0;
    EXPECT_EQ(reading.all_filters[0][i], expected) << "axis " << i;
  }
}

TEST(WrenchSensorTest, ClipsAndFlagsSaturationBeyondAdcRange) {
  WrenchSensorConfig config = QuietConfig();
  config.enable_quantization = true;
  const auto model = WrenchSensorModel::Create(config);
  const Wrench lsb = model->full_scale() / 16384.0;
  WrenchSensorState state;
  Reset(*model, state);

  // just inside the ADC range: no flag, rounds to the last count
  Wrench inside = 32766.6 * lsb;
  WrenchReading reading = Update(*model, state, inside, 0.001);
  EXPECT_FALSE(reading.saturated);
  EXPECT_TRUE(reading.near_saturated);
  EXPECT_EQ(reading.all_filters[0], 32767.0 * lsb);

  // below 80 %: neither flag
  reading = Update(*model, state, 0.75 * 32768.0 * lsb, 0.001);
  EXPECT_FALSE(reading.saturated);
  EXPECT_FALSE(reading.near_saturated);
  EXPECT_FALSE(state.saturated_latched);

  // beyond: clipped at ±32767 counts and flagged; the latch stays after the overload
  Wrench beyond = 3.0 * model->full_scale();
  beyond[1] = -beyond[1];
  reading = Update(*model, state, beyond, 0.001);
  EXPECT_TRUE(reading.saturated);
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(reading.all_filters[0][i], std::copysign(32767.0 * lsb[i], beyond[i]));
  }
  reading = Update(*model, state, Wrench::Zero(), 0.001);
  EXPECT_FALSE(reading.saturated);
  EXPECT_TRUE(state.saturated_latched);
  EXPECT_EQ(state.saturated_samples, 8u);
}

TEST(WrenchSensorTest, ChunkingDoesNotChangeOutputWithNoiseOn) {
  const auto model = WrenchSensorModel::Create(WrenchSensorConfig{});
  // 8 ms blocks cut into 1, 8, 4, 16, 80, 24 and 7 calls: the last three end between samples,
  // and 8 ms / 24 or / 7 is no binary fraction, so the phase carry must absorb rounding
  constexpr int kWays = 7;
  const double chunk_dt[kWays] = {0.008, 0.001, 0.002, 0.0005, 0.0001, 0.008 / 24, 0.008 / 7};
  const int chunks[kWays] = {1, 8, 4, 16, 80, 24, 7};
  std::vector<WrenchSensorState> states(kWays);
  for (auto& state : states) Reset(*model, state);
  for (int block = 0; block < 200; ++block) {
    Wrench load;
    load << 5.0 * std::sin(0.1 * block), 3.0, -20.0 + block * 0.01, 0.2, -0.1, 0.05 * block;
    std::vector<WrenchReading> readings(kWays);
    for (int c = 0; c < kWays; ++c) {
      for (int i = 0; i < chunks[c]; ++i) readings[c] = Update(*model, states[c], load, chunk_dt[c]);
    }
    for (int c = 1; c < kWays; ++c) {
      ASSERT_EQ(states[c].sample_count, states[0].sample_count) << "dt " << chunk_dt[c];
      for (int k = 0; k <= 6; ++k) {
        ASSERT_EQ(readings[c].all_filters[k], readings[0].all_filters[k])
            << "dt " << chunk_dt[c] << " filter " << k << " block " << block;
      }
    }
  }
  EXPECT_EQ(states[0].sample_count, 200u * 64u);
}

TEST(WrenchSensorTest, ReadSelectedIsReadsWrenchForEveryFilter) {
  // a host reading one data set per period gets the values Read gives, saturation included
  for (int f = 0; f <= 6; ++f) {
    WrenchSensorConfig config;
    config.filter = f;
    const auto model = WrenchSensorModel::Create(config);
    WrenchSensorState state;
    Reset(*model, state);
    for (int period = 0; period < 400; ++period) {
      Wrench load;
      load << 60.0 * std::sin(0.05 * period), 3.0, period % 100 < 20 ? 260.0 : -20.0, 0.2, -4.0, 0.01 * period;
      WrenchReading flags;
      Advance(*model, state, load, 0.002, &flags);
      ASSERT_EQ(ReadSelected(*model, state), Read(*model, state).wrench) << "filter " << f << " period " << period;
    }
  }
}

TEST(WrenchSensorTest, SameSeedSameReadingsOtherSeedOtherBias) {
  WrenchSensorConfig config;
  const auto model_a = WrenchSensorModel::Create(config);
  const auto model_b = WrenchSensorModel::Create(config);
  config.seed = 2;
  const auto model_c = WrenchSensorModel::Create(config);
  WrenchSensorState a, b, c;
  Reset(*model_a, a);
  Reset(*model_b, b);
  Reset(*model_c, c);
  EXPECT_EQ(a.bias, b.bias);
  for (int i = 0; i < 6; ++i) EXPECT_NE(a.bias[i], c.bias[i]) << "axis " << i;
  std::vector<Wrench> first;
  for (int n = 0; n < 500; ++n) {
    const WrenchReading ra = Update(*model_a, a, Wrench::Constant(1.0), 0.001);
    const WrenchReading rb = Update(*model_b, b, Wrench::Constant(1.0), 0.001);
    ASSERT_EQ(ra.all_filters[0], rb.all_filters[0]);
    ASSERT_EQ(ra.wrench, rb.wrench);
    first.push_back(ra.all_filters[0]);
  }
  // Reset replays the same sequence
  Reset(*model_a, a);
  for (int n = 0; n < 500; ++n) {
    ASSERT_EQ(Update(*model_a, a, Wrench::Constant(1.0), 0.001).all_filters[0], first[n]);
  }
}

TEST(WrenchSensorTest, ResetStartsInSteadyStateAndBadInputIsRefused) {
  const auto model = WrenchSensorModel::Create(QuietConfig());
  WrenchSensorState state;
  EXPECT_EQ(Update(*model, state, Wrench::Zero(), 0.001).status, WrenchStatus::kNotReset);

  Wrench load;
  load << 1.0, 2.0, -30.0, 0.1, 0.2, -0.3;
  Reset(*model, state, load);
  WrenchReading reading = Update(*model, state, load, 0.001);
  EXPECT_EQ(reading.status, WrenchStatus::kOk);
  for (int k = 0; k <= 6; ++k) {
    EXPECT_LT((reading.all_filters[k] - load).cwiseAbs().maxCoeff(), 1e-12) << "filter " << k;
  }

  const std::uint64_t count = state.sample_count;
  Wrench bad = load;
  bad[3] = std::nan("");
  reading = Update(*model, state, bad, 0.001);
  EXPECT_EQ(reading.status, WrenchStatus::kRejectedInput);
  EXPECT_EQ(Update(*model, state, load, -0.001).status, WrenchStatus::kRejectedInput);
  EXPECT_EQ(Update(*model, state, load, std::nan("")).status, WrenchStatus::kRejectedInput);
  EXPECT_EQ(state.sample_count, count);
  EXPECT_EQ(state.rejected_updates, 3u);
  EXPECT_LT((reading.wrench - load).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_THROW(Reset(*model, state, bad), std::invalid_argument);
}

TEST(WrenchSensorTest, LoadFromMujocoSensorNegates) {
  const double force[3] = {1.0, -2.0, 3.0};
  const double torque[3] = {-0.1, 0.2, -0.3};
  Wrench expected;
  expected << -1.0, 2.0, -3.0, 0.1, -0.2, 0.3;
  EXPECT_EQ(LoadFromMujocoSensor(force, torque), expected);
}

}  // namespace
}  // namespace vlab::sensors
