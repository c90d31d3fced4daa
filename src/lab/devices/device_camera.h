// Simulated webcam (kind camera): an MJCF camera rendered offscreen at the
// camera's own frame rate, through the webcam model (sensors/sensor_camera.h),
// delivered after its latency as chunked frames (bridge/bridge_camera_server.h).
//
// Ports
//   input   describe and subscribe requests on its port (docs/protocol.md, "Sessions")
//   output  frames to every subscriber: id, exposure stamp (the simulated time
//           of the state rendered), width, height, encoding, the camera's pose
//           in the world (OpenCV frame: x right, y down, z forward)
//   rate    fps, independent of the control rate: a frame whose stamp falls
//           in a control period is rendered from the state that closes the
//           period (within one control period of its nominal stamp) and sent
//           at the first period end at or after stamp + latency
// Threading: a served camera renders and encodes on its own worker thread,
// with its own GL context, from a copy of the state taken at the frame's
// stamp (CopyDrawnState: what drawing reads, not the constraint matrices and
// the stack); the control thread only copies the state and sends the
// chunks. In lockstep and fast runs a frame whose delivery time has come is
// waited for, so the frame of stamp t has the same bytes and goes out in the
// same period whatever the load; in realtime runs the control thread never
// waits: a frame not ready in time goes out at the first period end after it
// is (counted late), and it never blocks on the worker (see Pending). A worker
// runs below the control thread: one priority below a SCHED_FIFO one
// (core_realtime.h), at nice 10 under a normal one; llvmpipe's rasterizer
// threads follow the worker. Under a realtime loop without SCHED_FIFO that
// keeps its CPU (core_realtime.h), the worker and the rasterizer threads run
// on the other CPUs. It makes its GL context and draws its first frame
// before it drops there, at the control thread's priority (which waits for it). Rendering several cameras
// at realtime priority can spend the kernel's realtime budget (95 % of each
// second by default) and get the control thread throttled with it.
// Rendering reads the state and never changes it; nothing is rendered while
// nobody subscribes. Under `vlab run` (nothing served) the device is idle.
// It serves itself (OwnTransport): its frames travel in chunks on its own
// socket, which the lab's bridge binds with the other devices' sockets.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "bridge/bridge_camera.h"
#include "bridge/bridge_camera_server.h"
#include "lab/devices/device.h"
#include "render/renderer.h"
#include "sensors/sensor_camera.h"

namespace vlab::lab {

/// The name of a camera's render worker thread (/proc/PID/task/TID/comm).
inline constexpr const char* kWorkerThreadName = "vlab-camera";

/// A simulated webcam: an MJCF camera rendered offscreen at the camera's own
/// frame rate, through a lens and sensor model (sensors/sensor_camera.h).
struct CameraParams : DeviceParams {
  std::string camera;  ///< MJCF camera name
  int width = 640;     ///< pixels (at most the scene's offscreen buffer)
  int height = 480;
  double fps = 30.0;               ///< frame rate, independent of the control rate
  double exposure_s = 0.0;         ///< exposure time (0: instantaneous); the frame is stamped at its middle
  double latency_s = 0.03;         ///< from the exposure stamp to delivery
  std::vector<double> distortion;  ///< k1, k2, p1, p2 (Brown-Conrady); empty: none
  double noise = 0.0;              ///< pixel noise standard deviation, 8-bit grey levels
  bridge::CameraEncoding encoding = bridge::CameraEncoding::kJpeg;  ///< frames on the wire (jpeg | raw)
  int jpeg_quality = 90;                                            ///< 1-100
  render::Profile profile = render::Profile::kFast;                 ///< draft | fast | quality
  // Faults injected on purpose, to test that a client survives them (frame ids as
  // sent, 0 the first): a dropped frame is rendered and never sent (counted
  // dropped), as a frame lost on the way; a late frame is held `late_by_s` past
  // its due time and the frames behind it wait with it (counted late), as after a
  // stall of the camera's pipeline.
  std::vector<std::int64_t> drop_frames;  ///< ids never sent
  std::vector<std::int64_t> late_frames;  ///< ids delivered late_by_s late
  double late_by_s = 0.1;
};

/// Reads a camera entry's keys (camera, width, height, fps, exposure, latency,
/// distortion, noise, encoding, jpeg_quality, profile, drop_frames, late_frames,
/// late_by).
std::shared_ptr<const DeviceParams> ReadCameraParams(MapReader& r);
/// Makes a SimCamera.
std::unique_ptr<Device> MakeCamera(const DeviceContext& context, const DeviceConfig& config);

class SimCamera final : public Device, public OwnTransport, public RenderedOutput {
 public:
  /// Binds the MJCF camera and builds the webcam model. Throws InputError
  /// naming the device: unknown camera, size above the offscreen buffer, a
  /// bad model setting.
  static std::unique_ptr<SimCamera> Create(const DeviceContext& context, const DeviceConfig& config);
  ~SimCamera() override;

  const sensors::CameraModel& model() const { return *model_; }
  const bridge::CameraServer* server() const { return server_.get(); }
  long frames_rendered() const;
  /// The render worker's thread id (gettid), 0 before it has started.
  long worker_thread_id() const;
  /// Frames delivered after their stamp + latency (realtime: the worker was late).
  long frames_late() const { return late_; }
  /// Frames not rendered because the ring of frames in flight was full (realtime only).
  long frames_dropped() const { return dropped_; }

  // OwnTransport: binds its socket (address, port) and makes the describe reply;
  // the renderer is made by BeforeRun (or the first frame), on the thread that runs the lab
  void Serve(const std::string& address, int port, const std::string& server, const std::string& clock) override;
  bool served() const override { return server_ != nullptr; }
  /// Closes its socket and restarts its schedule (a run without serving).
  void Unserve() override;
  /// Unserves and stops the worker.
  int fd() const override { return server_->fd(); }
  /// A non-blocking pass over what arrived (describe and subscribe requests).
  void PollRequests() override { server_->Poll(0.0); }
  int port() const override { return server_->port(); }
  std::string address() const override { return server_->config().bind_address; }
  std::string describe_json() const override { return server_->describe_json(); }
  bridge::EndpointCounters counters() const override { return server_->counters().endpoint; }
  FrameCounters frames() const override { return {server_->counters().frames_sent, late_, dropped_}; }

  // RenderedOutput
  /// Before the run: makes the renderer and renders once from `d` (nothing is
  /// sent), so that the first frame does not pay for the GL context and the
  /// first draw (a realtime run's first periods). Nothing when not served.
  void BeforeRun(mjData* d) override;
  /// At every period end t (and t = 0), before the period's states go out:
  /// answers datagrams, sends the frames whose delivery time has come. The
  /// frames due at t are rendered here when they are delivered at t (no
  /// latency); otherwise AfterPublish renders them, once the states are out.
  void Deliver(double t, mjData* d) override;
  /// After the states of period end t went out, with the state still that of
  /// t: renders the frames due at t that are delivered later, so their
  /// rendering does not delay the states (a realtime controller's period).
  void AfterPublish(mjData* d) override;

 private:
  // a frame in flight: queued by the control thread (state copied), rendered and
  // encoded by the worker (done), sent by the control thread once its time has come
  // The control thread never takes the worker's mutex in a realtime run: a worker at
  // nice 10 preempted while holding it kept the control thread waiting for milliseconds
  // (priority inversion). It hands frames over with a semaphore (sem_post never blocks)
  // and reads `done` as an atomic; only lockstep and fast runs wait on the mutex.
  struct Pending {
    mjData* state = nullptr;  // the state at the stamp (owned; made with the ring)
    bridge::CameraFrame frame;
    std::atomic<bool> done{false};  // the worker has filled frame (release; set under the mutex)
    bool ok = false;                // (with done) the encoder succeeded
  };
  struct Worker;
  explicit SimCamera(const DeviceConfig& config);
  void QueueDue(mjData* d);  // the frames of due_, from the state at due_t_
  void StartWorker(mjData* d);
  void StopWorker();
  void WorkerMain();
  void Drain();                          // waits until the worker has done every queued frame
  bool WaitDone(Pending& p, bool wait);  // true when done (waiting for it when `wait`)

  std::string scene_;
  const mjModel* m_ = nullptr;
  int camera_ = -1;
  CameraParams config_;
  std::unique_ptr<sensors::CameraModel> model_;
  sensors::CameraNoiseState noise_;  // (the worker's; reseeded for every frame)
  std::uint64_t noise_seed_ = 1;     // the run's seed
  std::unique_ptr<bridge::CameraServer> server_;
  bool realtime_ = false;       // served on the realtime clock: delivery never waits for the worker
  std::vector<Pending> queue_;  // ring of frames queued, not yet delivered
  std::size_t head_ = 0, count_ = 0;
  std::unique_ptr<Worker> worker_;
  long late_ = 0;
  long dropped_ = 0;
  double t_prev_ = -1;
  sensors::FrameRange due_{0, 0};  // frames due at due_t_, not rendered yet
  double due_t_ = 0;
  std::int64_t id_base_ = 0;  // frame ids keep increasing across a reset of the simulated time
  std::int64_t next_id_ = 0;
};

}  // namespace vlab::lab
