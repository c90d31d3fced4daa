#include "lab/lab_camera_device.h"

#include <cmath>
#include <stdexcept>

#include "bridge/bridge_errors.h"
#include "core/core_errors.h"
#include "lab/lab_log.h"

namespace vlab::lab {

namespace {
constexpr double kSameTime_s = 1e-9;  // times closer than this are one instant
}  // namespace

std::unique_ptr<SimCamera> SimCamera::Create(const mjModel* m, const DeviceConfig& c, const std::string& scene,
                                             std::uint64_t seed) {
  std::unique_ptr<SimCamera> cam(new SimCamera());
  cam->name_ = c.name;
  cam->where_ = c.where;
  cam->scene_ = scene;
  cam->m_ = m;
  cam->config_ = c.camera;
  const std::string who = c.where + ": device '" + c.name + "'";
  try {
    cam->camera_ = render::CameraId(m, c.camera.camera);
  } catch (const InputError& e) {
    throw InputError(who + ": " + e.what());
  }
  if (c.camera.width > m->vis.global.offwidth || c.camera.height > m->vis.global.offheight) {
    throw InputError(who + ": " + std::to_string(c.camera.width) + "x" + std::to_string(c.camera.height) +
                     " is larger than the offscreen buffer of scene '" + scene + "' (" +
                     std::to_string(m->vis.global.offwidth) + "x" + std::to_string(m->vis.global.offheight) +
                     ", <visual><global offwidth offheight>)");
  }
  sensors::CameraModelConfig mc;
  mc.width = c.camera.width;
  mc.height = c.camera.height;
  mc.fps = c.camera.fps;
  mc.fovy_rad = m->cam_fovy[cam->camera_] * M_PI / 180.0;
  mc.exposure_s = c.camera.exposure_s;
  mc.latency_s = c.camera.latency_s;
  for (std::size_t i = 0; i < c.camera.distortion.size() && i < 4; ++i) mc.distortion[i] = c.camera.distortion[i];
  mc.noise = c.camera.noise;
  try {
    cam->model_ = sensors::CameraModel::Create(mc);
  } catch (const std::invalid_argument& e) {
    throw InputError(who + ": " + e.what());
  }
  cam->noise_ = sensors::CameraNoiseState(seed);
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
  d.name = name_;
  d.server = server;
  d.source = "MJCF camera '" + config_.camera + "'";
  d.clock = clock;
  d.width = config_.width;
  d.height = config_.height;
  d.fps = config_.fps;
  bridge::EncodingFromName(config_.encoding, &d.encoding);
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
    throw InputError(where_ + ": device '" + name_ + "': " + e.what());
  } catch (const std::invalid_argument& e) {
    throw InputError(where_ + ": device '" + name_ + "': " + e.what());
  }
}

void SimCamera::MakeRenderer() {
  render::Renderer::Options o;
  o.width = config_.width;
  o.height = config_.height;
  o.profile = render::ProfileFromName(config_.profile);
  o.scene = scene_;
  renderer_ = render::Renderer::Create(m_, o);
  ideal_.width = config_.width;
  ideal_.height = config_.height;
}

void SimCamera::Prepare(mjData* d) {
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

void SimCamera::Observe(double t, mjData* d) {
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

void SimCamera::RenderAhead(mjData* d) {
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
