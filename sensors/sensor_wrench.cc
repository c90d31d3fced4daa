// JR3 sensor model: Reset and the 8 kHz sample loop (ADC, quantisation, filter cascade).
#include "sensors/sensor_wrench.h"

#include "sensors/sensor_random.h"
#include "sensors/sensor_round.h"

#include <cmath>
#include <stdexcept>

namespace vlab::sensors {
namespace {

constexpr double kTwoPi = 6.28318530717958647692;
// a phase this close to a whole sample counts as on the sample instant, so that dt values
// that are not exact binary fractions (1 ms = 8 samples) neither drop nor double a sample
constexpr double kPhaseSnapSamples = 1e-6;
// Update refuses longer steps (a unit error, not a control period)
constexpr double kMaxUpdateDtSeconds = 60.0;

// six independent standard normal draws
Wrench DrawStandardNormal(const WrenchSensorModel& model, Xoshiro256pp& rng) {
  Wrench out;
  for (int i = 0; i < 6; ++i) out[i] = model.normal()(rng);
  return out;
}

// one channel's counts, clipped to the int16 range and (optionally) rounded; flags what was hit
inline double ChannelCounts(const WrenchSensorModel& model, int i, double value, bool* saturated,
                            bool* near_saturated) {
  double counts = value / model.lsb()[i];
  const double magnitude = std::abs(counts);
  if (magnitude >= kWrenchNearSaturationCounts && near_saturated) *near_saturated = true;
  if (magnitude > kWrenchClipCounts) {
    if (saturated) *saturated = true;
    counts = std::copysign(kWrenchClipCounts, counts);
  }
  return model.quantization_enabled() ? RoundHalfAway(counts) : counts;
}

// every channel's counts (ChannelCounts)
Wrench ToCounts(const WrenchSensorModel& model, const Wrench& value, bool* saturated, bool* near_saturated) {
  Wrench counts;
  for (int i = 0; i < 6; ++i) counts[i] = ChannelCounts(model, i, value[i], saturated, near_saturated);
  return counts;
}

// what the host reads: every data set as clipped (and rounded) counts times lsb
void FillReading(const WrenchSensorModel& model, const WrenchSensorState& state, WrenchReading& reading) {
  // filter0 is already ADC data
  reading.all_filters[0] = state.output[0];
  for (int k = 1; k < kWrenchFilterCount; ++k) {
    reading.all_filters[k] = ToCounts(model, state.output[k], nullptr, nullptr).cwiseProduct(model.lsb());
  }
  reading.filter = model.filter();
  reading.wrench = reading.all_filters[model.filter()];
}

// one sensor sample: noise, ADC, then every stage whose update instant this is; `load` is
// the true wrench plus the bias (constant over the samples of one Advance)
void ProcessSample(const WrenchSensorModel& model, WrenchSensorState& state, const Wrench& load,
                   WrenchReading& reading) {
  ++state.sample_count;

  // sensor signal plus white noise (the six draws first, in axis order), then the ADC's clip
  // and quantisation give filter0, channel by channel
  double normal[6] = {0, 0, 0, 0, 0, 0};
  const bool noise = model.noise_enabled();
  if (noise) {
    for (int i = 0; i < 6; ++i) normal[i] = model.normal()(state.rng);
  }
  bool saturated = false;
  for (int i = 0; i < 6; ++i) {
    const double signal = noise ? load[i] + model.noise_sigma()[i] * normal[i] : load[i];
    state.output[0][i] = ChannelCounts(model, i, signal, &saturated, &reading.near_saturated) * model.lsb()[i];
  }
  if (saturated) {
    reading.saturated = true;
    state.saturated_latched = true;
    ++state.saturated_samples;
  }

  // cascade: stage k runs every 4^(k-1) samples on the latest output of stage k-1
  for (int k = 1; k < kWrenchFilterCount; ++k) {
    const WrenchFilterStage& stage = model.stage(k);
    // decimation is a power of 4: a mask is the remainder
    if ((state.sample_count & (stage.decimation - 1)) != 0) break;  // later stages are slower still
    const Wrench& in = state.output[k - 1];
    Wrench& z1 = state.z1[k - 1];
    Wrench& z2 = state.z2[k - 1];
    const Wrench out = stage.b0 * in + z1;
    z1 = stage.b1 * in - stage.a1 * out + z2;
    z2 = stage.b2 * in - stage.a2 * out;
    state.output[k] = out;
  }
}

}  // namespace

void Reset(const WrenchSensorModel& model, WrenchSensorState& state, const Wrench& initial_load) {
  if (!initial_load.allFinite()) {
    throw std::invalid_argument("wrench sensor: Reset initial_load must be finite");
  }
  state.rng.Seed(model.seed());
  // always draw, so the noise stream does not depend on enable_bias
  const Wrench unit_bias = DrawStandardNormal(model, state.rng);
  state.bias = model.bias_sigma().cwiseProduct(unit_bias);

  // filter0 holds the noise-free ADC value of the initial load; every stage is in steady state
  state.output[0] = ToCounts(model, initial_load + state.bias, nullptr, nullptr).cwiseProduct(model.lsb());
  for (int k = 1; k < kWrenchFilterCount; ++k) {
    const WrenchFilterStage& stage = model.stage(k);
    const Wrench& u = state.output[k - 1];
    state.output[k] = u;
    state.z1[k - 1] = (1.0 - stage.b0) * u;
    state.z2[k - 1] = (stage.b2 - stage.a2) * u;
  }

  state.sample_count = 0;
  state.phase_samples = 0.0;
  state.saturated_latched = false;
  state.saturated_samples = 0;
  state.rejected_updates = 0;
  state.ready = true;
}

WrenchStatus Advance(const WrenchSensorModel& model, WrenchSensorState& state, const Wrench& true_wrench, double dt,
                     WrenchReading* flags) {
  if (!state.ready) {
    ++state.rejected_updates;
    flags->status = WrenchStatus::kNotReset;
    return flags->status;
  }
  if (!std::isfinite(dt) || dt < 0.0 || dt > kMaxUpdateDtSeconds || !true_wrench.allFinite()) {
    ++state.rejected_updates;
    flags->status = WrenchStatus::kRejectedInput;
    return flags->status;
  }

  // sample instants in (t, t + dt]; the fractional phase carries to the next call
  double phase = state.phase_samples + dt * model.sample_rate_hz();
  const double nearest = std::round(phase);
  if (std::abs(phase - nearest) < kPhaseSnapSamples) phase = nearest;
  const double whole = std::floor(phase);
  state.phase_samples = phase - whole;
  const auto samples = static_cast<std::uint64_t>(whole);

  const Wrench load = true_wrench + state.bias;
  for (std::uint64_t i = 0; i < samples; ++i) ProcessSample(model, state, load, *flags);
  flags->samples += samples;
  flags->status = WrenchStatus::kOk;
  return flags->status;
}

WrenchReading Read(const WrenchSensorModel& model, const WrenchSensorState& state) {
  WrenchReading reading;
  FillReading(model, state, reading);
  return reading;
}

Wrench ReadSelected(const WrenchSensorModel& model, const WrenchSensorState& state) {
  // filter0 is already ADC data (as FillReading)
  const int f = model.filter();
  if (f == 0) return state.output[0];
  return ToCounts(model, state.output[f], nullptr, nullptr).cwiseProduct(model.lsb());
}

WrenchReading Update(const WrenchSensorModel& model, WrenchSensorState& state, const Wrench& true_wrench, double dt) {
  WrenchReading reading;
  reading.filter = model.filter();
  if (Advance(model, state, true_wrench, dt, &reading) == WrenchStatus::kNotReset) return reading;
  FillReading(model, state, reading);
  return reading;
}

}  // namespace vlab::sensors
