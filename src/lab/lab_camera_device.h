// Simulated webcam (kind camera): an MJCF camera rendered offscreen at the
// camera's own frame rate, through the webcam model (sensors/sensor_camera.h),
// delivered after its latency as chunked frames (bridge/bridge_camera_server.h).
//
// Ports
//   input   describe requests and subscriptions (any datagram) on its port
//   output  frames to every subscriber: id, exposure stamp (the simulated time
//           of the state rendered), width, height, encoding, the camera's pose
//           in the world (OpenCV frame: x right, y down, z forward)
//   rate    fps, independent of the control rate: a frame whose stamp falls
//           in a control period is rendered from the state that closes the
//           period (within one control period of its nominal stamp) and sent
//           at the first period end at or after stamp + latency
// Rendering reads the state and never changes it; nothing is rendered while
// nobody subscribes. Under `vlab run` (nothing served) the device is idle.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "bridge/bridge_camera_server.h"
#include "lab/lab_scenario.h"
#include "render/renderer.h"
#include "sensors/sensor_camera.h"

namespace vlab::lab {

class SimCamera {
 public:
  /// Binds the MJCF camera and builds the webcam model. Throws InputError
  /// naming the device: unknown camera, size above the offscreen buffer, a
  /// bad model setting.
  static std::unique_ptr<SimCamera> Create(const mjModel* m, const DeviceConfig& config, const std::string& scene,
                                           std::uint64_t seed);
  ~SimCamera();

  const std::string& name() const { return name_; }
  const sensors::CameraModel& model() const { return *model_; }

  /// Binds its socket (address, port) and makes the describe reply; the
  /// renderer is made by Prepare (or the first frame), on the thread that runs the lab.
  /// Throws InputError naming the device when the port cannot be bound.
  void Serve(const std::string& address, int port, const std::string& server, const std::string& clock);
  bool served() const { return server_ != nullptr; }
  /// The served camera's socket (served() only), and a non-blocking pass over
  /// what arrived on it (describe requests subscribe their senders).
  int fd() { return server_->fd(); }
  void PollRequests() { server_->Poll(0.0); }
  /// Closes its socket and restarts its schedule (a run without serving).
  void Unserve();
  /// Before the run, on the thread that runs the lab: makes the renderer and
  /// renders once from `d` (nothing is sent), so that the first frame does not
  /// pay for the GL context and the first draw (a realtime run's first periods).
  /// Nothing for a camera that is not served.
  void Prepare(mjData* d);
  /// At every period end t (and t = 0), before the period's states go out:
  /// answers datagrams, sends the frames whose delivery time has come. The
  /// frames due at t are rendered here when they are delivered at t (no
  /// latency); otherwise RenderAhead renders them, once the states are out.
  void Observe(double t, mjData* d);
  /// After the states of period end t went out, with the state still that of
  /// t: renders the frames due at t that are delivered later, so their
  /// rendering does not delay the states (a realtime controller's period).
  void RenderAhead(mjData* d);

  const bridge::CameraServer* server() const { return server_.get(); }
  long frames_rendered() const { return rendered_; }

 private:
  struct Pending {
    std::int64_t id = -1;
    double stamp = 0;
    bridge::CameraPose pose;
    std::vector<std::uint8_t> rgb;  // the webcam image (after the lens and noise)
  };
  SimCamera() = default;
  void RenderFrame(std::int64_t id, double t, mjData* d, Pending* slot);
  void MakeRenderer();
  void RenderDue(mjData* d);  // the frames of due_, from the state at due_t_

  std::string name_, where_, scene_;
  const mjModel* m_ = nullptr;
  int camera_ = -1;
  CameraDeviceConfig config_;
  std::unique_ptr<sensors::CameraModel> model_;
  sensors::CameraNoiseState noise_;
  std::unique_ptr<render::Renderer> renderer_;
  render::RgbImage ideal_;
  std::unique_ptr<bridge::CameraServer> server_;
  std::vector<Pending> queue_;  // ring of frames rendered, not yet delivered
  std::size_t head_ = 0, count_ = 0;
  double t_prev_ = -1;
  sensors::FrameRange due_{0, 0};  // frames due at due_t_, not rendered yet
  double due_t_ = 0;
  std::int64_t id_base_ = 0;  // frame ids keep increasing across a reset of the simulated time
  std::int64_t next_id_ = 0;
  long rendered_ = 0;
};

}  // namespace vlab::lab
