#include "lab/lab_wrench_device.h"

#include "core/core_errors.h"

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

}  // namespace

std::unique_ptr<SimWrench> SimWrench::Create(const mjModel* m, const DeviceConfig& c, std::uint64_t seed) {
  std::unique_ptr<SimWrench> w(new SimWrench());
  w->name_ = c.name;
  const int force = SensorAddress(m, c, c.wrench.force_sensor, mjSENS_FORCE, "force");
  const int torque = SensorAddress(m, c, c.wrench.torque_sensor, mjSENS_TORQUE, "torque");
  if (m->sensor_objid[force] != m->sensor_objid[torque]) {
    throw InputError(c.where + ": device '" + c.name + "': force and torque sensors are at different sites");
  }
  if (!c.wrench.site.empty()) {
    const int site = mj_name2id(m, mjOBJ_SITE, c.wrench.site.c_str());
    if (site < 0) throw InputError(c.where + ": device '" + c.name + "': no site '" + c.wrench.site + "'");
    if (site != m->sensor_objid[force]) {
      throw InputError(c.where + ": device '" + c.name + "': sensors are not at site '" + c.wrench.site + "'");
    }
  }
  w->force_adr_ = m->sensor_adr[force];
  w->torque_adr_ = m->sensor_adr[torque];

  sensors::WrenchSensorConfig sc;
  sc.model = c.wrench.model;
  if (!c.wrench.full_scale.empty()) sc.full_scale = Eigen::Map<const sensors::Wrench>(c.wrench.full_scale.data());
  sc.filter = c.wrench.filter;
  sc.enable_noise = c.wrench.noise;
  sc.enable_bias = c.wrench.bias;
  sc.enable_quantization = c.wrench.quantization;
  sc.seed = seed;
  try {
    w->sensor_ = sensors::WrenchSensorModel::Create(sc);
  } catch (const std::invalid_argument& e) {
    throw InputError(c.where + ": device '" + c.name + "': " + e.what());
  }
  return w;
}

sensors::Wrench SimWrench::TrueLoad(const mjData& d) const {
  return sensors::LoadFromMujocoSensor(d.sensordata + force_adr_, d.sensordata + torque_adr_);
}

void SimWrench::Reset(const mjData& d) {
  sensors::Reset(*sensor_, state_, TrueLoad(d));
  reading_ = sensors::Read(*sensor_, state_);
  saturated_ = false;
  saturated_in_period_ = false;
}

void SimWrench::Step(const mjData& d, double dt) {
  sensors::WrenchReading flags;
  sensors::Advance(*sensor_, state_, TrueLoad(d), dt, &flags);
  saturated_in_period_ = saturated_in_period_ || flags.saturated;
}

void SimWrench::EndPeriod() {
  reading_ = sensors::Read(*sensor_, state_);
  saturated_ = saturated_in_period_;
  saturated_in_period_ = false;
}

void SimWrench::Sample(double time_s, bridge::WrenchState* s) const {
  s->time_s = time_s;
  s->wrench = reading_.wrench;
  s->filter = reading_.filter;
  s->saturated = saturated_;
}

std::vector<std::string> SimWrench::Columns() const {
  std::vector<std::string> columns;
  for (const char* axis : {"Fx", "Fy", "Fz", "Mx", "My", "Mz"}) columns.push_back(name_ + "." + axis);
  columns.push_back(name_ + ".saturated");
  return columns;
}

void SimWrench::Row(double* out) const {
  for (int i = 0; i < 6; ++i) out[i] = reading_.wrench[i];
  out[6] = saturated_ ? 1.0 : 0.0;
}

}  // namespace vlab::lab
