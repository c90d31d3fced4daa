// Ground-truth gaze probe (kind gaze): where a target lies relative to an
// MJCF camera, from the simulation's kinematics, for checks and logs of
// tracking scenarios (what a vision pipeline should measure from the images).
//
// Ports
//   input   none
//   output  [error_deg, u, v, visible]:
//           error_deg  angle between the camera's optical axis and the ray from
//                      the camera to the target, deg (0 .. 180)
//           u, v       the target's pixel in the camera's pinhole image of
//                      width x height (OpenCV convention: u right, v down,
//                      pixel centres at whole numbers; fx = fy =
//                      (height/2) / tan(fovy/2), cx = width/2 - 0.5,
//                      cy = height/2 - 0.5; no lens distortion); -1, -1 when
//                      the target is not in front of the camera
//           visible    1 when the target is in front of the camera and its
//                      pixel inside the image (-0.5 <= u < width - 0.5, the
//                      same for v), else 0; occlusion is not considered
//   rate    sampled at the end of every control period, from the kinematics
//           of the last physics step: the poses the camera devices render
// The target is an MJCF site (its origin) or, when no site has that name, a
// body (its frame origin, not its centre of mass).
#include <cmath>

#include <nlohmann/json.hpp>

#include "bridge/bridge_layouts.h"

#include "core/core_errors.h"
#include "lab/devices/device_gaze.h"
#include "lab/scenario/lab_yaml.h"

namespace vlab::lab {

namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

class SimGaze final : public Device {
 public:
  SimGaze(const mjModel* m, const DeviceConfig& c) : Device(c), config_(c.ParamsAs<GazeParams>()) {
    const std::string who = c.where + ": device '" + c.name + "'";
    camera_ = mj_name2id(m, mjOBJ_CAMERA, config_.camera.c_str());
    if (camera_ < 0) throw InputError(who + ": the scene has no camera '" + config_.camera + "'");
    site_ = mj_name2id(m, mjOBJ_SITE, config_.target.c_str());
    if (site_ < 0) body_ = mj_name2id(m, mjOBJ_BODY, config_.target.c_str());
    if (site_ < 0 && body_ < 0) {
      throw InputError(who + ": the scene has no site or body '" + config_.target + "' (target)");
    }
    if (config_.width < 1 || config_.height < 1) throw InputError(who + ": width and height must be >= 1 pixel");
    fovy_deg_ = m->cam_fovy[camera_];
    f_ = 0.5 * config_.height / std::tan(0.5 * fovy_deg_ * M_PI / 180.0);
    cx_ = 0.5 * config_.width - 0.5;
    cy_ = 0.5 * config_.height - 0.5;
  }

  /// The initial row and state: the pose after the lab's reset.
  void Reset(const mjData& d) override { Sample(d, d.time); }

  void Sample(const mjData& d, double) override {
    const mjtNum* target = site_ >= 0 ? d.site_xpos + 3 * site_ : d.xpos + 3 * body_;
    const mjtNum* p = d.cam_xpos + 3 * camera_;
    const mjtNum* x = d.cam_xmat + 9 * camera_;
    const double r[3] = {target[0] - p[0], target[1] - p[1], target[2] - p[2]};
    // the ray in the OpenCV camera frame: MuJoCo's camera x, -y, -z
    const double cam_x = x[0] * r[0] + x[3] * r[1] + x[6] * r[2];
    const double cam_y = -(x[1] * r[0] + x[4] * r[1] + x[7] * r[2]);
    const double cam_z = -(x[2] * r[0] + x[5] * r[1] + x[8] * r[2]);
    // angle to the optical axis (+z): atan2 stays accurate near 0 and 180 deg
    error_deg_ = std::atan2(std::hypot(cam_x, cam_y), cam_z) * kRadToDeg;
    if (cam_z > 0) {
      u_ = f_ * cam_x / cam_z + cx_;
      v_ = f_ * cam_y / cam_z + cy_;
      visible_ = u_ >= -0.5 && u_ < config_.width - 0.5 && v_ >= -0.5 && v_ < config_.height - 0.5;
    } else {
      u_ = v_ = -1.0;
      visible_ = false;
    }
  }

  void State(std::vector<double>* payload) const override {
    payload->assign({error_deg_, u_, v_, visible_ ? 1.0 : 0.0});
  }
  std::vector<std::string> Columns() const override {
    return {name() + ".error_deg", name() + ".u", name() + ".v", name() + ".visible"};
  }
  int ColumnCount() const override { return 4; }
  void Row(const mjData&, double* out) const override {
    out[0] = error_deg_;
    out[1] = u_;
    out[2] = v_;
    out[3] = visible_ ? 1.0 : 0.0;
  }

  std::string DescribeFacts() const override {
    nlohmann::json j;
    j["layout"] = bridge::LayoutJson(kind());
    j["units"] = {{"error_deg", "deg"}, {"u", "px"}, {"v", "px"}, {"visible", "1 or 0"}};
    j["camera"] = config_.camera;
    j["target"] = config_.target;
    j["target_type"] = site_ >= 0 ? "site" : "body";
    j["width"] = config_.width;
    j["height"] = config_.height;
    j["fovy_deg"] = fovy_deg_;
    j["intrinsics"] = {
        {"model", "pinhole"}, {"width", config_.width}, {"height", config_.height}, {"fx", f_}, {"fy", f_}, {"cx", cx_},
        {"cy", cy_},          {"source", "fovy"}};
    j["camera_frame"] = "OpenCV: x right, y down, z forward";
    j["ground_truth"] = true;
    return j.dump();
  }

 private:
  GazeParams config_;
  int camera_ = -1;
  int site_ = -1;
  int body_ = -1;
  double fovy_deg_ = 0;
  double f_ = 0, cx_ = 0, cy_ = 0;  // pinhole intrinsics, px
  // last sample
  double error_deg_ = 0, u_ = -1, v_ = -1;
  bool visible_ = false;
};

}  // namespace

std::shared_ptr<const DeviceParams> ReadGazeParams(MapReader& r) {
  auto p = std::make_shared<GazeParams>();

  p->camera = r.String("camera");
  p->target = r.String("target");
  p->width = r.Integer("width", p->width);
  p->height = r.Integer("height", p->height);
  if (p->width < 1 || p->width > 8192) r.Fail("width", "must be 1 to 8192 pixels");
  if (p->height < 1 || p->height > 8192) r.Fail("height", "must be 1 to 8192 pixels");
  return p;
}

std::unique_ptr<Device> MakeGaze(const DeviceContext& context, const DeviceConfig& config) {
  return std::make_unique<SimGaze>(context.model, config);
}

}  // namespace vlab::lab
