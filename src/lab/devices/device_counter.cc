// A speed counter (kind counter), like the PowerBall's own rpm counter or a
// tachometer on a shaft: it counts the turns of an MJCF hinge joint and reads
// the speed as the turns counted over a gate time.
//
// Ports
//   input   none
//   output  [revolutions, rpm]: the signed whole turns since the start of the
//           run (the joint's angle from its start, floor(Δθ / 2π)), and the
//           speed of the last gate, Δθ / gate (rpm), rounded to `resolution`
//   rate    the speed is read every 1 / rate s (the gate time; rate 0: every
//           control period) and held between readings; the turns are counted
//           at every control period; a reading is due at the first period end
//           at or after its time (gates are whole control periods)
//   log     NAME.revolutions, NAME.rpm (the output), NAME.true_rpm (the joint's
//           speed at the period end, lab ground truth); with `powerball: true` also
//           the ball's truth (powerball_truth.h): NAME.spin_rpm (rotor spin relative to
//           the shell), NAME.precess_rate (rad/s, relative to the shell), NAME.slip
//           (tip slip ratio) and NAME.moment (N m, |wall couple|)
// A gate-time counter reads the mean speed over its gate, not the speed at its
// end: it lags a spin-up by half a gate.
#include <cmath>

#include <nlohmann/json.hpp>

#include "bridge/bridge_layouts.h"
#include "core/core_clock.h"
#include "core/core_errors.h"
#include "lab/devices/device_counter.h"
#include "lab/devices/powerball_truth.h"
#include "lab/outputs/lab_log.h"
#include "lab/scenario/lab_yaml.h"

namespace vlab::lab {

namespace {

class SimCounter final : public Device {
 public:
  SimCounter(const DeviceContext& context, const DeviceConfig& c) : Device(c), config_(c.ParamsAs<CounterParams>()) {
    const mjModel* m = context.model;
    model_ = m;
    if (config_.powerball) ball_ = PowerballBinding::Bind(*m, who());
    const double period_s = context.control_period_s;
    const int joint = mj_name2id(m, mjOBJ_JOINT, config_.joint.c_str());
    if (joint < 0) throw InputError(who() + ": the scene has no joint '" + config_.joint + "'");
    if (m->jnt_type[joint] != mjJNT_HINGE) throw InputError(who() + ": joint '" + config_.joint + "' is not a hinge");
    qpos_adr_ = m->jnt_qposadr[joint];
    dof_adr_ = m->jnt_dofadr[joint];
    gate_s_ = config_.rate_hz > 0 ? 1.0 / config_.rate_hz : period_s;
    if (gate_s_ < period_s - kSameTime_s) {
      throw InputError(who() + ": rate " + FormatDouble(config_.rate_hz) + " Hz is faster than the control rate (" +
                       FormatDouble(1.0 / period_s) + " Hz)");
    }
  }

  void Reset(const mjData& d) override {
    angle_start_ = gate_angle_ = d.qpos[qpos_adr_];
    gate_start_ = d.time;
    next_reading_ = d.time + gate_s_;
    rpm_ = 0;
    Sample(d, d.time);
  }

  void Sample(const mjData& d, double t) override {
    const double angle = d.qpos[qpos_adr_];
    revolutions_ = std::floor((angle - angle_start_) / (2.0 * M_PI));
    true_rpm_ = d.qvel[dof_adr_] * kRpmPerRadPerSecond;
    if (!CounterReadingDue(t, gate_s_, &next_reading_)) return;
    // a reading: the turns over the gate that ends now
    const double rpm = (angle - gate_angle_) / (t - gate_start_) * kRpmPerRadPerSecond;
    rpm_ = config_.resolution > 0 ? std::round(rpm / config_.resolution) * config_.resolution : rpm;
    gate_angle_ = angle;
    gate_start_ = t;
  }

  void State(std::vector<double>* p) const override { p->assign({revolutions_, rpm_}); }
  std::vector<std::string> Columns() const override {
    std::vector<std::string> columns = {name() + ".revolutions", name() + ".rpm", name() + ".true_rpm"};
    if (config_.powerball) {
      for (const char* truth : {".spin_rpm", ".precess_rate", ".slip", ".moment"}) columns.push_back(name() + truth);
    }
    return columns;
  }
  int ColumnCount() const override { return config_.powerball ? 7 : 3; }
  void Row(const mjData& d, double* out) const override {
    out[0] = revolutions_;
    out[1] = rpm_;
    out[2] = true_rpm_;
    if (!config_.powerball) return;
    const PowerballTruth truth = MeasurePowerball(*model_, d, ball_);
    out[3] = truth.Rpm();
    out[4] = truth.nu;
    out[5] = truth.slip;
    out[6] = truth.CoupleNorm();
  }

  std::string DescribeFacts() const override {
    nlohmann::json j;
    j["layout"] = bridge::LayoutJson(kind());
    j["units"] = {{"revolutions", "turns"}, {"rpm", "1/min"}};
    j["joint"] = config_.joint;
    j["gate_s"] = gate_s_;
    j["resolution_rpm"] = config_.resolution;
    return j.dump();
  }

 private:
  CounterParams config_;
  const mjModel* model_ = nullptr;
  PowerballBinding ball_;
  int qpos_adr_ = -1, dof_adr_ = -1;
  double gate_s_ = 0;
  double angle_start_ = 0, gate_angle_ = 0, gate_start_ = 0, next_reading_ = 0;
  double revolutions_ = 0, rpm_ = 0, true_rpm_ = 0;
};

}  // namespace

bool CounterReadingDue(double t, double gate_s, double* next_s) {
  if (t + kSameTime_s < *next_s) return false;
  *next_s += gate_s;
  if (*next_s < t + kSameTime_s) *next_s = t + gate_s;  // a gate shorter than a period: catch up
  return true;
}

std::shared_ptr<const DeviceParams> ReadCounterParams(MapReader& r) {
  auto p = std::make_shared<CounterParams>();
  p->joint = r.String("joint");
  p->rate_hz = r.Number("rate", p->rate_hz);
  if (!(p->rate_hz >= 0 && std::isfinite(p->rate_hz))) r.Fail("rate", "must be >= 0 Hz (0: every control period)");
  p->resolution = r.Number("resolution", p->resolution);
  if (!(p->resolution >= 0 && std::isfinite(p->resolution))) r.Fail("resolution", "must be >= 0 rpm (0: none)");
  p->powerball = r.Bool("powerball", p->powerball);
  return p;
}

std::unique_ptr<Device> MakeCounter(const DeviceContext& context, const DeviceConfig& config) {
  return std::make_unique<SimCounter>(context, config);
}

}  // namespace vlab::lab
