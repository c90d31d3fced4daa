#include "lab/devices/device_camera.h"

#include <cmath>
#include <stdexcept>

#include "bridge/bridge_errors.h"
#include "core/core_errors.h"
#include "lab/lab_log.h"
#include "lab/lab_yaml.h"

namespace vlab::lab {

namespace {
constexpr double kSameTime_s = 1e-9;  // times closer than this are one instant
}  // namespace

std::shared_ptr<const DeviceParams> ReadCameraParams(MapReader& r) {
  auto c = std::make_shared<CameraParams>();
  c->camera = r.String("camera");
  c->width = r.Integer("width", c->width);
  c->height = r.Integer("height", c->height);
  if (c->width < 1 || c->width > 8192) r.Fail("width", "must be 1 to 8192 pixels");
  if (c->height < 1 || c->height > 8192) r.Fail("height", "must be 1 to 8192 pixels");
  c->fps = r.Number("fps", c->fps);
  if (!(c->fps > 0 && c->fps <= 1000)) r.Fail("fps", "must be > 0 and <= 1000 Hz");
  c->exposure_s = r.Number("exposure", c->exposure_s);
  if (!(c->exposure_s >= 0 && c->exposure_s < 1 / c->fps)) r.Fail("exposure", "must be >= 0 s and shorter than a frame");
  c->latency_s = r.Number("latency", c->latency_s);
  if (!(c->latency_s >= 0 && c->latency_s <= 1)) r.Fail("latency", "must be 0 to 1 s");
  c->distortion = r.Numbers("distortion", {});
  if (!c->distortion.empty() && c->distortion.size() != 4) r.Fail("distortion", "expected 4 numbers: k1, k2, p1, p2");
  c->noise = r.Number("noise", c->noise);
  if (!(c->noise >= 0 && c->noise <= 64)) r.Fail("noise", "must be 0 to 64 grey levels");
  const std::string encoding = r.String("encoding", "jpeg");
  if ((encoding != "jpeg" && encoding != "raw") || !bridge::EncodingFromName(encoding, &c->encoding)) {
    r.Fail("encoding", "must be jpeg or raw");
  }
  c->jpeg_quality = r.Integer("jpeg_quality", c->jpeg_quality);
  if (c->jpeg_quality < 1 || c->jpeg_quality > 100) r.Fail("jpeg_quality", "must be 1 to 100");
  const std::string profile = r.String("profile", "fast");
  if (profile != "fast" && profile != "quality") r.Fail("profile", "must be fast or quality");
  c->profile = render::ProfileFromName(profile);
  return c;
}

std::unique_ptr<Device> MakeCamera(const DeviceContext& context, const DeviceConfig& config) {
  return SimCamera::Create(context, config);
}

std::unique_ptr<SimCamera> SimCamera::Create(const DeviceContext& context, const DeviceConfig& c) {
  const mjModel* m = context.model;
  const std::string& scene = context.scene;
  std::unique_ptr<SimCamera> cam(new SimCamera(c));
  cam->scene_ = scene;
  cam->m_ = m;
  cam->config_ = c.ParamsAs<CameraParams>();
  const std::string who = cam->who();
  try {
    cam->camera_ = render::CameraId(m, cam->config_.camera);
  } catch (const InputError& e) {
    throw InputError(who + ": " + e.what());
  }
  if (cam->config_.width > m->vis.global.offwidth || cam->config_.height > m->vis.global.offheight) {
    throw InputError(who + ": " + std::to_string(cam->config_.width) + "x" + std::to_string(cam->config_.height) +
                     " is larger than the offscreen buffer of scene '" + scene + "' (" +
                     std::to_string(m->vis.global.offwidth) + "x" + std::to_string(m->vis.global.offheight) +
                     ", <visual><global offwidth offheight>)");
  }
  sensors::CameraModelConfig mc;
  mc.width = cam->config_.width;
  mc.height = cam->config_.height;
  mc.fps = cam->config_.fps;
  mc.fovy_rad = m->cam_fovy[cam->camera_] * M_PI / 180.0;
  mc.exposure_s = cam->config_.exposure_s;
  mc.latency_s = cam->config_.latency_s;
  for (std::size_t i = 0; i < cam->config_.distortion.size() && i < 4; ++i) mc.distortion[i] = cam->config_.distortion[i];
  mc.noise = cam->config_.noise;
  try {
    cam->model_ = sensors::CameraModel::Create(mc);
  } catch (const std::invalid_argument& e) {
    throw InputError(who + ": " + e.what());
  }
  cam->noise_ = sensors::CameraNoiseState(context.seed);
  cam->queue_.resize(static_cast<std::size_t>(cam->model_->FramesInFlight()) + 2);
  for (Pending& p : cam->queue_) p.rgb.resize(static_cast<std::size_t>(mc.width) * mc.height * 3);
  return cam;
}

SimCamera::~SimCamera() = default;

void SimCamera::Serve(const std::string& address, int port, const std::string& server, const std::string& clock) {
  bridge::CameraServerConfig sc;
  sc.bind_address = address;
  sc.port = port;
  bridge::CameraDescription& d = sc.description;
  d.name = name();
  d.server = server;
  d.source = "MJCF camera '" + config_.camera + "'";
  d.clock = clock;
  d.width = config_.width;
  d.height = config_.height;
  d.fps = config_.fps;
  d.encoding = config_.encoding;
  d.jpeg_quality = config_.jpeg_quality;
  const sensors::PinholeIntrinsics& k = model_->intrinsics();
  d.fx = k.fx;
  d.fy = k.fy;
  d.cx = k.cx;
  d.cy = k.cy;
  d.intrinsics_source = "fovy";
  d.distortion = model_->config().distortion;
  d.exposure_s = config_.exposure_s;
  d.latency_s = config_.latency_s;
  d.noise = config_.noise;
  d.pose = m_->cam_bodyid[camera_] == 0 ? "fixed" : "moving";
  try {
    server_ = bridge::CameraServer::Create(sc);
  } catch (const bridge::NetworkError& e) {
    throw InputError(who() + ": " + e.what());
  } catch (const std::invalid_argument& e) {
    throw InputError(who() + ": " + e.what());
  }
}

void SimCamera::MakeRenderer() {
  render::Renderer::Options o;
  o.width = config_.width;
  o.height = config_.height;
  o.profile = config_.profile;
  o.scene = scene_;
  renderer_ = render::Renderer::Create(m_, o);
  ideal_.width = config_.width;
  ideal_.height = config_.height;
}

void SimCamera::BeforeRun(mjData* d) {
  if (!server_ || renderer_) return;
  MakeRenderer();
  renderer_->Render(d, camera_, &ideal_);
}

void SimCamera::RenderFrame(std::int64_t id, double t, mjData* d, Pending* slot) {
  if (!renderer_) MakeRenderer();
  renderer_->Render(d, camera_, &ideal_);
  model_->Apply(ideal_.pixels.data(), slot->rgb.data(), &noise_);
  slot->id = id;
  slot->stamp = t;
  // the OpenCV camera frame: MuJoCo's camera axes with y and z flipped
  const mjtNum* x = d->cam_xmat + 9 * camera_;
  Eigen::Matrix3d r;
  r << x[0], -x[1], -x[2], x[3], -x[4], -x[5], x[6], -x[7], -x[8];
  slot->pose.valid = true;
  slot->pose.p_WC = Eigen::Vector3d(d->cam_xpos[3 * camera_], d->cam_xpos[3 * camera_ + 1], d->cam_xpos[3 * camera_ + 2]);
  slot->pose.q_WC = Eigen::Quaterniond(r).normalized();
  ++rendered_;
}

void SimCamera::Unserve() {
  server_.reset();
  t_prev_ = -1;
  due_ = {0, 0};
  head_ = count_ = 0;
  id_base_ = next_id_ = 0;
}

void SimCamera::Deliver(double t, mjData* d) {
  if (!server_) return;
  server_->Poll(0.0);
  if (t < t_prev_) {  // the sim device reset the time: a new schedule, ids go on increasing
    t_prev_ = -1;
    head_ = count_ = 0;
    id_base_ = next_id_;
  }
  // frames due: rendered from this state (skipped while nobody listens); a frame
  // stamped t is delivered at t only without latency, and then rendered now
  due_ = model_->DueForRender(t_prev_, t);
  due_t_ = t;
  t_prev_ = t;
  if (config_.latency_s <= kSameTime_s) RenderDue(d);
  // frames delivered: their latency has passed
  while (count_ > 0 && queue_[head_].stamp + config_.latency_s <= t + kSameTime_s) {
    const Pending& p = queue_[head_];
    server_->SendImage(p.id, p.stamp, p.rgb.data(), p.pose);
    head_ = (head_ + 1) % queue_.size();
    --count_;
  }
}

void SimCamera::AfterPublish(mjData* d) {
  if (server_) RenderDue(d);
}

void SimCamera::RenderDue(mjData* d) {
  for (std::int64_t i = due_.first; i < due_.end; ++i) {
    if (server_->subscribers() == 0) continue;
    if (count_ == queue_.size()) {  // cannot happen with FramesInFlight() + 2 slots; never block
      head_ = (head_ + 1) % queue_.size();
      --count_;
    }
    Pending& slot = queue_[(head_ + count_) % queue_.size()];
    RenderFrame(id_base_ + i, due_t_, d, &slot);
    next_id_ = id_base_ + i + 1;
    ++count_;
  }
  due_.first = due_.end;
}

}  // namespace vlab::lab
