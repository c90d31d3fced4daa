// Seeded normal deviates for sensor noise models.
//
// ZigguratNormal draws standard normal deviates by the ziggurat method
// (G. Marsaglia and W. W. Tsang, "The Ziggurat Method for Generating Random
// Variables", J. Statistical Software 5(8), 2000): 128 layers of equal area
// under exp(-x²/2); about 99 % of draws cost one 64-bit random word, a table
// look-up and a multiply, the rest fall back to an exact test under the curve
// or Marsaglia's exponential tail method. The layer index, the sign and the
// value come from disjoint bits of one 64-bit word (J. A. Doornik, "An
// Improved Ziggurat Method to Generate Normal Random Samples", 2005, showed
// that sharing bits between them biases the original 32-bit version).
//
// The uniform source is xoshiro256++ (D. Blackman and S. Vigna, "Scrambled
// Linear Pseudorandom Number Generators", ACM TOMS 47(4), 2021): 256 bits of
// state, period 2^256 - 1, seeded through splitmix64 as its authors advise. It
// is specified bit for bit, so the same seed gives the same deviates on every
// platform and library, and it costs a few instructions a word (a third of
// std::mt19937_64's cost, which matters at 48 deviates per millisecond).
#pragma once

#include <array>
#include <cstdint>
#include <cstring>

namespace vlab::sensors {

/// xoshiro256++ 64-bit generator; satisfies UniformRandomBitGenerator.
class Xoshiro256pp {
 public:
  using result_type = std::uint64_t;
  /// Seeds the 256-bit state from a 64-bit seed with splitmix64.
  explicit Xoshiro256pp(std::uint64_t seed = 1) { Seed(seed); }
  /// Sets the raw state (must not be all zero); for tests against hand-computed values.
  Xoshiro256pp(std::uint64_t s0, std::uint64_t s1, std::uint64_t s2, std::uint64_t s3) : s_{s0, s1, s2, s3} {}
  void Seed(std::uint64_t seed);
  static constexpr result_type min() { return 0; }
  static constexpr result_type max() { return ~result_type{0}; }
  result_type operator()() {
    const std::uint64_t result = Rotl(s_[0] + s_[3], 23) + s_[0];
    const std::uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = Rotl(s_[3], 45);
    return result;
  }

 private:
  static std::uint64_t Rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  std::array<std::uint64_t, 4> s_;
};

class ZigguratNormal {
 public:
  /// Builds the layer tables (128 entries; no allocation).
  ZigguratNormal();
  /// One standard normal deviate (mean 0, variance 1). Inline, without a branch on the
  /// sign (a random one): the JR3 model draws 48 per millisecond.
  double operator()(Xoshiro256pp& rng) const {
    // bits 0-6: layer, bit 7: sign, bits 8-63: position in the layer
    const std::uint64_t word = rng();
    const int layer = static_cast<int>(word & (kLayers - 1));
    const std::uint64_t value = word >> 8;
    const double x = static_cast<double>(value) * scale_[layer];
    const double magnitude = value < fast_[layer] ? x : Slow(rng, layer, x);
    // the sign bit set from bit 7: -magnitude when it is set
    std::uint64_t bits;
    std::memcpy(&bits, &magnitude, sizeof bits);
    bits ^= (word & 0x80) << 56;
    double signed_value;
    std::memcpy(&signed_value, &bits, sizeof bits);
    return signed_value;
  }

 private:
  static constexpr int kLayers = 128;
  double Slow(Xoshiro256pp& rng, int layer, double x) const;

  std::array<double, kLayers + 1> edge_{};     // layer widths: edge_[0] base width, edge_[1] = r, edge_[128] = 0
  std::array<double, kLayers + 1> height_{};   // exp(-edge²/2)
  std::array<std::uint64_t, kLayers> fast_{};  // 56-bit thresholds: value < fast_[i] lies under the curve
  std::array<double, kLayers> scale_{};        // edge_[i] / 2^56
};

}  // namespace vlab::sensors
