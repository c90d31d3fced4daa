// The chain through which the point and tool devices drive their arm: made from
// the scenario's keys, bound to the arm device, read and driven each period.
#include "lab/devices/device_arm_chain.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "core/core_errors.h"
#include "lab/scenario/lab_yaml.h"

namespace vlab::lab {

namespace {
using Matrix3RowMajor = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
}  // namespace

MapReader ReadArmChainParams(MapReader& r, ArmChainParams* params) {
  params->arm = r.String("arm");
  params->site = r.String("site", params->site);
  params->base_body = r.String("base_body", params->base_body);
  MapReader gains = r.Map("gains");
  params->k_position = gains.Number("position", params->k_position);
  params->k_orientation = gains.Number("orientation", params->k_orientation);
  params->k_null = gains.Number("null_space", params->k_null);
  params->damping = gains.Number("damping", params->damping);
  return gains;
}

ArmChain MakeArmChain(const mjModel* model, const ArmChainParams& params, const std::string& who) {
  ArmChain chain;
  try {
    chain.model = control::RobotModel::Create(model, {params.base_body, params.site});
  } catch (const std::invalid_argument& e) {
    throw InputError(who + ": " + e.what());
  }
  chain.site = chain.model->tip_site_id();
  chain.q.setZero(chain.model->dof());
  chain.qd.setZero(chain.model->dof());
  chain.velocity.mode = bridge::ArmMode::kVelocity;
  chain.hold.mode = bridge::ArmMode::kHold;
  return chain;
}

void BindArmChain(ArmChain& chain, const ArmChainParams& params, const std::vector<Device*>& devices,
                  const std::string& who) {
  chain.arm = nullptr;
  for (Device* d : devices) {
    if (d->name() == params.arm) chain.arm = d->arm();
  }
  if (!chain.arm) throw InputError(who + ": arm: the scenario has no arm device '" + params.arm + "'");
  // chain joint i is arm joint arm_index[i]
  chain.arm_index.clear();
  const std::vector<std::string>& joints = chain.arm->joint_names();
  for (const std::string& joint : chain.model->joint_names()) {
    const auto it = std::find(joints.begin(), joints.end(), joint);
    if (it == joints.end()) {
      throw InputError(who + ": chain joint '" + joint + "' (from '" + params.base_body + "' to site '" + params.site +
                       "') is not a joint of arm '" + chain.arm->name() + "'");
    }
    chain.arm_index.push_back(static_cast<int>(it - joints.begin()));
  }
  chain.velocity.value.setZero(chain.arm->dof());
}

void ReadArmChain(ArmChain& chain, const mjData& d) {
  for (int i = 0; i < chain.model->dof(); ++i) {
    chain.q[i] = d.qpos[chain.model->qpos_addresses()[i]];
    chain.qd[i] = d.qvel[chain.model->dof_addresses()[i]];
  }
  chain.model->SetState(chain.q, chain.qd);
}

void ResetArmChain(ArmChain& chain, const ArmChainParams& params) {
  control::TaskSpaceConfig tc;
  tc.k_position = params.k_position;
  tc.k_orientation = params.k_orientation;
  tc.k_null = params.k_null;
  tc.damping = params.damping;
  if (chain.arm->max_velocity().size() > 0) {
    double slowest = INFINITY;  // uniform scaling below the slowest chain joint's limit: never refused
    for (int i : chain.arm_index) slowest = std::min(slowest, chain.arm->max_velocity()[i]);
    tc.max_joint_speed = 0.999 * slowest;
  }
  tc.q_rest = chain.q;  // the posture the null-space term keeps
  chain.controller = control::TaskSpaceController::Create(tc, *chain.model);
  chain.holding = true;
}

void CommandArmChain(ArmChain& chain) {
  chain.resume = chain.holding;
  chain.holding = false;
}

bool BeginArmChainPeriod(ArmChain& chain, const mjData& d, bool* resumed) {
  if (chain.holding) {
    HoldArm(chain);
    return false;
  }
  ReadArmChain(chain, d);
  *resumed = chain.resume;
  chain.resume = false;
  return true;
}

void DriveArm(ArmChain& chain, const control::TaskSpaceTarget& target) {
  const control::TaskSpaceOutput& out = chain.controller->Update(*chain.model, chain.q, target);
  chain.velocity.value.setZero();
  for (std::size_t i = 0; i < chain.arm_index.size(); ++i) chain.velocity.value[chain.arm_index[i]] = out.qd_cmd[i];
  if (!out.ok || !chain.arm->Command(chain.velocity)) chain.arm->Command(chain.hold);  // non-finite state: hold
}

void HoldArm(ArmChain& chain) { chain.arm->Command(chain.hold); }

SiteMotion ReadSiteMotion(const mjModel* model, const mjData& d, const ArmChain& chain) {
  SiteMotion m;
  m.p_W = Eigen::Map<const Eigen::Vector3d>(d.site_xpos + 3 * chain.site);
  m.R_WS = Eigen::Map<const Matrix3RowMajor>(d.site_xmat + 9 * chain.site);
  mjtNum velocity[6];
  mj_objectVelocity(model, &d, mjOBJ_SITE, chain.site, velocity, 0);  // [angular, linear], world frame
  m.w_W = Eigen::Vector3d(velocity[0], velocity[1], velocity[2]);
  m.v_W = Eigen::Vector3d(velocity[3], velocity[4], velocity[5]);
  return m;
}

nlohmann::json ArmChainFacts(const ArmChain& chain, const ArmChainParams& params, bridge::DeviceKind kind) {
  nlohmann::json j;
  j["layout"] = bridge::LayoutJson(kind);
  j["frame"] = "world";
  j["arm"] = chain.arm->name();
  j["site"] = params.site;
  j["status_bits"] = {{"holding", bridge::kStatusHolding},
                      {"refused", bridge::kStatusRefused},
                      {"watchdog", bridge::kStatusWatchdog},
                      {"not_owner", bridge::kStatusNotOwner}};
  j["gains"] = {{"position", params.k_position},
                {"orientation", params.k_orientation},
                {"null_space", params.k_null},
                {"damping", params.damping}};
  j["watchdog_periods"] = params.input.watchdog_periods;
  return j;
}

}  // namespace vlab::lab
