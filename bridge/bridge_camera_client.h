// The C++ client of a camera device (kind 4, docs/protocol_camera.md): whole
// frames, reassembled from their chunks, with the raw or JPEG bytes as sent
// and the decoded RGB8 image.
//
//   auto camera = vlab::bridge::CameraClient::Connect("127.0.0.1", 50013);
//   vlab::bridge::CameraClient::Frame frame;
//   camera.ReceiveLatest(1.0, &frame);   // id, time_s, width, height, pose, rgb
//
// Connecting makes a session (docs/protocol.md, "Sessions": the cookie, the
// describe reply, a subscription); it then renews the subscription every
// keepalive_s while it receives, so it never lapses, and ends it on
// destruction. Incomplete frames are dropped (FrameAssembler);
// a frame is never returned torn. Malformed chunks are refused and counted
// (counters()), not thrown: a camera stream survives a stray datagram.
//
// Threading: a client is not thread-safe; use one from one thread at a time.
// Errors (bridge_errors.h): NetworkError, TimeoutError, ProtocolError (a bad
// describe reply), VersionMismatch (a reply or chunk of another version).
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "bridge/bridge_camera.h"
#include "bridge/bridge_camera_assembler.h"
#include "bridge/bridge_errors.h"
#include "bridge/bridge_session.h"
#include "bridge/bridge_udp.h"

namespace vlab::bridge {

struct CameraClientOptions {
  double timeout_s = 1.0;                ///< Connect waits this long for the describe reply, s
  std::string bind_address = "0.0.0.0";  ///< local address (port: any free one)
  int receive_buffer_bytes = 8 << 20;    ///< SO_RCVBUF asked for (forced where permitted)
  double keepalive_s = 1.0;              ///< renew the subscription this often while receiving, s
  bool decode = true;                    ///< fill Frame::rgb (JPEG decoded with OpenCV)
  AssemblerConfig assembler;
};

/// Intrinsics and distortion from the describe reply, pixels.
struct CameraCalibration {
  int width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  std::array<double, 4> distortion{0, 0, 0, 0};  ///< k1 k2 p1 p2 (OpenCV plumb_bob)
  std::string source;                            ///< fovy | calibration | estimated
};

class CameraClient {
 public:
  /// A whole frame: the wire fields (CameraFrame) and the decoded image.
  struct Frame : CameraFrame {
    std::vector<std::uint8_t> rgb;  ///< RGB8, rows top-down, width*height*3 (empty when decode is off)
  };

  /// Connects to the camera at address:port (numeric IPv4/IPv6 or a host
  /// name; port 1..65535): describes it and subscribes to its frames.
  /// Throws NetworkError, TimeoutError (no reply within options.timeout_s),
  /// VersionMismatch, ProtocolError (not a camera, or a reply without width,
  /// height, fps, encoding or intrinsics).
  static CameraClient Connect(const std::string& address, int port, const CameraClientOptions& options = {});
  CameraClient(CameraClient&&) noexcept;
  CameraClient& operator=(CameraClient&&) noexcept;
  ~CameraClient();

  /// Waits up to timeout_s (s) for the next whole frame (frames arrive in
  /// increasing id). Throws TimeoutError, VersionMismatch.
  Frame Receive(double timeout_s);
  /// The same into *frame (no allocation once its buffers have the size).
  void Receive(double timeout_s, Frame* frame);
  /// Waits up to timeout_s for a whole frame, then takes every datagram
  /// already queued and returns the newest whole frame: what a real-time
  /// consumer wants. Throws as Receive.
  void ReceiveLatest(double timeout_s, Frame* frame);

  /// Renews the subscription now (Receive does it every keepalive_s).
  bool KeepAlive();

  const nlohmann::json& describe() const;
  const std::string& name() const { return name_; }
  int width() const { return calibration_.width; }
  int height() const { return calibration_.height; }
  double fps() const { return fps_; }
  CameraEncoding encoding() const { return encoding_; }
  const CameraCalibration& calibration() const { return calibration_; }
  /// "camera 'webcam' at 127.0.0.1:50013", for messages.
  std::string Label() const;
  int local_port() const;
  /// SO_RCVBUF the kernel granted, bytes (as getsockopt reports it).
  int receive_buffer_bytes() const { return receive_buffer_bytes_; }

  /// Chunks and frames: refused by reason, late, dropped incomplete, ...
  const AssemblerCounters& counters() const;
  long frames_returned() const { return frames_returned_; }
  long frames_skipped() const { return frames_skipped_; }  ///< whole frames ReceiveLatest passed over
  long undecodable() const { return undecodable_; }        ///< whole frames whose JPEG did not decode to width x height
  long datagrams_skipped() const { return datagrams_skipped_; }  ///< describe and session replies, other senders

 private:
  using Clock = std::chrono::steady_clock;
  struct Impl;
  CameraClient(const std::string& address, int port, const CameraClientOptions& options);
  void CheckDescribe(const unsigned char* data, long size);
  /// The next whole frame into *frame (undecoded), waiting until the
  /// deadline, or with queued_only from the datagrams already queued; false if none.
  bool NextFrame(Clock::time_point deadline, bool queued_only, CameraFrame* frame);
  /// Fills frame->rgb; false if the JPEG does not decode to its size.
  bool Decode(Frame* frame);
  [[noreturn]] void ThrowTimeout(double timeout_s) const;

  CameraClientOptions options_;
  Endpoint device_;
  std::unique_ptr<UdpSocket> socket_;
  std::unique_ptr<Impl> impl_;
  std::unique_ptr<nlohmann::json> describe_;  // the full JSON type stays in the .cc
  std::string name_;
  double fps_ = 0;
  CameraEncoding encoding_ = CameraEncoding::kRaw;
  CameraCalibration calibration_;
  std::vector<unsigned char> buffer_;
  std::unique_ptr<ClientSession> session_;
  Clock::time_point start_;
  Clock::time_point next_keepalive_;
  int receive_buffer_bytes_ = 0;
  long frames_returned_ = 0;
  long frames_skipped_ = 0;
  long undecodable_ = 0;
  long datagrams_skipped_ = 0;
};

}  // namespace vlab::bridge
