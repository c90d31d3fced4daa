// Feet and IMU devices: MJCF sensors read as they are, with optional seeded
// Gaussian noise.
//
// Ports
//   input   none
//   output  feet: one normal force per force-sensing resistor (MJCF touch
//           sensors), N; imu: the gyro (rad/s) and accelerometer (m/s^2,
//           specific force: reads +g upwards at rest) values, sensor frame
//   rate    sampled at the end of every control period
//   log     the values; feet with `pads` and/or `weight_of` also log (not on
//           the wire) NAME.sum (N), NAME.sum_error (sum / weight - 1), and
//           NAME.cop_x, NAME.cop_y (world, m), NAME.cop_margin (m, signed
//           distance of the centre of pressure to the edge of the support
//           polygon, positive inside), from the pads reading more than
//           contact_threshold (NaN when none does)
#include <cmath>
#include <limits>

#include <nlohmann/json.hpp>

#include "bridge/bridge_layouts.h"

#include "core/core_errors.h"
#include "lab/devices/device_sensors.h"
#include "lab/devices/support_polygon.h"
#include "lab/scenario/lab_yaml.h"
#include "sensors/sensor_random.h"

namespace vlab::lab {

namespace {

class SimSensorDevice final : public Device {
 public:
  SimSensorDevice(const mjModel* m, const DeviceConfig& c, std::uint64_t seed)
      : Device(c), kind_(c.kind), noise_(c.ParamsAs<SensorParams>().noise), rng_(seed) {
    for (const std::string& s : c.ParamsAs<SensorParams>().sensors) {
      const int id = mj_name2id(m, mjOBJ_SENSOR, s.c_str());
      if (id < 0) throw InputError(c.where + ": device '" + c.name + "': the scene has no sensor '" + s + "'");
      const int type = m->sensor_type[id];
      if (kind_ == bridge::DeviceKind::kFeet && type != mjSENS_TOUCH) {
        throw InputError(c.where + ": device '" + c.name + "': sensor '" + s + "' is not a touch sensor");
      }
      if (kind_ == bridge::DeviceKind::kImu && type != mjSENS_GYRO && type != mjSENS_ACCELEROMETER) {
        throw InputError(c.where + ": device '" + c.name + "': sensor '" + s +
                         "' is neither a gyro nor an accelerometer");
      }
      const int dim = m->sensor_dim[id];
      const char* axes[3] = {"x", "y", "z"};
      for (int k = 0; k < dim; ++k) {
        address_.push_back(m->sensor_adr[id] + k);
        names_.push_back(dim == 1 ? s : s + "." + axes[k]);
      }
      sensors_.push_back(s);
      types_.push_back(type == mjSENS_TOUCH ? "touch" : type == mjSENS_GYRO ? "gyro" : "accelerometer");
    }
    values_.assign(address_.size(), 0.0);
    if (kind_ == bridge::DeviceKind::kFeet) BindSupport(m, c);
  }

  void Sample(const mjData& d, double) override {
    for (std::size_t i = 0; i < address_.size(); ++i) {
      values_[i] = d.sensordata[address_[i]] + (noise_ > 0 ? noise_ * normal_(rng_) : 0.0);
    }
    if (sum_column_) SampleSupport(d);
  }
  void State(std::vector<double>* payload) const override { payload->assign(values_.begin(), values_.end()); }
  std::vector<std::string> Columns() const override {
    std::vector<std::string> out;
    for (const std::string& n : names_) out.push_back(name() + "." + n);
    if (sum_column_) out.push_back(name() + ".sum");
    if (weight_N_ > 0) out.push_back(name() + ".sum_error");
    if (!pad_sites_.empty()) {
      for (const char* c : {".cop_x", ".cop_y", ".cop_margin"}) out.push_back(name() + c);
    }
    return out;
  }
  int ColumnCount() const override {
    return static_cast<int>(names_.size()) + (sum_column_ ? 1 : 0) + (weight_N_ > 0 ? 1 : 0) +
           (pad_sites_.empty() ? 0 : 3);
  }
  void Row(const mjData&, double* out) const override {
    for (double v : values_) *out++ = v;
    if (sum_column_) *out++ = sum_N_;
    if (weight_N_ > 0) *out++ = sum_N_ / weight_N_ - 1.0;
    if (!pad_sites_.empty()) {
      *out++ = cop_W_.x();
      *out++ = cop_W_.y();
      *out++ = cop_margin_m_;
    }
  }

  std::string DescribeFacts() const override {
    nlohmann::json j;
    j["layout"] = bridge::LayoutJson(kind(), names_);
    if (kind_ == bridge::DeviceKind::kFeet) {
      j["units"] = {{"force", "N"}};
    } else {
      j["units"] = {
          {"gyro", "rad/s"}, {"accelerometer", "m/s^2 (specific force, +g up at rest)"}, {"frame", "sensor site"}};
    }
    j["sensors"] = sensors_;
    j["sensor_types"] = types_;
    j["noise_std"] = noise_;
    if (!pad_names_.empty()) j["pads"] = pad_names_;
    if (weight_N_ > 0) j["weight_N"] = weight_N_;
    return j.dump();
  }

 private:
  // feet: the pad sites, the reference weight, and buffers sized once
  void BindSupport(const mjModel* m, const DeviceConfig& c) {
    const SensorParams& f = c.ParamsAs<SensorParams>();
    if (!f.pads.empty() && f.pads.size() != sensors_.size()) {
      throw InputError(c.where + ": device '" + c.name + "': pads: needs one site per sensor (" +
                       std::to_string(sensors_.size()) + ")");
    }
    for (const std::string& site : f.pads) {
      const int id = mj_name2id(m, mjOBJ_SITE, site.c_str());
      if (id < 0) throw InputError(c.where + ": device '" + c.name + "': pads: the scene has no site '" + site + "'");
      pad_sites_.push_back(id);
    }
    pad_names_ = f.pads;
    if (!f.weight_of.empty()) {
      const int body = mj_name2id(m, mjOBJ_BODY, f.weight_of.c_str());
      if (body < 0) {
        throw InputError(c.where + ": device '" + c.name + "': weight_of: the scene has no body '" + f.weight_of + "'");
      }
      const mjtNum* g = m->opt.gravity;
      weight_N_ = m->body_subtreemass[body] * std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
      if (!(weight_N_ > 0)) {
        throw InputError(c.where + ": device '" + c.name + "': weight_of: body '" + f.weight_of +
                         "' weighs nothing (no mass or no gravity)");
      }
    }
    threshold_N_ = f.contact_threshold;
    sum_column_ = !pad_sites_.empty() || weight_N_ > 0;
    contacts_.reserve(pad_sites_.size());
    hull_.reserve(2 * pad_sites_.size() + 1);
  }

  // sum of the readings; CoP and its margin from the pads in contact
  void SampleSupport(const mjData& d) {
    sum_N_ = 0;
    for (double v : values_) sum_N_ += v;
    if (pad_sites_.empty()) return;
    contacts_.clear();
    double loaded_N = 0;
    Eigen::Vector2d moment = Eigen::Vector2d::Zero();
    for (std::size_t i = 0; i < pad_sites_.size(); ++i) {
      if (!(values_[i] > threshold_N_)) continue;
      const Eigen::Vector2d p(d.site_xpos[3 * pad_sites_[i]], d.site_xpos[3 * pad_sites_[i] + 1]);
      contacts_.push_back(p);
      loaded_N += values_[i];
      moment += values_[i] * p;
    }
    if (contacts_.empty()) {
      cop_W_.setConstant(std::numeric_limits<double>::quiet_NaN());
      cop_margin_m_ = std::numeric_limits<double>::quiet_NaN();
      return;
    }
    cop_W_ = moment / loaded_N;
    ConvexHull(contacts_, &hull_);
    cop_margin_m_ = SignedDistanceToHull(hull_, cop_W_);
  }

  bridge::DeviceKind kind_;
  double noise_;
  std::vector<int> address_;
  std::vector<std::string> names_, sensors_, types_;
  std::vector<double> values_;
  std::vector<int> pad_sites_;
  std::vector<std::string> pad_names_;
  double weight_N_ = 0, threshold_N_ = 0;
  bool sum_column_ = false;
  double sum_N_ = 0, cop_margin_m_ = 0;
  Eigen::Vector2d cop_W_ = Eigen::Vector2d::Zero();
  std::vector<Eigen::Vector2d> contacts_, hull_;
  sensors::Xoshiro256pp rng_;
  sensors::ZigguratNormal normal_;
};

// the keys of both kinds
std::shared_ptr<SensorParams> ReadSensorParams(MapReader& r) {
  auto p = std::make_shared<SensorParams>();
  p->sensors = r.Strings("sensors", {});
  if (p->sensors.empty()) r.Fail("sensors", "needs at least one MJCF sensor");
  p->noise = r.Number("noise", 0.0);
  if (!(p->noise >= 0)) r.Fail("noise", "must be >= 0");
  return p;
}

}  // namespace

std::shared_ptr<const DeviceParams> ReadFeetParams(MapReader& r) {
  std::shared_ptr<SensorParams> p = ReadSensorParams(r);
  p->pads = r.Strings("pads", {});
  if (!p->pads.empty() && p->pads.size() != p->sensors.size()) {
    r.Fail("pads", "needs one site per sensor (" + std::to_string(p->sensors.size()) + ")");
  }
  p->weight_of = r.String("weight_of", "");
  p->contact_threshold = r.Number("contact_threshold", p->contact_threshold);
  if (!(p->contact_threshold >= 0)) r.Fail("contact_threshold", "must be >= 0 N");
  return p;
}

std::shared_ptr<const DeviceParams> ReadImuParams(MapReader& r) { return ReadSensorParams(r); }

std::unique_ptr<Device> MakeSensors(const DeviceContext& context, const DeviceConfig& config) {
  return std::make_unique<SimSensorDevice>(context.model, config, context.seed);
}

}  // namespace vlab::lab
