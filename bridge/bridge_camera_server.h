// Device side of a camera (kind 4): one UDP socket, subscribers, describe
// replies, and frames sent in chunks. Shared by every camera server: the
// lab's simulated webcam under `vlab serve` and `vlab camera` (a V4L2 webcam
// or a video file), so that a client cannot tell them apart but by the pictures.
//
// Ports
//   input   describe and subscribe requests (and any other datagram) from clients (Poll)
//   output  every frame, chunked, to every subscriber (Send / SendImage);
//           describe replies (JSON) to the requester
//   rate    driven by its owner: Poll whenever its socket is readable (or
//           now and then), Send once per frame
// Rules (the same as bridge::DeviceEndpoint's, with frames for periods)
//   - sessions (bridge_session.h): frames go to subscribers only, who asked
//     with a subscribe request after the cookie handshake; describe replies
//     only to a request with the cookie, rate-limited per source; a
//     subscriber silent for subscriber_timeout_s is dropped (renew the
//     subscription now and then); a full table refuses newcomers;
//   - a malformed datagram is refused and counted by reason; nothing else changes;
//   - a camera takes no commands: a command is refused and counted.
// Threading: one thread at a time. Never throws and never blocks in Poll,
// Send or SendImage (the socket is non-blocking: a chunk the kernel cannot
// take is counted as a send failure). No allocation per chunk; JPEG encoding
// allocates only when a frame is larger than any before.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "bridge/bridge_camera.h"
#include "bridge/bridge_device_server.h"
#include "bridge/bridge_endpoint.h"
#include "bridge/bridge_protocol.h"

namespace vlab::bridge {

/// What a camera's describe reply says about it (docs/protocol_camera.md).
struct CameraDescription {
  std::string name = "camera";
  std::string server;              ///< "vlab camera", "vlab serve (MuJoCo 2.2.2)"
  std::string source;              ///< "/dev/video0", "clip.avi", "MJCF camera 'webcam'"
  std::string clock = "realtime";  ///< whose time the stamps are: realtime (wall clock), lockstep, fast
  int width = 640;                 ///< pixels
  int height = 480;
  double fps = 30;  ///< nominal frame rate, Hz
  CameraEncoding encoding = CameraEncoding::kJpeg;
  int jpeg_quality = 90;  ///< 1..100
  /// Pinhole intrinsics of the images as sent, pixels (centres at whole numbers).
  double fx = 0, fy = 0, cx = 0, cy = 0;
  std::string intrinsics_source = "fovy";        ///< fovy | calibration | estimated
  std::array<double, 4> distortion{0, 0, 0, 0};  ///< k1 k2 p1 p2 (OpenCV plumb_bob) of the images as sent
  double exposure_s = 0;                         ///< exposure time; the stamp is its middle
  double latency_s = 0;                          ///< from the exposure stamp to sending
  double noise = 0;                              ///< pixel noise, grey levels (0: none or unknown)
  std::string pose = "none";                     ///< none | fixed | moving: what the chunks' pose fields carry
};

/// The describe reply (JSON) of a camera bound at address:port.
std::string CameraDescribeJson(const CameraDescription& d, const std::string& address, int port,
                               std::size_t chunk_bytes);

struct CameraServerConfig {
  std::string bind_address = "127.0.0.1";
  int port = 0;  ///< 0: any free port
  CameraDescription description;
  std::size_t chunk_bytes = kDefaultChunkBytes;  ///< frame bytes per chunk, 1..kMaxChunkBytes
  double subscriber_timeout_s = 10;              ///< drop a subscriber silent this long (wall clock)
  int max_subscribers = 16;
  int send_buffer_bytes = 4 << 20;  ///< SO_SNDBUF asked for (a burst of chunks to every subscriber)
  /// Test hook: drop each chunk with this probability before it is sent
  /// (the same chunks for every subscriber), from a seeded generator.
  double test_drop_probability = 0;
  std::uint64_t test_drop_seed = 1;
};

struct CameraServerCounters {
  EndpointCounters endpoint;     ///< received, describes, refused, refused_malformed, sessions (the rest stay 0)
  long frames = 0;               ///< frames given to Send / SendImage
  long frames_sent = 0;          ///< frames sent to at least one subscriber
  long chunks_sent = 0;          ///< datagrams sent, all subscribers
  long send_failures = 0;        ///< datagrams the socket did not take
  long bytes_sent = 0;           ///< frame bytes sent, all subscribers
  long refused_frames = 0;       ///< frames that break the layout (size, encoding, id not increasing)
  long test_dropped_chunks = 0;  ///< chunks dropped by the test hook
  long test_damaged_frames = 0;  ///< frames with at least one chunk dropped by the test hook
  long subscribers_dropped = 0;  ///< silent subscribers dropped
};

/// Encodes RGB8 images (rows top-down) as a camera sends them: raw bytes, or a
/// JPEG file at a quality. Keeps its buffers between frames. One thread at a
/// time; separate encoders may run on separate threads (the lab encodes on a
/// camera's render worker, off its control thread).
class FrameEncoder {
 public:
  FrameEncoder(CameraEncoding encoding, int jpeg_quality);
  ~FrameEncoder();
  FrameEncoder(const FrameEncoder&) = delete;
  FrameEncoder& operator=(const FrameEncoder&) = delete;
  /// width x height x 3 bytes of rgb into *out (resized). False only when
  /// the JPEG encoder fails (never for a valid image).
  bool Encode(int width, int height, const std::uint8_t* rgb, std::vector<std::uint8_t>* out);

 private:
  CameraEncoding encoding_;
  struct Jpeg;
  std::unique_ptr<Jpeg> jpeg_;
};

class CameraServer {
 public:
  /// Validates the configuration and binds the socket. Throws
  /// std::invalid_argument naming a bad field, NetworkError when the address
  /// cannot be bound.
  static std::unique_ptr<CameraServer> Create(const CameraServerConfig& config);
  ~CameraServer();

  /// Handles the datagrams that arrive within timeout_s (0: only those
  /// already queued; the call returns after the first one when it waited).
  void Poll(double timeout_s);
  /// Sends an encoded frame (its data raw RGB8 or JPEG, any size within the
  /// protocol's limits) in chunks to every subscriber. Frame ids must
  /// increase; a frame with a lower or equal id, or a raw frame whose size
  /// is not width*height*3, is refused and counted. True when at least one
  /// subscriber was sent every chunk.
  bool Send(const CameraFrame& frame);
  /// Encodes an RGB8 image (rows top-down, description.width x height) with
  /// the configured encoding and sends it; as Send. Nothing is encoded when
  /// there is no subscriber.
  bool SendImage(std::int64_t id, double time_s, const std::uint8_t* rgb, const CameraPose& pose);

  int port() const;
  /// The socket's descriptor, to wait on it together with others (WaitReadable).
  int fd();
  int subscribers() const { return static_cast<int>(server_->sessions().sessions().size()); }
  /// SO_SNDBUF the kernel granted, bytes.
  int send_buffer_bytes() const { return send_buffer_bytes_; }
  const std::string& describe_json() const { return server_->describe_json(); }
  const CameraServerConfig& config() const { return config_; }
  const CameraServerCounters& counters() const { return counters_; }

 private:
  explicit CameraServer(const CameraServerConfig& config);
  void Handle(const unsigned char* data, std::size_t size, const Endpoint& from);
  void DropSilent();
  bool SendBytes(const ChunkHeader& frame, const std::uint8_t* data);
  bool TestDrop();

  CameraServerConfig config_;
  CameraServerCounters counters_;
  std::unique_ptr<DeviceServer> server_;
  std::int64_t last_id_ = -1;
  int send_buffer_bytes_ = 0;
  std::uint64_t drop_state_ = 0;
  // scratch, sized at creation
  std::vector<unsigned char> chunk_;
  std::unique_ptr<FrameEncoder> encoder_;  // SendImage's
  std::vector<std::uint8_t> encoded_;
};

}  // namespace vlab::bridge
