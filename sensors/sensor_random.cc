#include "sensors/sensor_random.h"

#include <cmath>

namespace vlab::sensors {

namespace {

// right edge of the base rectangle and the common layer area for 128 layers
// (Marsaglia & Tsang 2000, section 3)
constexpr double kR = 3.442619855899;
constexpr double kArea = 9.91256303526217e-3;
constexpr double kTwoTo56 = 72057594037927936.0;

double Density(double x) { return std::exp(-0.5 * x * x); }

// uniform in (0, 1]: safe for log
double UniformOpenZero(Xoshiro256pp& rng) { return (static_cast<double>(rng() >> 11) + 1.0) * 0x1.0p-53; }

}  // namespace

void Xoshiro256pp::Seed(std::uint64_t seed) {
  // splitmix64 (S. Vigna): consecutive outputs fill the state, never all zero
  for (auto& word : s_) {
    std::uint64_t z = (seed += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    word = z ^ (z >> 31);
  }
}

ZigguratNormal::ZigguratNormal() {
  // layer i spans heights [f(edge_i), f(edge_i+1)] over [0, edge_i]; the base
  // layer is the rectangle [0, r] x [0, f(r)] plus the tail beyond r, drawn as
  // one rectangle of width area / f(r)
  edge_[0] = kArea / Density(kR);
  edge_[1] = kR;
  for (int i = 1; i < kLayers - 1; ++i) {
    edge_[i + 1] = std::sqrt(-2.0 * std::log(kArea / edge_[i] + Density(edge_[i])));
  }
  edge_[kLayers] = 0.0;
  for (int i = 0; i <= kLayers; ++i) height_[i] = Density(edge_[i]);
  height_[kLayers] = 1.0;
  for (int i = 0; i < kLayers; ++i) {
    fast_[i] = static_cast<std::uint64_t>(edge_[i + 1] / edge_[i] * kTwoTo56);
    scale_[i] = edge_[i] / kTwoTo56;
  }
}

double ZigguratNormal::Slow(Xoshiro256pp& rng, int layer, double x) const {
  for (;;) {
    if (layer == 0) {
      // tail beyond r (Marsaglia 1964): exponential proposals, exact acceptance
      double t, y;
      do {
        t = -std::log(UniformOpenZero(rng)) / kR;
        y = -std::log(UniformOpenZero(rng));
      } while (y + y < t * t);
      return kR + t;
    }
    // wedge between the rectangle and the curve: accept when under f
    const double u = static_cast<double>(rng() >> 11) * 0x1.0p-53;
    if (height_[layer] + u * (height_[layer + 1] - height_[layer]) < Density(x)) return x;
    // rejected: a fresh draw from the whole ziggurat (magnitude only; the caller signs it)
    const std::uint64_t word = rng();
    layer = static_cast<int>(word & (kLayers - 1));
    const std::uint64_t value = word >> 8;
    x = static_cast<double>(value) * scale_[layer];
    if (value < fast_[layer]) return x;
  }
}

}  // namespace vlab::sensors
