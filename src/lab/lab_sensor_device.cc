// Feet and IMU devices: MJCF sensors read as they are, with optional seeded
// Gaussian noise.
//
// Ports
//   input   none
//   output  feet: one normal force per force-sensing resistor (MJCF touch
//           sensors), N; imu: the gyro (rad/s) and accelerometer (m/s^2,
//           specific force: reads +g upwards at rest) values, sensor frame
//   rate    sampled at the end of every control period
#include <cmath>

#include <nlohmann/json.hpp>

#include "lab/lab_device.h"
#include "lab/lab_errors.h"
#include "sensors/sensor_random.h"

namespace vlab::lab {

namespace {

class SimSensorDevice final : public SimDevice {
 public:
  SimSensorDevice(const mjModel* m, const DeviceConfig& c, std::uint64_t seed)
      : SimDevice(c.name), kind_(c.kind == "feet" ? bridge::DeviceKind::kFeet : bridge::DeviceKind::kImu),
        noise_(c.sensors.noise), rng_(seed) {
    for (const std::string& s : c.sensors.sensors) {
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
  }

  bridge::DeviceKind kind() const override { return kind_; }

  void Sample(const mjData& d, double) override {
    for (std::size_t i = 0; i < address_.size(); ++i) {
      values_[i] = d.sensordata[address_[i]] + (noise_ > 0 ? noise_ * normal_(rng_) : 0.0);
    }
  }
  void State(std::vector<double>* payload) const override { payload->assign(values_.begin(), values_.end()); }
  std::vector<std::string> Columns() const override {
    std::vector<std::string> out;
    for (const std::string& n : names_) out.push_back(name() + "." + n);
    return out;
  }
  int ColumnCount() const override { return static_cast<int>(names_.size()); }
  void Row(double* out) const override {
    for (double v : values_) *out++ = v;
  }

  std::string DescribeFacts() const override {
    nlohmann::json j;
    j["layout"] = {{"state", names_}, {"command", nlohmann::json::array()}};
    if (kind_ == bridge::DeviceKind::kFeet) {
      j["units"] = {{"force", "N"}};
    } else {
      j["units"] = {{"gyro", "rad/s"}, {"accelerometer", "m/s^2 (specific force, +g up at rest)"},
                    {"frame", "sensor site"}};
    }
    j["sensors"] = sensors_;
    j["sensor_types"] = types_;
    j["noise_std"] = noise_;
    return j.dump();
  }

 private:
  bridge::DeviceKind kind_;
  double noise_;
  std::vector<int> address_;
  std::vector<std::string> names_, sensors_, types_;
  std::vector<double> values_;
  sensors::Xoshiro256pp rng_;
  sensors::ZigguratNormal normal_;
};

}  // namespace

std::unique_ptr<SimDevice> MakeSensorDevice(const mjModel* m, const DeviceConfig& config, std::uint64_t seed) {
  return std::make_unique<SimSensorDevice>(m, config, seed);
}

}  // namespace vlab::lab
