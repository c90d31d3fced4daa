// sensor_round.h: the inline roundings equal std::round and std::llround bit for bit.
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "sensors/sensor_round.h"
#include "test_util.h"

namespace vlab::sensors {
namespace {

using vlab::testing::Bits;

// halves, their neighbours, signed zeros, the 2^52 edge, counts of the JR3's int16 range
std::vector<double> EdgeValues() {
  std::vector<double> v = {0.0,
                           -0.0,
                           0.5,
                           -0.5,
                           1.5,
                           -1.5,
                           2.5,
                           -2.5,
                           32767.5,
                           -32767.5,
                           32767.0,
                           -32768.0,
                           0.49999999999999994,
                           -0.49999999999999994,
                           4503599627370495.5,
                           -4503599627370495.5,
                           4503599627370496.0,
                           -4503599627370496.0,
                           9007199254740993.0,
                           1e300,
                           -1e300,
                           std::numeric_limits<double>::denorm_min(),
                           -std::numeric_limits<double>::denorm_min()};
  for (double h = 0.5; h < 1e6; h = h * 3 + 0.5) {
    v.push_back(std::nextafter(h, 0.0));
    v.push_back(std::nextafter(h, 1e9));
    v.push_back(-std::nextafter(h, 0.0));
    v.push_back(-std::nextafter(h, 1e9));
  }
  return v;
}

TEST(SensorRoundTest, RoundHalfAwayEqualsStdRoundToTheBit) {
  std::vector<double> values = EdgeValues();
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> wide(-40000.0, 40000.0), narrow(-3.0, 3.0);
  for (int i = 0; i < 200000; ++i) values.push_back(i % 2 ? wide(rng) : narrow(rng));
  for (double x : values) EXPECT_EQ(Bits(RoundHalfAway(x)), Bits(std::round(x))) << x;
  // not finite: what std::round gives
  EXPECT_TRUE(std::isnan(RoundHalfAway(std::numeric_limits<double>::quiet_NaN())));
  EXPECT_EQ(RoundHalfAway(std::numeric_limits<double>::infinity()), std::numeric_limits<double>::infinity());
  EXPECT_EQ(RoundHalfAway(-std::numeric_limits<double>::infinity()), -std::numeric_limits<double>::infinity());
}

TEST(SensorRoundTest, RoundToCountEqualsStdLlround) {
  std::vector<double> values = EdgeValues();
  std::mt19937_64 rng(4);
  // encoder counts: angles of +-4 rad at 7.7e-6 rad per count and finer
  std::uniform_real_distribution<double> counts(-2e6, 2e6), near(-2.0, 2.0);
  for (int i = 0; i < 200000; ++i) values.push_back(i % 2 ? counts(rng) : near(rng));
  for (double x : values) {
    if (std::abs(x) > 9e18) continue;  // llround's own range
    EXPECT_EQ(RoundToCount(x), std::llround(x)) << x;
  }
}

}  // namespace
}  // namespace vlab::sensors
