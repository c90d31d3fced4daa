// JR3 sensor model: configuration validation, default tables, filter coefficient design.
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "sensors/sensor_wrench.h"

namespace vlab::sensors {
namespace {

constexpr double kPi = 3.14159265358979323846;
// default noise per sample and bias, as fractions of full scale (see header for the reasoning)
constexpr double kDefaultNoiseFractionOfFullScale = 0.002;
constexpr double kDefaultBiasFractionOfFullScale = 0.0005;
// filter1 cut-off = fs / 16; each stage runs at 1/4 the rate of the previous one
constexpr double kCutoffToRateRatio = 1.0 / 16.0;
constexpr std::uint64_t kStageDecimation = 4;

struct KnownSensor {
  const char* name;
  double full_scale[6];
};

// [Fx Fy Fz N, Mx My Mz N·m]; 67M25A from the rosjr3 README default, the others [EST] from the
// DATASHEET §4 rating ranges.
constexpr KnownSensor kKnownSensors[] = {
    {"67M25A", {100.0, 100.0, 200.0, 5.0, 5.0, 5.0}},
    {"85M35A", {400.0, 400.0, 800.0, 40.0, 40.0, 40.0}},
    {"50M31A", {100.0, 100.0, 200.0, 6.0, 6.0, 6.0}},
};

[[noreturn]] void Fail(const std::string& what) { throw std::invalid_argument("wrench sensor: " + what); }

std::string KnownSensorNames() {
  std::string names;
  for (const KnownSensor& sensor : kKnownSensors) {
    if (!names.empty()) names += ", ";
    names += sensor.name;
  }
  return names;
}

// checks every axis of `value` is finite and above (or, if allow_zero, at least) zero
void CheckAxes(const Wrench& value, const char* field, bool allow_zero) {
  for (int i = 0; i < 6; ++i) {
    const double v = value[i];
    const bool ok = std::isfinite(v) && (allow_zero ? v >= 0.0 : v > 0.0);
    if (!ok) {
      std::ostringstream message;
      message << field << "[" << i << "] must be " << (allow_zero ? ">= 0" : "> 0") << " and finite (got " << v << ")";
      Fail(message.str());
    }
  }
}

// 2-pole Butterworth low-pass, bilinear transform with the cut-off prewarped
WrenchFilterStage DesignStage(double cutoff_hz, double rate_hz, std::uint64_t decimation) {
  WrenchFilterStage stage;
  const double k = std::tan(kPi * cutoff_hz / rate_hz);
  const double norm = 1.0 / (1.0 + std::sqrt(2.0) * k + k * k);
  stage.b0 = k * k * norm;
  stage.b1 = 2.0 * stage.b0;
  stage.b2 = stage.b0;
  stage.a1 = 2.0 * (k * k - 1.0) * norm;
  stage.a2 = (1.0 - std::sqrt(2.0) * k + k * k) * norm;
  stage.cutoff_hz = cutoff_hz;
  stage.rate_hz = rate_hz;
  stage.decimation = decimation;
  return stage;
}

}  // namespace

Wrench LoadFromMujocoSensor(const double force[3], const double torque[3]) {
  Wrench load;
  load << -force[0], -force[1], -force[2], -torque[0], -torque[1], -torque[2];
  return load;
}

std::unique_ptr<WrenchSensorModel> WrenchSensorModel::Create(const WrenchSensorConfig& config) {
  std::unique_ptr<WrenchSensorModel> model(new WrenchSensorModel());

  // full scale: explicit, or from the sensor model table
  if (config.full_scale) {
    CheckAxes(*config.full_scale, "full_scale", /*allow_zero=*/false);
    model->full_scale_ = *config.full_scale;
  } else {
    const KnownSensor* known = nullptr;
    for (const KnownSensor& sensor : kKnownSensors) {
      if (config.model == sensor.name) known = &sensor;
    }
    if (known == nullptr) {
      Fail("unknown model '" + config.model + "' (known: " + KnownSensorNames() +
           "); give full_scale for a custom sensor");
    }
    for (int i = 0; i < 6; ++i) model->full_scale_[i] = known->full_scale[i];
  }
  model->model_name_ = config.model;
  model->lsb_ = model->full_scale_ / kWrenchCountsPerFullScale;

  if (!std::isfinite(config.sample_rate_hz) || config.sample_rate_hz <= 0.0) {
    std::ostringstream message;
    message << "sample_rate_hz must be > 0 and finite (got " << config.sample_rate_hz << ")";
    Fail(message.str());
  }
  if (config.filter < 0 || config.filter >= kWrenchFilterCount) {
    Fail("filter " + std::to_string(config.filter) + " out of range 0.." + std::to_string(kWrenchFilterCount - 1));
  }

  // noise and bias: explicit, or a fraction of full scale
  const Wrench noise = config.noise_sigma.value_or(model->full_scale_ * kDefaultNoiseFractionOfFullScale);
  const Wrench bias = config.bias_sigma.value_or(model->full_scale_ * kDefaultBiasFractionOfFullScale);
  CheckAxes(noise, "noise_sigma", /*allow_zero=*/true);
  CheckAxes(bias, "bias_sigma", /*allow_zero=*/true);
  model->noise_sigma_ = config.enable_noise ? noise : Wrench::Zero();
  model->bias_sigma_ = config.enable_bias ? bias : Wrench::Zero();

  model->sample_rate_hz_ = config.sample_rate_hz;
  model->filter_ = config.filter;
  model->enable_noise_ = config.enable_noise;
  model->enable_bias_ = config.enable_bias;
  model->enable_quantization_ = config.enable_quantization;
  model->seed_ = config.seed;

  // the cascade: stage k at fs / 4^(k-1), cut-off 1/16 of its own rate
  std::uint64_t decimation = 1;
  for (int k = 1; k < kWrenchFilterCount; ++k) {
    const double rate_hz = config.sample_rate_hz / static_cast<double>(decimation);
    model->stages_[k - 1] = DesignStage(rate_hz * kCutoffToRateRatio, rate_hz, decimation);
    decimation *= kStageDecimation;
  }
  return model;
}

const WrenchFilterStage& WrenchSensorModel::stage(int k) const {
  if (k < 1 || k >= kWrenchFilterCount) k = 1;
  return stages_[k - 1];
}

}  // namespace vlab::sensors
