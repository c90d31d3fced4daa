#include "lab/devices/device_camera.h"

#include <pthread.h>
#include <sched.h>
#include <semaphore.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "bridge/bridge_errors.h"
#include "core/core_clock.h"
#include "core/core_errors.h"
#include "core/core_mujoco.h"
#include "core/core_realtime.h"
#include "lab/outputs/lab_log.h"
#include "lab/scenario/lab_yaml.h"

namespace vlab::lab {

namespace {
// the nice value of a worker (and the rasterizer threads) under a control thread that is not realtime
constexpr int kWorkerNice = 10;

// the seed of frame `id`'s noise (Xoshiro256pp::Seed mixes it further with splitmix64)
std::uint64_t FrameNoiseSeed(std::uint64_t seed, std::int64_t id) {
  return seed * 0x9E3779B97F4A7C15ull ^ (static_cast<std::uint64_t>(id) + 0x632BE59BD9B4E019ull);
}

bool Listed(const std::vector<std::int64_t>& sorted_ids, std::int64_t id) {
  return !sorted_ids.empty() && std::binary_search(sorted_ids.begin(), sorted_ids.end(), id);
}
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
  if (!(c->exposure_s >= 0 && c->exposure_s < 1 / c->fps))
    r.Fail("exposure", "must be >= 0 s and shorter than a frame");
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
  if (!render::ParseProfile(profile, &c->profile)) r.Fail("profile", std::string("must be ") + render::ProfileNames());
  const auto ids = [&r](const char* key) {
    std::vector<std::int64_t> out;
    for (double v : r.Numbers(key, {})) {
      if (!(v >= 0 && v <= 1e15 && v == std::floor(v))) r.Fail(key, "frame ids are whole numbers >= 0");
      out.push_back(static_cast<std::int64_t>(v));
    }
    std::sort(out.begin(), out.end());
    return out;
  };
  c->drop_frames = ids("drop_frames");
  c->late_frames = ids("late_frames");
  c->late_by_s = r.Number("late_by", c->late_by_s);
  if (!(c->late_by_s > 0 && c->late_by_s <= 10)) r.Fail("late_by", "must be > 0 and <= 10 s");
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
  for (std::size_t i = 0; i < cam->config_.distortion.size() && i < 4; ++i)
    mc.distortion[i] = cam->config_.distortion[i];
  mc.noise = cam->config_.noise;
  try {
    cam->model_ = sensors::CameraModel::Create(mc);
  } catch (const std::invalid_argument& e) {
    throw InputError(who + ": " + e.what());
  }
  cam->noise_seed_ = context.seed;
  // the frames in flight, and room for a worker a few frames behind (realtime)
  // (a new vector, not resize: a Pending, with its atomic, does not move)
  cam->queue_ = std::vector<Pending>(static_cast<std::size_t>(cam->model_->FramesInFlight()) + 4);
  for (Pending& p : cam->queue_) p.frame.data.reserve(static_cast<std::size_t>(mc.width) * mc.height * 3);
  return cam;
}

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
  realtime_ = clock == "realtime";
  try {
    server_ = bridge::CameraServer::Create(sc);
  } catch (const bridge::NetworkError& e) {
    throw InputError(who() + ": " + e.what());
  } catch (const std::invalid_argument& e) {
    throw InputError(who() + ": " + e.what());
  }
}

// ---- the worker: renders, models the lens and sensor, encodes ----

struct SimCamera::Worker {
  Worker() { ::sem_init(&jobs, 0, 0); }
  ~Worker() { ::sem_destroy(&jobs); }
  std::thread thread;
  sem_t jobs;  // to the worker: one post per frame queued, and one to stop
  std::atomic<bool> stop{false};
  std::mutex mutex;
  std::condition_variable done;  // to a waiting control thread: a frame is done, or the worker is ready
  long queued = 0;               // (control thread's) frames handed to the worker
  long finished = 0;             // (mutex) frames it has done
  std::size_t at = 0;            // (worker's; reset by the control thread while it is idle) next ring index
  bool ready = false;            // (mutex) renderer made, warm-up drawn (or error set)
  std::string error;             // (mutex) why the renderer could not be made
  long rendered = 0;             // (mutex)
  std::atomic<long> tid{0};      // the worker's thread id, once it runs
  mjData* warm = nullptr;        // the state of the warm-up draw (control thread's, read before ready)
};

SimCamera::SimCamera(const DeviceConfig& config) : Device(config) {
  capabilities_.own_transport = this;
  capabilities_.rendered_output = this;
}

long SimCamera::worker_thread_id() const { return worker_ ? worker_->tid.load() : 0; }

long SimCamera::frames_rendered() const {
  if (!worker_) return 0;
  std::lock_guard<std::mutex> lock(worker_->mutex);
  return worker_->rendered;
}

void SimCamera::StartWorker(mjData* d) {
  if (worker_) return;
  for (Pending& p : queue_) {
    if (!p.state) p.state = mj_makeData(m_);
  }
  worker_ = std::make_unique<Worker>();
  worker_->warm = d;
  worker_->thread = std::thread([this] { WorkerMain(); });
  // the GL context and the first draw are paid here, before the run
  std::unique_lock<std::mutex> lock(worker_->mutex);
  worker_->done.wait(lock, [this] { return worker_->ready; });
  if (!worker_->error.empty()) {
    const std::string error = worker_->error;
    lock.unlock();
    StopWorker();
    throw std::runtime_error(error);
  }
}

void SimCamera::StopWorker() {
  if (!worker_) return;
  worker_->stop = true;
  ::sem_post(&worker_->jobs);
  worker_->thread.join();
  worker_.reset();
}

void SimCamera::WorkerMain() {
  Worker& w = *worker_;
  // below the control thread, always: under a realtime one (SCHED_FIFO P) at SCHED_FIFO
  // P - 1; under a normal one at nice 10 (not SCHED_IDLE: that starves under any load,
  // and a worker must always progress). The rasterizer threads it waits for follow it.
  // Not SCHED_OTHER at nice -20 under a realtime loop: that keeps the workers out of
  // the kernel's realtime throttling, but the kernel shares the CPU between sessions
  // first (autogroup), so work started from another terminal took the workers' share
  // whatever their nice value (yo-yo stage 3 beside a build: 36 frames dropped, 1022
  // late, a bad swing).
  // It starts at the control thread's priority, which waits for it: the GL context, the
  // shaders and the warm-up draw took more than 5 s at nice 10 beside two CPU-bound
  // processes, and no describe request was answered meanwhile.
  int policy = 0;
  sched_param param{};
  int loop_priority = ::pthread_getschedparam(::pthread_self(), &policy, &param) == 0 && policy == SCHED_FIFO
                          ? param.sched_priority
                          : 0;
  if (loop_priority == 0 && realtime_ && (loop_priority = DeadlineLoopPriority()) > 0) {
    // made by a SCHED_DEADLINE loop, which cannot pass its policy on: its priority, asked
    SetThreadRealtime(loop_priority);
  }
  const bool realtime_loop = loop_priority > 0;
  const id_t tid = static_cast<id_t>(::gettid());
  ::pthread_setname_np(::pthread_self(), kWorkerThreadName);  // (for ps -L and top -H)
  const int worker_policy = realtime_loop ? SCHED_FIFO : SCHED_OTHER;
  const int worker_value = realtime_loop ? std::max(kMinRealtimePriority, loop_priority - 1) : kWorkerNice;
  // a realtime loop without SCHED_FIFO that keeps its CPU: the worker, and the
  // rasterizer threads its first context makes, run on the others (core_realtime.h)
  const DeviceCpus cpus = realtime_loop ? DeviceCpus{} : BindDeviceThread();
  const auto go_below = [&] {
    if (realtime_loop) {
      SetThreadRealtime(worker_value);
    } else {
      ::setpriority(PRIO_PROCESS, tid, worker_value);
      SetThreadSlice(0);  // the scheduler's default slice, not the control thread's short one it inherited
    }
    // the rasterizer threads it waits for: as it is, wherever they were made
    render::SetRasterizerScheduling(worker_policy, worker_value);
    if (!cpus.device.empty()) render::BindRasterizers(cpus.device);
  };
  w.tid = static_cast<long>(tid);  // (set: for the tests)
  // everything GL lives and dies on this thread
  std::unique_ptr<render::Renderer> renderer;
  render::RgbImage ideal;
  ideal.width = config_.width;
  ideal.height = config_.height;
  bridge::FrameEncoder encoder(config_.encoding, config_.jpeg_quality);
  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(config_.width) * config_.height * 3);
  try {
    render::Renderer::Options o;
    o.width = config_.width;
    o.height = config_.height;
    o.profile = config_.profile;
    o.scene = scene_;
    renderer = render::Renderer::Create(m_, o);
    renderer->Render(w.warm, camera_, &ideal);
    go_below();
  } catch (const std::exception& e) {
    std::lock_guard<std::mutex> lock(w.mutex);
    w.error = who() + ": " + e.what();
  }
  {
    std::lock_guard<std::mutex> lock(w.mutex);
    w.ready = true;
    w.warm = nullptr;
  }
  w.done.notify_all();
  if (!renderer) return;

  for (;;) {
    while (::sem_wait(&w.jobs) != 0) {
    }                   // (only EINTR: retried)
    if (w.stop) break;  // what is still queued would not be sent: the camera is no longer served
    Pending& p = queue_[w.at];
    bool ok = false;
    try {
      renderer->Render(p.state, camera_, &ideal);
      // the lens, the sensor's noise, the encoding. The noise is drawn from the run's seed
      // and the frame's id, not from one stream in render order: frames are rendered only
      // while someone subscribes, and when a client subscribed (a wall-clock matter) then
      // changed the pixels of every later frame, and what a vision program made of them.
      noise_.rng.Seed(FrameNoiseSeed(noise_seed_, p.frame.id));
      model_->Apply(ideal.pixels.data(), rgb.data(), &noise_);
      ok = encoder.Encode(config_.width, config_.height, rgb.data(), &p.frame.data);
    } catch (const std::exception&) {
      ok = false;  // (never for a valid camera and size: both were checked at creation)
    }
    w.at = (w.at + 1) % queue_.size();
    p.ok = ok;
    {
      std::lock_guard<std::mutex> lock(w.mutex);  // (for a control thread that waits: lockstep, fast)
      p.done.store(true, std::memory_order_release);
      ++w.rendered;
      ++w.finished;
    }
    w.done.notify_all();
  }
  renderer.reset();
  render::SetRasterizerScheduling(SCHED_OTHER, 0);  // (the pool outlives this camera)
  if (!cpus.allowed.empty()) render::BindRasterizers(cpus.allowed);
}

void SimCamera::Drain() {
  if (!worker_) return;
  std::unique_lock<std::mutex> lock(worker_->mutex);
  worker_->done.wait(lock, [this] { return worker_->finished == worker_->queued; });
}

bool SimCamera::WaitDone(Pending& p, bool wait) {
  if (p.done.load(std::memory_order_acquire)) return true;
  if (!wait) return false;  // (realtime: never the mutex)
  std::unique_lock<std::mutex> lock(worker_->mutex);
  worker_->done.wait(lock, [&p] { return p.done.load(std::memory_order_acquire); });
  return true;
}

// ---- the control thread ----

void SimCamera::BeforeRun(mjData* d) {
  if (server_) StartWorker(d);
}

void SimCamera::Unserve() {
  StopWorker();  // (what is still queued is dropped: nothing is sent once unserved)
  server_.reset();
  t_prev_ = -1;
  due_ = {0, 0};
  head_ = count_ = 0;
  id_base_ = next_id_ = 0;
}

SimCamera::~SimCamera() {
  StopWorker();
  for (Pending& p : queue_) {
    if (p.state) mj_deleteData(p.state);
  }
}

void SimCamera::Deliver(double t, mjData* d) {
  if (!server_) return;
  server_->Poll(0.0);
  const double t_before = t_prev_;  // the previous period end: frames due by then are late
  if (t < t_prev_) {                // the sim device reset the time: a new schedule, ids go on increasing
    Drain();
    t_prev_ = -1;
    head_ = count_ = 0;
    if (worker_) worker_->at = 0;  // (idle: nothing queued)
    id_base_ = next_id_;
  }
  // frames due: copied from this state (skipped while nobody listens); a frame
  // stamped t is delivered at t only without latency, and then queued now
  due_ = model_->DueForRender(t_prev_, t);
  due_t_ = t;
  t_prev_ = t;
  if (config_.latency_s <= kSameTime_s) QueueDue(d);
  // frames delivered: their latency has passed, and (realtime) the worker has done them
  while (count_ > 0) {
    Pending& p = queue_[head_];
    const bool held = Listed(config_.late_frames, p.frame.id);  // an injected stall
    const double due_at = p.frame.time_s + config_.latency_s + (held ? config_.late_by_s : 0.0);
    if (due_at > t + kSameTime_s || !WaitDone(p, !realtime_)) break;
    if (held || p.frame.time_s + config_.latency_s <= t_before + kSameTime_s) ++late_;
    if (Listed(config_.drop_frames, p.frame.id)) {  // an injected loss
      ++dropped_;
    } else if (p.ok) {
      server_->Send(p.frame);
    }
    head_ = (head_ + 1) % queue_.size();
    --count_;
  }
}

void SimCamera::AfterPublish(mjData* d) {
  if (server_) QueueDue(d);
}

void SimCamera::QueueDue(mjData* d) {
  for (std::int64_t i = due_.first; i < due_.end; ++i) {
    if (server_->subscribers() == 0) continue;
    if (!worker_) StartWorker(d);
    if (count_ == queue_.size()) {  // the ring is full (realtime, a worker far behind): this frame is lost
      ++dropped_;
      continue;
    }
    Pending& slot = queue_[(head_ + count_) % queue_.size()];
    // (the worker is not reading this slot: it is free)
    CopyDrawnState(m_, d, slot.state);
    slot.frame.id = id_base_ + i;
    slot.frame.time_s = due_t_;
    slot.frame.width = config_.width;
    slot.frame.height = config_.height;
    slot.frame.encoding = config_.encoding;
    // the OpenCV camera frame: MuJoCo's camera axes with y and z flipped
    const mjtNum* x = d->cam_xmat + 9 * camera_;
    Eigen::Matrix3d r;
    r << x[0], -x[1], -x[2], x[3], -x[4], -x[5], x[6], -x[7], -x[8];
    slot.frame.pose.valid = true;
    slot.frame.pose.p_WC =
        Eigen::Vector3d(d->cam_xpos[3 * camera_], d->cam_xpos[3 * camera_ + 1], d->cam_xpos[3 * camera_ + 2]);
    slot.frame.pose.q_WC = Eigen::Quaterniond(r).normalized();
    next_id_ = id_base_ + i + 1;
    ++count_;
    slot.done.store(false, std::memory_order_relaxed);  // (published to the worker by the post)
    ++worker_->queued;
    ::sem_post(&worker_->jobs);  // never blocks
  }
  due_.first = due_.end;
}

}  // namespace vlab::lab
