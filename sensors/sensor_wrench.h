// JR3 six-axis force/torque sensor model (sensor head + DSP receiver).
//
// Ports
//   input   true_wrench: the load the TOOL SIDE applies to the sensor, in the sensor frame
//           [Fx Fy Fz N, Mx My Mz N·m], held constant (zero-order hold) over each Update call.
//           From MuJoCo force/torque sensors at the sensor site use LoadFromMujocoSensor().
//   output  WrenchReading: filter0..filter6 data as the host reads it from the DSP, the selected
//           filter, and saturation flags.
//   rates   the model samples at sample_rate_hz (JR3: 8 kHz) internally; Update may be called at
//           any period (1 ms physics step, 2 ms control period, ...). Every sample instant in
//           (t, t + dt] is processed and the fractional phase carries over, so chunking the same
//           held input differently gives bitwise the same samples.
//   latency only that of the filters: DC group delay of filter k ≈ 0.3 / cut-off_k
//           (0.45 ms filter1, 38 ms filter4), plus up to one stage period of decimation hold.
//
// Model (sources: DATASHEET §4; linux drivers/comedi/drivers/jr3_pci.h, whose comments
// transcribe the JR3 DSP manual; Orocos JR3 driver CUTOFF_FREQUENCY_FILTER1..6):
//   1. Sample at fs = sample_rate_hz: x = true_wrench + bias + white noise (per-axis sigma).
//   2. ADC / data scaling: counts c = x / lsb with lsb = full_scale / 16384 (jr3_pci.h:
//      ±16384 counts = full scale). The raw ADC clips at ±32767 counts (≈ 2·FS; jr3_pci.h
//      sat_value = 32768 − 2^(16 − bits) = 32767 for a 16-bit ADC): |c| > 32767 clips and
//      raises `saturated`; |c| ≥ 26214 (80 %, jr3_pci.h near_sat) raises `near_saturated`.
//      Then c is rounded to the nearest count (std::round). The clip applies even with
//      enable_quantization = false (it is the ADC range); rounding does not.
//      Decoupling is the identity (ideal calibration matrix). The result is filter0, the
//      "decoupled, unfiltered" data.
//   3. Cascade of six low-pass stages (jr3_pci.h): filter k (k = 1..6) runs at fs / 4^(k−1)
//      (8 kHz, 2 kHz, 500 Hz, 125 Hz, 31.25 Hz, 7.8125 Hz) on the latest output of filter k−1,
//      with cut-off fs / 16 / 4^(k−1) (500, 125, 31.25, 7.813, 1.953, 0.4883 Hz).
//   4. The host reads every filter output as int16 counts: reported filter outputs are clipped
//      to ±32767 counts and (when enable_quantization) rounded to lsb; the filter states
//      themselves are kept in double precision (the DSP keeps wide accumulators).
//
// Filter design (the JR3 manual does not state the section type in any public text we found):
//   each stage is a 2-pole Butterworth low-pass obtained by the bilinear transform with the
//   cut-off prewarped, H(z) = b0 (1 + z^-1)^2 / (1 + a1 z^-1 + a2 z^-2). Reasons: (a) the ratio
//   cut-off / stage rate is 1/16 for EVERY stage, so one coefficient set run at decimated rates
//   reproduces the whole cascade — the structure the 1/4-cut-off, 1/4-rate figures suggest;
//   (b) the next stage samples at 1/4 of the rate, i.e. its Nyquist is 2·fc of this stage: a
//   2-pole section attenuates there by 12.3 dB (a 1-pole only by 7 dB), limiting aliasing;
//   (c) prewarping puts the −3 dB point exactly at the stated cut-off; (d) the double zero at
//   Nyquist and DC gain exactly 1 keep static loads exact. Realised in transposed direct form II.
//
// Noise defaults ([EST], DATASHEET §4: σ ≈ 0.05–0.1 % FS at filter1, ≈ 0.01 % FS at filter4):
//   white noise per 8 kHz sample σ0 = 0.2 % FS. The noise-equivalent bandwidth of a 2-pole
//   Butterworth is 1.111·fc, so σ1 ≈ σ0·sqrt(2·555 Hz / 8 kHz) ≈ 0.074 % FS and
//   σ4 ≈ σ0·sqrt(2·8.68 Hz / 8 kHz) ≈ 0.0093 % FS, matching both datasheet figures.
//   Bias (residual offset after taring + drift) σb = 0.05 % FS ≈ 2 effective-resolution steps
//   (DATASHEET: effective resolution ≈ FS/4000), drawn once per Reset from the seed.
//
// Threading: model is immutable and shareable; a state belongs to one thread. Update never
// throws and never allocates; it rejects non-finite input or dt and reports it in the status.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <random>
#include <string>

#include <Eigen/Core>

#include "sensors/sensor_random.h"

namespace vlab::sensors {

/// Fx Fy Fz [N], Mx My Mz [N·m], in the sensor frame.
using Wrench = Eigen::Matrix<double, 6, 1>;

/// Number of JR3 data sets: filter0 (unfiltered) .. filter6.
inline constexpr int kWrenchFilterCount = 7;
/// Counts that represent one full scale in decoupled/filtered data (jr3_pci.h).
inline constexpr double kWrenchCountsPerFullScale = 16384.0;
/// ADC clip level in counts (±2·FS); beyond it a sample is saturated.
inline constexpr double kWrenchClipCounts = 32767.0;
/// Near-saturation level in counts (80 % of 32768, jr3_pci.h near_sat).
inline constexpr double kWrenchNearSaturationCounts = 26214.0;

/// Converts MuJoCo `force`/`torque` sensor data at the sensor site (the force and torque the
/// parent exerts on the child subtree, site frame) into the load the tool applies to the sensor,
/// which is what a JR3 reads: a plain negation. A mass m hanging below a z-up sensor gives
/// Fz = −m·g.
Wrench LoadFromMujocoSensor(const double force[3], const double torque[3]);

/// Configuration; plain values, validated once by WrenchSensorModel::Create.
struct WrenchSensorConfig {
  /// Sensor model name: "67M25A", "85M35A" or "50M31A" set the default full scales. Any other
  /// name is accepted only together with an explicit full_scale (a custom sensor).
  std::string model = "67M25A";
  /// Per axis, the value that reads as 16384 counts [N, N·m]. Empty: the model's default,
  /// 67M25A [100 100 200 N, 5 5 5 N·m] (rosjr3 driver default), 85M35A [400 400 800, 40 40 40]
  /// and 50M31A [100 100 200, 6 6 6] (both [EST] from DATASHEET §4 rating ranges).
  std::optional<Wrench> full_scale;
  /// DSP sample rate [Hz]; cut-offs scale with it (filter1 = fs/16).
  double sample_rate_hz = 8000.0;
  /// Data set returned in WrenchReading::wrench: 0 (unfiltered) .. 6.
  int filter = 4;
  /// Constant bias standard deviation per axis [N, N·m]. Empty: 0.05 % of full scale.
  std::optional<Wrench> bias_sigma;
  /// White noise standard deviation per axis per sample [N, N·m]. Empty: 0.2 % of full scale.
  std::optional<Wrench> noise_sigma;
  bool enable_noise = true;
  bool enable_bias = true;
  bool enable_quantization = true;
  /// Seed of the bias and noise generator (xoshiro256++ and ziggurat normals, sensor_random.h).
  std::uint64_t seed = 1;
};

/// One low-pass stage: coefficients of b0 (1 + z^-1)^2 / (1 + a1 z^-1 + a2 z^-2).
struct WrenchFilterStage {
  double b0 = 0.0, b1 = 0.0, b2 = 0.0, a1 = 0.0, a2 = 0.0;
  double cutoff_hz = 0.0;        // −3 dB frequency
  double rate_hz = 0.0;          // update rate
  std::uint64_t decimation = 1;  // updated every `decimation` sensor samples
};

/// Immutable JR3 sensor description (resolved full scales, noise levels, filter coefficients).
class WrenchSensorModel {
 public:
  /// Validates `config` and resolves its defaults. Throws std::invalid_argument whose message
  /// names the offending field, e.g. "wrench sensor: filter 9 out of range 0..6".
  static std::unique_ptr<WrenchSensorModel> Create(const WrenchSensorConfig& config);

  const std::string& model_name() const { return model_name_; }
  /// Per axis full scale [N, N·m] and its count size lsb = full_scale / 16384.
  const Wrench& full_scale() const { return full_scale_; }
  const Wrench& lsb() const { return lsb_; }
  /// Effective sigmas (zero when the corresponding feature is disabled).
  const Wrench& noise_sigma() const { return noise_sigma_; }
  const Wrench& bias_sigma() const { return bias_sigma_; }
  double sample_rate_hz() const { return sample_rate_hz_; }
  int filter() const { return filter_; }
  bool noise_enabled() const { return enable_noise_; }
  bool bias_enabled() const { return enable_bias_; }
  bool quantization_enabled() const { return enable_quantization_; }
  std::uint64_t seed() const { return seed_; }
  /// Stage k = 1..6 (k outside that range returns stage 1).
  const WrenchFilterStage& stage(int k) const;
  /// Standard normal generator used for bias and noise.
  const ZigguratNormal& normal() const { return normal_; }

 private:
  WrenchSensorModel() = default;

  std::string model_name_;
  Wrench full_scale_ = Wrench::Zero();
  Wrench lsb_ = Wrench::Zero();
  Wrench noise_sigma_ = Wrench::Zero();
  Wrench bias_sigma_ = Wrench::Zero();
  double sample_rate_hz_ = 0.0;
  int filter_ = 0;
  bool enable_noise_ = true;
  bool enable_bias_ = true;
  bool enable_quantization_ = true;
  std::uint64_t seed_ = 0;
  std::array<WrenchFilterStage, kWrenchFilterCount - 1> stages_{};
  ZigguratNormal normal_;  // noise deviates (tables built with the model)
};

/// Mutable sensor state: filter states, generator, bias, sample clock. Call Reset before use.
struct WrenchSensorState {
  bool ready = false;                                     // set by Reset
  std::array<Wrench, kWrenchFilterCount> output{};        // latest unquantised data sets 0..6
  std::array<Wrench, kWrenchFilterCount - 1> z1{}, z2{};  // transposed DF-II states, stage 1..6
  Wrench bias = Wrench::Zero();                           // drawn at Reset [N, N·m]
  Xoshiro256pp rng;
  std::uint64_t sample_count = 0;  // samples processed since Reset
  double phase_samples = 0.0;      // time since the last sample, in sample periods, [0, 1)
  bool saturated_latched = false;  // any sample clipped since Reset
  std::uint64_t saturated_samples = 0;
  std::uint64_t rejected_updates = 0;  // Update calls refused (non-finite input/dt, no Reset)
};

enum class WrenchStatus {
  kOk,
  kRejectedInput,  // non-finite true_wrench, or dt < 0, > 60 s or non-finite: state unchanged
  kNotReset,       // Reset was never called on this state
};

/// What the host reads after an Update.
struct WrenchReading {
  Wrench wrench = Wrench::Zero();  // data set `filter` [N, N·m], sensor frame
  int filter = 0;
  bool saturated = false;       // some axis of some sample in this call clipped (|c| > 32767)
  bool near_saturated = false;  // some axis of some sample in this call reached 80 % (26214)
  std::uint64_t samples = 0;    // sensor samples processed in this call
  WrenchStatus status = WrenchStatus::kOk;
  std::array<Wrench, kWrenchFilterCount> all_filters{};  // filter0..filter6 as read
};

/// Re-seeds the generator, draws the bias and sets the filters to steady state at
/// `initial_load` (+ bias), as if that load had been applied forever. Sample phase = 0.
/// Setup path: throws std::invalid_argument if initial_load is not finite.
void Reset(const WrenchSensorModel& model, WrenchSensorState& state, const Wrench& initial_load = Wrench::Zero());

/// Advances the sensor like Update but forms no reading: for callers that feed the sensor
/// more often than they read it (the lab feeds it every physics step and reads it once per
/// control period). Sets flags->status, adds to flags->samples and sets (never clears)
/// flags->saturated / near_saturated; the data sets in *flags are left untouched.
WrenchStatus Advance(const WrenchSensorModel& model, WrenchSensorState& state, const Wrench& true_wrench, double dt,
                     WrenchReading* flags);

/// What the host reads now: every data set as clipped (and rounded) counts times lsb.
WrenchReading Read(const WrenchSensorModel& model, const WrenchSensorState& state);

/// The selected data set alone (Read's `wrench`, the same values), for a host that reads
/// one filter every control period.
Wrench ReadSelected(const WrenchSensorModel& model, const WrenchSensorState& state);

/// Advances the sensor by dt [s] with `true_wrench` held over (t, t + dt] and returns what the
/// host reads at t + dt. dt = 0 only reads. Never throws, never allocates: bad input is
/// refused (status kRejectedInput, last data returned, state.rejected_updates counted).
WrenchReading Update(const WrenchSensorModel& model, WrenchSensorState& state, const Wrench& true_wrench, double dt);

}  // namespace vlab::sensors
