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
//           site, in the same frame; with grippers (lab-only truth, from the
//           contacts at the period's end), NAME.holders: how many of the
//           grippers hold the site's body (two of a gripper's finger bodies, the
//           child bodies of its body, touch it) and NAME.free_time (s): how long
//           the body has touched nothing (0 while it touches anything: a body
//           that falls shows the time it has been falling)
#include <algorithm>
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
  SimPose(const mjModel* m, const DeviceConfig& c) : Device(c), config_(c.ParamsAs<PoseParams>()), model_(m) {
    site_ = Id(m, c, mjOBJ_SITE, "site", config_.site);
    body_ = Id(m, c, mjOBJ_BODY, "body", config_.relative_to);
    if (!config_.target.empty()) target_ = Id(m, c, mjOBJ_SITE, "site", config_.target);
    tracked_body_ = m->site_bodyid[site_];
    // each gripper's fingers: the bodies whose parent is the gripper's body
    finger_gripper_.assign(m->nbody, -1);
    for (std::size_t g = 0; g < config_.grippers.size(); ++g) {
      const int b = Id(m, c, mjOBJ_BODY, "body", config_.grippers[g]);
      int fingers = 0;
      for (int k = 1; k < m->nbody; ++k) {
        if (m->body_parentid[k] == b) {
          finger_gripper_[k] = static_cast<int>(g);
          ++fingers;
        }
      }
      if (fingers < 2) {
        throw InputError(c.where + ": device '" + c.name + "': grippers: body '" + config_.grippers[g] + "' has " +
                         std::to_string(fingers) + " child bodies; a gripper needs two fingers");
      }
    }
    touching_.assign(config_.grippers.size(), 0);
    first_finger_.assign(config_.grippers.size(), -1);
  }

  void Reset(const mjData& d) override {
    Measure(d, &p_start_, &q_start_);
    last_touch_s_ = d.time;
    Sample(d, d.time);
  }

  void Sample(const mjData& d, double t) override {
    Measure(d, &p_, &q_);
    drift_ = (p_ - p_start_).norm();
    rot_drift_ = q_start_.angularDistance(q_);
    if (target_ >= 0) {
      const Eigen::Vector3d p_target = Eigen::Map<const Eigen::Vector3d>(d.site_xpos + 3 * target_);
      error_ = (p_ - InReference(d, p_target)).norm();
    }
    if (!config_.grippers.empty()) Contacts(d, t);
  }

  void State(std::vector<double>* p) const override {
    p->assign({p_.x(), p_.y(), p_.z(), q_.w(), q_.x(), q_.y(), q_.z()});
  }
  std::vector<std::string> Columns() const override {
    std::vector<std::string> out;
    for (const char* c : {"x", "y", "z", "drift", "rot_drift"}) out.push_back(name() + "." + c);
    if (target_ >= 0) out.push_back(name() + ".error");
    if (!config_.grippers.empty()) {
      out.push_back(name() + ".holders");
      out.push_back(name() + ".free_time");
    }
    return out;
  }
  int ColumnCount() const override { return 5 + (target_ >= 0 ? 1 : 0) + (config_.grippers.empty() ? 0 : 2); }
  void Row(const mjData&, double* out) const override {
    for (double v : {p_.x(), p_.y(), p_.z(), drift_, rot_drift_}) *out++ = v;
    if (target_ >= 0) *out++ = error_;
    if (!config_.grippers.empty()) {
      *out++ = holders_;
      *out = free_time_s_;
    }
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
  // the contacts of the tracked body: which grippers hold it, since when it touches nothing
  void Contacts(const mjData& d, double t) {
    const mjModel* m = model_;
    bool touches = false;
    std::fill(touching_.begin(), touching_.end(), 0);
    std::fill(first_finger_.begin(), first_finger_.end(), -1);
    for (int i = 0; i < d.ncon; ++i) {
      const int b1 = m->geom_bodyid[d.contact[i].geom1], b2 = m->geom_bodyid[d.contact[i].geom2];
      if (b1 != tracked_body_ && b2 != tracked_body_) continue;
      touches = true;
      const int other = b1 == tracked_body_ ? b2 : b1;
      const int g = finger_gripper_[other];
      if (g < 0 || first_finger_[g] == other || touching_[g] >= 2) continue;
      // a second finger of gripper g (a gripper's fingers: first seen, then any other)
      if (first_finger_[g] < 0) {
        first_finger_[g] = other;
        touching_[g] = 1;
      } else {
        touching_[g] = 2;
      }
    }
    holders_ = 0;
    for (int n : touching_) holders_ += n >= 2 ? 1 : 0;
    if (touches) last_touch_s_ = t;
    free_time_s_ = t - last_touch_s_;
  }
  void Measure(const mjData& d, Eigen::Vector3d* p, Eigen::Quaterniond* q) const {
    const Eigen::Matrix3d R_WB = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(d.xmat + 9 * body_);
    const Eigen::Matrix3d R_WS =
        Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(d.site_xmat + 9 * site_);
    *p = InReference(d, Eigen::Map<const Eigen::Vector3d>(d.site_xpos + 3 * site_));
    *q = Eigen::Quaterniond(R_WB.transpose() * R_WS).normalized();
  }

  PoseParams config_;
  const mjModel* model_ = nullptr;
  int site_ = -1, body_ = -1, target_ = -1, tracked_body_ = -1;
  std::vector<int> finger_gripper_;  // per body: the gripper (index) it is a finger of, or -1
  std::vector<int> touching_;        // per gripper: fingers touching the body (0, 1, 2)
  std::vector<int> first_finger_;    // per gripper: the first finger seen touching it
  double holders_ = 0, last_touch_s_ = 0, free_time_s_ = 0;
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
  p->grippers = r.Strings("grippers", {});
  return p;
}

std::unique_ptr<Device> MakePose(const DeviceContext& context, const DeviceConfig& config) {
  return std::make_unique<SimPose>(context.model, config);
}

}  // namespace vlab::lab
