// The yo-yo of mjcf/yoyo measured (kind yoyo), as the lab's webcam and string
// sensor would: where its centre is, how fast it moves up or down, the
// string's tension and the spin rate.
//
// Ports
//   input   none
//   output  [status, x, y, z, vz, string_force, spin] (bridge/bridge_yoyo.h):
//           the centre site's position (m, world) and vertical velocity (m/s,
//           world: the hand's motion included), the sum of the string's
//           tendonlimitfrc sensors (N, >= 0, 0 while slack) and the spin joint's
//           rate (rad/s); status kYoyoNotSeen when the values are held, not fresh
//   rate    sampled at the end of a control period; with `rate` > 0 Hz a new
//           measurement is taken only in the first period ending at or after
//           each multiple of 1/rate (sample and hold, like a 25 Hz camera), the
//           other periods repeat it with kYoyoNotSeen; the values are those
//           mjData holds after the period's last step (no latency)
//   noise   seeded Gaussian noise of std `noise` (m) on x, y and z of every
//           new measurement; none on the other values
//   log     NAME.z, NAME.vz, NAME.string_force, NAME.spin (as sent) and NAME.depth
//           (d, m: the slide joint, the centre's distance below the hand)
#include <cmath>

#include <nlohmann/json.hpp>

#include "bridge/bridge_layouts.h"

#include "bridge/bridge_yoyo.h"
#include "core/core_errors.h"
#include "lab/devices/device_yoyo.h"
#include "lab/scenario/lab_yaml.h"
#include "sensors/sensor_random.h"

namespace vlab::lab {

namespace {

class SimYoyo final : public Device {
 public:
  SimYoyo(const mjModel* m, const DeviceConfig& c, std::uint64_t seed)
      : Device(c), model_(m), config_(c.ParamsAs<YoyoParams>()), seed_(seed), rng_(seed) {
    const std::string who = c.where + ": device '" + c.name + "': ";
    const int slide = mj_name2id(m, mjOBJ_JOINT, config_.slide.c_str());
    const int spin = mj_name2id(m, mjOBJ_JOINT, config_.spin.c_str());
    if (slide < 0 || m->jnt_type[slide] != mjJNT_SLIDE)
      throw InputError(who + "the scene has no slide joint '" + config_.slide + "'");
    if (spin < 0 || m->jnt_type[spin] != mjJNT_HINGE)
      throw InputError(who + "the scene has no hinge joint '" + config_.spin + "'");
    slide_qpos_ = m->jnt_qposadr[slide];
    spin_dof_ = m->jnt_dofadr[spin];
    centre_ = mj_name2id(m, mjOBJ_SITE, config_.centre.c_str());
    if (centre_ < 0) throw InputError(who + "the scene has no site '" + config_.centre + "'");
    for (const std::string& s : config_.tension) {
      const int id = mj_name2id(m, mjOBJ_SENSOR, s.c_str());
      if (id < 0 || m->sensor_type[id] != mjSENS_TENDONLIMITFRC) {
        throw InputError(who + "the scene has no tendonlimitfrc sensor '" + s + "'");
      }
      tension_.push_back(m->sensor_adr[id]);
    }
  }

  void Reset(const mjData& d) override {
    rng_.Seed(seed_);  // every run from a reset draws the same noise
    last_sample_ = -1;
    Sample(d, d.time);
  }

  void Sample(const mjData& d, double t) override {
    // sample and hold: a new measurement once per 1/rate (every period with rate 0)
    if (config_.rate_hz > 0) {
      const long index = static_cast<long>(std::floor(t * config_.rate_hz + 1e-9));
      fresh_ = index > last_sample_;
      if (!fresh_) return;
      last_sample_ = index;
    }
    fresh_ = true;
    for (int i = 0; i < 3; ++i) {
      p_[i] = d.site_xpos[3 * centre_ + i] + (config_.noise > 0 ? config_.noise * normal_(rng_) : 0.0);
    }
    mjtNum velocity[6];
    mj_objectVelocity(model_, &d, mjOBJ_SITE, centre_, velocity, 0);  // [angular, linear], world frame
    vz_ = velocity[5];
    force_ = 0;
    for (int adr : tension_) force_ += d.sensordata[adr];
    spin_ = d.qvel[spin_dof_];
    depth_ = d.qpos[slide_qpos_];
  }

  void State(std::vector<double>* p) const override {
    p->assign({fresh_ ? 0.0 : static_cast<double>(bridge::kYoyoNotSeen), p_[0], p_[1], p_[2], vz_, force_, spin_});
  }
  std::vector<std::string> Columns() const override {
    std::vector<std::string> out;
    for (const char* c : {"z", "vz", "string_force", "spin", "depth"}) out.push_back(name() + "." + c);
    return out;
  }
  int ColumnCount() const override { return 5; }
  void Row(const mjData&, double* out) const override {
    for (double v : {p_[2], vz_, force_, spin_, depth_}) *out++ = v;
  }

  std::string DescribeFacts() const override {
    nlohmann::json j;
    j["layout"] = bridge::LayoutJson(kind());
    j["units"] = {{"x", "m"}, {"vz", "m/s"}, {"string_force", "N"}, {"spin", "rad/s"}};
    j["frame"] = "world";
    j["status_bits"] = {{"not_seen", bridge::kYoyoNotSeen}};
    j["rate_hz"] = config_.rate_hz;  // 0: every control period
    j["noise"] = config_.noise;
    j["joints"] = {{"slide", config_.slide}, {"spin", config_.spin}};
    j["site"] = config_.centre;
    j["tension_sensors"] = config_.tension;
    return j.dump();
  }

 private:
  const mjModel* model_;
  YoyoParams config_;
  std::uint64_t seed_;
  sensors::Xoshiro256pp rng_;
  sensors::ZigguratNormal normal_;
  int slide_qpos_ = -1, spin_dof_ = -1, centre_ = -1;
  std::vector<int> tension_;  // sensordata addresses
  long last_sample_ = -1;     // index of the last measurement (rate > 0)
  bool fresh_ = true;
  double p_[3] = {0, 0, 0};
  double vz_ = 0, force_ = 0, spin_ = 0, depth_ = 0;
};

}  // namespace

std::shared_ptr<const DeviceParams> ReadYoyoParams(MapReader& r) {
  auto p = std::make_shared<YoyoParams>();

  p->slide = r.String("slide", p->slide);
  p->spin = r.String("spin", p->spin);
  p->centre = r.String("centre", p->centre);
  p->tension = r.Strings("tension", p->tension);
  if (p->tension.empty()) r.Fail("tension", "needs at least one tendonlimitfrc sensor");
  p->rate_hz = r.Number("rate", p->rate_hz);
  if (!(p->rate_hz >= 0)) r.Fail("rate", "must be >= 0 Hz (0: every control period)");
  p->noise = r.Number("noise", p->noise);
  if (!(p->noise >= 0)) r.Fail("noise", "must be >= 0 m");
  return p;
}

std::unique_ptr<Device> MakeYoyo(const DeviceContext& context, const DeviceConfig& config) {
  return std::make_unique<SimYoyo>(context.model, config, context.seed);
}

}  // namespace vlab::lab
