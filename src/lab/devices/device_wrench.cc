#include "lab/devices/device_wrench.h"

#include "bridge/bridge_describe.h"
#include "bridge/bridge_messages.h"
#include "core/core_errors.h"
#include "lab/scenario/lab_yaml.h"

namespace vlab::lab {

namespace {

int SensorAddress(const mjModel* m, const DeviceConfig& c, const std::string& name, int type, const char* what) {
  const int id = mj_name2id(m, mjOBJ_SENSOR, name.c_str());
  if (id < 0) throw InputError(c.where + ": device '" + c.name + "': no sensor '" + name + "' in the scene");
  if (m->sensor_type[id] != type) {
    throw InputError(c.where + ": device '" + c.name + "': sensor '" + name + "' is not a " + what + " sensor");
  }
  return id;
}

class SimWrench final : public Device, public StepHooks {
 public:
  SimWrench(const DeviceContext& context, const DeviceConfig& c) : Device(c) {
    capabilities_.step_hooks = this;
    const mjModel* m = context.model;
    const WrenchParams& p = c.ParamsAs<WrenchParams>();
    const int force = SensorAddress(m, c, p.force_sensor, mjSENS_FORCE, "force");
    const int torque = SensorAddress(m, c, p.torque_sensor, mjSENS_TORQUE, "torque");
    if (m->sensor_objid[force] != m->sensor_objid[torque]) {
      throw InputError(who() + ": force and torque sensors are at different sites");
    }
    if (!p.site.empty()) {
      const int site = mj_name2id(m, mjOBJ_SITE, p.site.c_str());
      if (site < 0) throw InputError(who() + ": no site '" + p.site + "'");
      if (site != m->sensor_objid[force]) throw InputError(who() + ": sensors are not at site '" + p.site + "'");
    }
    force_adr_ = m->sensor_adr[force];
    torque_adr_ = m->sensor_adr[torque];

    try {
      sensor_ = sensors::WrenchSensorModel::Create(WrenchSensorConfigOf(p, context.seed));
    } catch (const std::invalid_argument& e) {
      throw InputError(who() + ": " + e.what());
    }
  }

  // restarts the sensor (new bias from the seed, filters settled on the current load)
  void Reset(const mjData& d) override {
    sensors::Reset(*sensor_, state_, TrueLoad(d));
    reading_ = sensors::Read(*sensor_, state_);
    saturated_ = false;
    saturated_in_period_ = false;
  }
  // feeds the load of the physics step just taken
  void AfterStep(const mjData& d, double dt) override {
    sensors::WrenchReading flags;
    sensors::Advance(*sensor_, state_, TrueLoad(d), dt, &flags);
    saturated_in_period_ = saturated_in_period_ || flags.saturated;
  }
  // forms the host's reading at the end of a control period
  void Sample(const mjData&, double) override {
    reading_.wrench = sensors::ReadSelected(*sensor_, state_);  // (the filter is the one Reset read)
    saturated_ = saturated_in_period_;
    saturated_in_period_ = false;
  }

  std::vector<std::string> Columns() const override {
    std::vector<std::string> columns;
    for (const char* axis : kWrenchAxes) columns.push_back(name() + "." + axis);
    columns.push_back(name() + ".saturated");
    return columns;
  }
  int ColumnCount() const override { return 7; }
  void Row(const mjData&, double* out) const override {
    for (int i = 0; i < 6; ++i) out[i] = reading_.wrench[i];
    out[6] = saturated_ ? 1.0 : 0.0;
  }
  int log_rank() const override { return 1; }

  void EncodeState(double seq, double t, std::uint32_t, std::vector<double>*,
                   std::vector<unsigned char>* out) const override {
    bridge::WrenchStateMsg m;
    for (int i = 0; i < 6; ++i) m.wrench[i] = reading_.wrench[i];
    m.filter = reading_.filter;
    m.saturated = saturated_;
    bridge::EncodeWrenchState(seq, t, m, out);
  }
  std::string DescribeJson(const bridge::DeviceDescription& common) const override {
    bridge::WrenchDescription desc;
    desc.sensor_model = sensor_->model_name();
    desc.full_scale.assign(sensor_->full_scale().data(), sensor_->full_scale().data() + 6);
    desc.filter = sensor_->filter();
    desc.filter_cutoff_hz = desc.filter > 0 ? sensor_->stage(desc.filter).cutoff_hz : 0.0;
    desc.sample_hz = sensor_->sample_rate_hz();
    static_cast<bridge::DeviceDescription&>(desc) = common;
    return bridge::DescribeJson(desc);
  }

 private:
  sensors::Wrench TrueLoad(const mjData& d) const {
    return sensors::LoadFromMujocoSensor(d.sensordata + force_adr_, d.sensordata + torque_adr_);
  }

  int force_adr_ = -1, torque_adr_ = -1;
  std::unique_ptr<sensors::WrenchSensorModel> sensor_;
  sensors::WrenchSensorState state_;
  sensors::WrenchReading reading_;
  bool saturated_in_period_ = false;  // since the last Sample
  bool saturated_ = false;            // during the period the reading closes
};

}  // namespace

sensors::WrenchSensorConfig WrenchSensorConfigOf(const WrenchParams& p, std::uint64_t seed) {
  sensors::WrenchSensorConfig sc;
  sc.model = p.model;
  if (!p.full_scale.empty()) sc.full_scale = Eigen::Map<const sensors::Wrench>(p.full_scale.data());
  sc.filter = p.filter;
  sc.enable_noise = p.noise;
  sc.enable_bias = p.bias;
  sc.enable_quantization = p.quantization;
  sc.seed = seed;
  return sc;
}

std::shared_ptr<const DeviceParams> ReadWrenchParams(MapReader& r) {
  auto w = std::make_shared<WrenchParams>();
  w->site = r.String("site", "");
  w->force_sensor = r.String("force_sensor");
  w->torque_sensor = r.String("torque_sensor");
  w->model = r.String("model", w->model);
  w->full_scale = r.Numbers("full_scale", {});
  if (!w->full_scale.empty() && w->full_scale.size() != 6) {
    r.Fail("full_scale", "expected 6 numbers (N, N, N, N·m, N·m, N·m)");
  }
  w->filter = r.Integer("filter", w->filter);
  if (w->filter < 0 || w->filter > 6) r.Fail("filter", "must be 0 (unfiltered) to 6");
  w->noise = r.Bool("noise", w->noise);
  w->bias = r.Bool("bias", w->bias);
  w->quantization = r.Bool("quantization", w->quantization);
  return w;
}

std::unique_ptr<Device> MakeWrench(const DeviceContext& context, const DeviceConfig& config) {
  return std::make_unique<SimWrench>(context, config);
}

}  // namespace vlab::lab
