// A tracked frame (kind pose), like a motion-capture system's rigid body: the
// pose of an MJCF site in the frame of a body (the world, a robot's base), with
// how far it has moved since the start and how far it is from a target site.
//
// Ports
//   input   none
//   output  [x, y, z, qw, qx, qy, qz]: the site's position (m) and orientation
//           (unit quaternion) in the reference body's frame
//   rate    sampled at the end of every control period (ground truth: no
//           noise, no latency)
//   log     NAME.x, NAME.y, NAME.z (m); NAME.drift (m) and NAME.rot_drift
//           (rad): distance and rotation angle from the pose at the start of
//           the run; with a target, NAME.error (m): distance to the target
//           site, in the same frame
#include <cmath>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "bridge/bridge_layouts.h"

#include "core/core_errors.h"
#include "lab/devices/device_pose.h"
#include "lab/scenario/lab_yaml.h"

namespace vlab::lab {

namespace {

class SimPose final : public Device {
 public:
  SimPose(const mjModel* m, const DeviceConfig& c) : Device(c), config_(c.ParamsAs<PoseParams>()) {
    site_ = Id(m, c, mjOBJ_SITE, "site", config_.site);
    body_ = Id(m, c, mjOBJ_BODY, "body", config_.relative_to);
    if (!config_.target.empty()) target_ = Id(m, c, mjOBJ_SITE, "site", config_.target);
  }

  void Reset(const mjData& d) override {
    Measure(d, &p_start_, &q_start_);
    Sample(d, d.time);
  }

  void Sample(const mjData& d, double) override {
    Measure(d, &p_, &q_);
    drift_ = (p_ - p_start_).norm();
    rot_drift_ = q_start_.angularDistance(q_);
    if (target_ >= 0) {
      const Eigen::Vector3d p_target = Eigen::Map<const Eigen::Vector3d>(d.site_xpos + 3 * target_);
      error_ = (p_ - InReference(d, p_target)).norm();
    }
  }

  void State(std::vector<double>* p) const override {
    p->assign({p_.x(), p_.y(), p_.z(), q_.w(), q_.x(), q_.y(), q_.z()});
  }
  std::vector<std::string> Columns() const override {
    std::vector<std::string> out;
    for (const char* c : {"x", "y", "z", "drift", "rot_drift"}) out.push_back(name() + "." + c);
    if (target_ >= 0) out.push_back(name() + ".error");
    return out;
  }
  int ColumnCount() const override { return target_ >= 0 ? 6 : 5; }
  void Row(const mjData&, double* out) const override {
    for (double v : {p_.x(), p_.y(), p_.z(), drift_, rot_drift_}) *out++ = v;
    if (target_ >= 0) *out = error_;
  }

  std::string DescribeFacts() const override {
    nlohmann::json j;
    j["layout"] = bridge::LayoutJson(kind());
    j["units"] = {{"x", "m"}, {"qw", "unit quaternion"}};
    j["site"] = config_.site;
    j["frame"] = config_.relative_to;
    if (target_ >= 0) j["target"] = config_.target;
    return j.dump();
  }

 private:
  static int Id(const mjModel* m, const DeviceConfig& c, mjtObj type, const char* what, const std::string& name) {
    const int id = mj_name2id(m, type, name.c_str());
    if (id < 0) throw InputError(c.where + ": device '" + c.name + "': the scene has no " + what + " '" + name + "'");
    return id;
  }
  // a world point in the reference body's frame
  Eigen::Vector3d InReference(const mjData& d, const Eigen::Vector3d& p_W) const {
    const Eigen::Vector3d p_WB = Eigen::Map<const Eigen::Vector3d>(d.xpos + 3 * body_);
    const Eigen::Matrix3d R_WB = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(d.xmat + 9 * body_);
    return R_WB.transpose() * (p_W - p_WB);
  }
  void Measure(const mjData& d, Eigen::Vector3d* p, Eigen::Quaterniond* q) const {
    const Eigen::Matrix3d R_WB = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(d.xmat + 9 * body_);
    const Eigen::Matrix3d R_WS =
        Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(d.site_xmat + 9 * site_);
    *p = InReference(d, Eigen::Map<const Eigen::Vector3d>(d.site_xpos + 3 * site_));
    *q = Eigen::Quaterniond(R_WB.transpose() * R_WS).normalized();
  }

  PoseParams config_;
  int site_ = -1, body_ = -1, target_ = -1;
  Eigen::Vector3d p_ = Eigen::Vector3d::Zero(), p_start_ = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_ = Eigen::Quaterniond::Identity(), q_start_ = Eigen::Quaterniond::Identity();
  double drift_ = 0, rot_drift_ = 0, error_ = 0;
};

}  // namespace

std::shared_ptr<const DeviceParams> ReadPoseParams(MapReader& r) {
  auto p = std::make_shared<PoseParams>();
  p->site = r.String("site");
  p->relative_to = r.String("relative_to", p->relative_to);
  p->target = r.String("target", "");
  return p;
}

std::unique_ptr<Device> MakePose(const DeviceContext& context, const DeviceConfig& config) {
  return std::make_unique<SimPose>(context.model, config);
}

}  // namespace vlab::lab
