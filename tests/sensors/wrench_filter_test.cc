// Tests for the JR3 filter cascade and noise: step responses against independent
// implementations and closed forms, DC gain, -3 dB points, noise levels.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "sensors/sensor_wrench.h"
#include "sensors/wrench_reference.h"

namespace vlab::sensors {
namespace {

using wrench_testing::kFs;
using wrench_testing::kPi;
using wrench_testing::kTs;
using wrench_testing::QuietConfig;
using wrench_testing::ReferenceCascade;
using wrench_testing::ReferenceStage;

TEST(WrenchSensorTest, StepResponseMatchesIndependentDifferenceEquations) {
  const auto model = WrenchSensorModel::Create(QuietConfig());
  WrenchSensorState state;
  Reset(*model, state);
  Wrench amplitude;
  amplitude << 1.0, -2.0, 30.0, 0.5, -0.25, 1.5;
  ReferenceCascade reference;
  double worst = 0.0;
  for (int n = 0; n < 3 * 8000; ++n) {
    const WrenchReading reading = Update(*model, state, amplitude, kTs);
    ASSERT_EQ(reading.samples, 1u) << "sample " << n;
    reference.Step(1.0);
    for (int k = 0; k <= 6; ++k) {
      for (int i = 0; i < 6; ++i) {
        worst = std::max(
            worst, std::abs(reading.all_filters[k][i] - amplitude[i] * reference.out[k]) / std::abs(amplitude[i]));
      }
    }
  }
  // same recursion evaluated in another form: only rounding differences remain
  EXPECT_LT(worst, 1e-12);
}

TEST(WrenchSensorTest, Filter1StepFollowsContinuousButterworth) {
  // Continuous 2-pole Butterworth at the prewarped frequency wa, step at t = 0:
  //   y(t) = 1 - exp(-zeta wa t) (cos(wd t) + zeta / sqrt(1 - zeta^2) sin(wd t)).
  // The bilinear transform is the trapezoidal rule: it sees the sampled step as a ramp over the
  // sample before, i.e. a step half a period earlier, and its error is O((wa T)^2 / 12) of the
  // response (0.013 here); tolerance 1.5 times that.
  const auto model = WrenchSensorModel::Create(QuietConfig());
  WrenchSensorState state;
  Reset(*model, state);
  const double wa = 2.0 * kFs * std::tan(kPi * 500.0 / kFs);
  const double zeta = 1.0 / std::sqrt(2.0);
  const double wd = wa * std::sqrt(1.0 - zeta * zeta);
  const double tolerance = 1.5 * (wa * kTs) * (wa * kTs) / 12.0;
  for (int m = 0; m < 200; ++m) {
    const WrenchReading reading = Update(*model, state, Wrench::Ones(), kTs);
    const double t = m * kTs + 0.5 * kTs;
    const double expected =
        1.0 - std::exp(-zeta * wa * t) * (std::cos(wd * t) + zeta / std::sqrt(1.0 - zeta * zeta) * std::sin(wd * t));
    ASSERT_NEAR(reading.all_filters[1][0], expected, tolerance) << "sample " << m;
  }
}

TEST(WrenchSensorTest, DcGainIsOne) {
  WrenchSensorConfig config = QuietConfig();
  config.filter = 6;
  const auto model = WrenchSensorModel::Create(config);
  WrenchSensorState state;
  Reset(*model, state);
  Wrench load;
  load << 10.0, -20.0, 55.0, 1.0, -2.0, 3.0;
  WrenchReading reading;
  // filter6 decays as exp(-zeta 2 pi 0.488 t): 30 s leaves e^-65
  for (int i = 0; i < 3000; ++i) reading = Update(*model, state, load, 0.01);
  for (int k = 0; k <= 6; ++k) {
    EXPECT_LT((reading.all_filters[k] - load).cwiseAbs().maxCoeff(), 1e-10) << "filter " << k;
  }
  EXPECT_EQ(reading.wrench, reading.all_filters[6]);
}

// amplitude of filter k for a unit sine at f, fitted over whole periods at its update instants
double SineGain(int k, double frequency_hz, double settle_s, double measure_s) {
  const auto model = WrenchSensorModel::Create(QuietConfig());
  WrenchSensorState state;
  Reset(*model, state);
  const long decimation = static_cast<long>(std::pow(4.0, k - 1));
  const long settle = static_cast<long>(settle_s * kFs);
  const long total = settle + static_cast<long>(measure_s * kFs);
  double sum_sin = 0.0, sum_cos = 0.0;
  long count = 0;
  for (long n = 1; n <= total; ++n) {
    const double t = n * kTs;
    const WrenchReading reading = Update(*model, state, Wrench::Constant(std::sin(2.0 * kPi * frequency_hz * t)), kTs);
    if (n > settle && n % decimation == 0) {
      sum_sin += reading.all_filters[k][0] * std::sin(2.0 * kPi * frequency_hz * t);
      sum_cos += reading.all_filters[k][0] * std::cos(2.0 * kPi * frequency_hz * t);
      ++count;
    }
  }
  return 2.0 / count * std::hypot(sum_sin, sum_cos);
}

TEST(WrenchSensorTest, Minus3dBAtStatedCutoff) {
  const auto db = [](double gain) { return 20.0 * std::log10(gain); };
  // filter1 alone: the prewarped bilinear section is exactly 1/sqrt(2) at 500 Hz
  EXPECT_NEAR(db(SineGain(1, 500.0, 0.05, 0.1)), -3.0103, 0.01);
  // filter4 includes stages 1..3, which pass 7.8 Hz with < 0.02 dB loss
  EXPECT_NEAR(db(SineGain(4, 7.8125, 1.0, 2.048)), -3.0103, 0.1);
  // and the response falls: well above -3 dB at fc/4, well below at 4 fc
  EXPECT_GT(db(SineGain(1, 125.0, 0.05, 0.1)), -0.1);
  EXPECT_LT(db(SineGain(1, 2000.0, 0.05, 0.1)), -20.0);
}

TEST(WrenchSensorTest, NoiseHasConfiguredSigmaAndShrinksThroughTheCascade) {
  WrenchSensorConfig config;
  config.enable_bias = false;
  config.enable_quantization = false;
  const auto model = WrenchSensorModel::Create(config);
  WrenchSensorState state;
  Reset(*model, state);
  Wrench load;
  load << 10.0, -5.0, 40.0, 0.5, 1.0, -1.0;
  const long samples = 20 * 8000;
  const long warmup = 8000;
  std::vector<Wrench> sum(7, Wrench::Zero()), sum_sq(7, Wrench::Zero());
  for (long n = 0; n < warmup + samples; ++n) {
    const WrenchReading reading = Update(*model, state, load, kTs);
    if (n < warmup) continue;
    for (int k = 0; k <= 6; ++k) {
      const Wrench e = reading.all_filters[k] - load;
      sum[k] += e;
      sum_sq[k] += e.cwiseProduct(e);
    }
  }
  std::vector<Wrench> sigma(7);
  for (int k = 0; k <= 6; ++k) {
    const Wrench mean = sum[k] / samples;
    sigma[k] = (sum_sq[k] / samples - mean.cwiseProduct(mean)).cwiseSqrt();
  }
  // filter1 noise gain from the reference impulse response: sigma1 = sigma0 sqrt(sum h^2)
  ReferenceStage stage1(500.0, kFs);
  double sum_h2 = 0.0;
  for (int n = 0; n < 2000; ++n) {
    const double h = stage1.Step(n == 0 ? 1.0 : 0.0);
    sum_h2 += h * h;
  }
  for (int i = 0; i < 6; ++i) {
    const double sigma0 = model->noise_sigma()[i];
    // 160k samples: the std estimate is good to 1/sqrt(2N) = 0.2 %
    EXPECT_NEAR(sigma[0][i] / sigma0, 1.0, 0.02) << "axis " << i;
    EXPECT_NEAR(sigma[0 + 1][i] / (sigma0 * std::sqrt(sum_h2)), 1.0, 0.05) << "axis " << i;
    for (int k = 1; k <= 5; ++k) {
      EXPECT_LT(sigma[k][i], 0.7 * sigma[k - 1][i]) << "axis " << i << " filter " << k;
    }
    // the datasheet figures the defaults were chosen for: ~0.074 % FS and ~0.0093 % FS
    EXPECT_NEAR(sigma[1][i] / model->full_scale()[i], 0.00074, 0.0001) << "axis " << i;
    EXPECT_NEAR(sigma[4][i] / model->full_scale()[i], 0.000093, 0.00002) << "axis " << i;
  }
}

}  // namespace
}  // namespace vlab::sensors
