// Rounding to whole counts on the sensors' sample paths (the JR3 model's ADC, the arm's
// encoders), inline: std::round and std::llround are library calls on baseline x86-64
// (no SSE4.1 round instruction), and these run 48 times per physics step.
#pragma once

#include <cmath>
#include <cstdint>

namespace vlab::sensors {

/// 0.49999999999999994, the largest double below 1/2.
inline constexpr double kJustBelowHalf = 0.49999999999999994;

/// std::round(x), bit for bit (halves away from zero; -0.0 for -0.5 < x <= -0.0), without a
/// library call for |x| < 2^52; larger values, infinities and NaN go to std::round.
inline double RoundHalfAway(double x) {
  if (!(std::abs(x) < 4503599627370496.0)) return std::round(x);
  // the largest double below 1/2 moves a half (and nothing less) past the next whole number,
  // and the sum rounds up to it exactly when x's fraction is a half or more; no branch, as the
  // fractions of noisy samples are random
  const double toward_zero = static_cast<double>(static_cast<std::int64_t>(x + std::copysign(kJustBelowHalf, x)));
  return std::copysign(toward_zero, x);
}

/// std::llround(x) for |x| < 2^52 (the nearest count, halves away from zero), without a
/// library call; other values go to std::llround.
inline std::int64_t RoundToCount(double x) {
  if (!(std::abs(x) < 4503599627370496.0)) return std::llround(x);
  return static_cast<std::int64_t>(x + std::copysign(kJustBelowHalf, x));
}

}  // namespace vlab::sensors
