#include "bridge/bridge_camera_client.h"

#include <sys/socket.h>

#include <algorithm>
#include <sstream>

#include <nlohmann/json.hpp>

#include "bridge/bridge_protocol.h"
#include "render/image_codec.h"

namespace vlab::bridge {

struct CameraClient::Impl {
  explicit Impl(const AssemblerConfig& config) : assembler(config) {}
  FrameAssembler assembler;
  CameraFrame pending;    // a frame being passed over by ReceiveLatest
  render::Image decoded;  // JPEG decoder output (its buffer reused)
};

namespace {

double Seconds(std::chrono::steady_clock::duration d) { return std::chrono::duration<double>(d).count(); }

std::chrono::steady_clock::time_point After(std::chrono::steady_clock::time_point t, double s) {
  return t + std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(s));
}

}  // namespace

const nlohmann::json& CameraClient::describe() const { return *describe_; }

CameraClient::CameraClient(CameraClient&&) noexcept = default;
CameraClient& CameraClient::operator=(CameraClient&&) noexcept = default;
CameraClient::~CameraClient() {
  if (session_ && socket_) session_->Leave(*socket_, device_);
}

CameraClient CameraClient::Connect(const std::string& address, int port, const CameraClientOptions& options) {
  return CameraClient(address, port, options);
}

CameraClient::CameraClient(const std::string& address, int port, const CameraClientOptions& options)
    : options_(options), device_(UdpSocket::Resolve(address, port)), impl_(new Impl(options.assembler)),
      buffer_(kDatagramBufferBytes), start_(Clock::now()) {
  const bool any_v4 = options.bind_address == "0.0.0.0";
  socket_ = UdpSocket::Bind(any_v4 && device_.address().is_v6() ? "::" : options.bind_address, 0);
  receive_buffer_bytes_ = SetSocketBuffer(socket_->fd(), SO_RCVBUF, options.receive_buffer_bytes);
  session_ = std::make_unique<ClientSession>(DeviceKind::kCamera, Label());
  // the handshake; chunks arriving meanwhile are fed to the assembler
  session_->Connect(
      *socket_, device_, options.timeout_s, &buffer_,
      [this](const unsigned char* json, long size) { CheckDescribe(json, size); },
      [this](long size) {
        impl_->assembler.Add(buffer_.data(), static_cast<std::size_t>(size), Seconds(Clock::now() - start_));
      },
      &datagrams_skipped_);
  next_keepalive_ = After(Clock::now(), options_.keepalive_s);
}

void CameraClient::CheckDescribe(const unsigned char* data, long size) {
  try {
    describe_ = std::make_unique<nlohmann::json>(nlohmann::json::parse(data, data + size));
  } catch (const nlohmann::json::exception& e) {
    throw ProtocolError(Label() + ": describe reply is not valid JSON: " + e.what());
  }
  if (!describe_->is_object()) throw ProtocolError(Label() + ": describe reply is not a JSON object");
  const nlohmann::json version = describe_->value("protocol", nlohmann::json());
  if (!version.is_number()) throw ProtocolError(Label() + ": describe reply has no numeric \"protocol\"");
  if (version.get<double>() != kProtocolVersion) {
    throw VersionMismatch(Label() + ": the device speaks protocol version " + version.dump() +
                          ", this client speaks version " + std::to_string(kProtocolVersion));
  }
  const nlohmann::json kind = describe_->value("kind", nlohmann::json());
  if (!kind.is_string() || kind.get<std::string>() != "camera") {
    throw ProtocolError(Label() + ": the device is of kind " + kind.dump() + ", not \"camera\"");
  }
  const nlohmann::json name = describe_->value("name", nlohmann::json());
  if (name.is_string()) name_ = name.get<std::string>();

  // the facts a client relies on
  auto number = [&](const nlohmann::json& object, const char* field, const std::string& path) {
    if (!object.is_object() || !object.contains(field) || !object[field].is_number()) {
      throw ProtocolError(Label() + ": describe reply has no number \"" + path + "\"");
    }
    return object[field].get<double>();
  };
  calibration_.width = static_cast<int>(number(*describe_, "width", "width"));
  calibration_.height = static_cast<int>(number(*describe_, "height", "height"));
  fps_ = number(*describe_, "fps", "fps");
  const nlohmann::json encoding = describe_->value("encoding", nlohmann::json());
  if (!encoding.is_string() || !EncodingFromName(encoding.get<std::string>(), &encoding_)) {
    throw ProtocolError(Label() + ": describe reply's \"encoding\" is " + encoding.dump() +
                        ", not \"raw\" or \"jpeg\"");
  }
  const nlohmann::json intrinsics = describe_->value("intrinsics", nlohmann::json());
  calibration_.fx = number(intrinsics, "fx", "intrinsics.fx");
  calibration_.fy = number(intrinsics, "fy", "intrinsics.fy");
  calibration_.cx = number(intrinsics, "cx", "intrinsics.cx");
  calibration_.cy = number(intrinsics, "cy", "intrinsics.cy");
  calibration_.source = intrinsics.value("source", "");
  const nlohmann::json distortion = describe_->value("distortion", nlohmann::json());
  if (distortion.is_object()) {
    const char* fields[4] = {"k1", "k2", "p1", "p2"};
    for (int i = 0; i < 4; ++i) {
      calibration_.distortion[i] = number(distortion, fields[i], std::string("distortion.") + fields[i]);
    }
  }
}

std::string CameraClient::Label() const {
  std::string label = "camera";
  if (!name_.empty()) label += " '" + name_ + "'";
  return label + " at " + EndpointText(device_);
}

int CameraClient::local_port() const { return socket_->local_port(); }

const AssemblerCounters& CameraClient::counters() const { return impl_->assembler.counters(); }

bool CameraClient::KeepAlive() { return session_->KeepAlive(*socket_, device_); }

bool CameraClient::NextFrame(Clock::time_point deadline, bool queued_only, CameraFrame* frame) {
  FrameAssembler& assembler = impl_->assembler;
  for (;;) {
    if (assembler.Take(frame)) return true;
    Clock::time_point now = Clock::now();
    // a stream of chunks that never completes a frame must not hold the caller past its deadline
    if (!queued_only && now >= deadline) {
      assembler.Expire(Seconds(now - start_));
      return false;
    }
    if (now >= next_keepalive_) {
      KeepAlive();
      next_keepalive_ = After(now, options_.keepalive_s);
    }
    const double wait_s = queued_only ? 0.0 : std::max(0.0, Seconds(std::min(deadline, next_keepalive_) - now));
    Endpoint from;
    const long n = socket_->Receive(buffer_.data(), buffer_.size(), &from, wait_s);
    now = Clock::now();
    if (n < 0) {
      assembler.Expire(Seconds(now - start_));
      if (queued_only || now >= deadline) return false;
      continue;
    }
    if (from.port() != device_.port() || (n > 0 && buffer_[0] == '{') ||
        IsSessionReply(buffer_.data(), static_cast<std::size_t>(n))) {
      ++datagrams_skipped_;  // another sender, a describe reply, or the answer to a keep-alive
      continue;
    }
    ChunkError error;
    assembler.Add(buffer_.data(), static_cast<std::size_t>(n), Seconds(now - start_), &error);
    if (error == ChunkError::kBadVersion) {
      throw VersionMismatch(Label() + ": the device sent a chunk of protocol version " +
                            ErrorNumber(GetDouble(buffer_.data() + 8)) + ", this client speaks version " +
                            std::to_string(kProtocolVersion));
    }
  }
}

bool CameraClient::Decode(Frame* frame) {
  if (!options_.decode) {
    frame->rgb.clear();
    return true;
  }
  const std::size_t bytes = 3u * static_cast<std::size_t>(frame->width) * frame->height;
  if (frame->encoding == CameraEncoding::kRaw) {
    frame->rgb.assign(frame->data.begin(), frame->data.end());
    return true;
  }
  try {
    render::DecodeImage(frame->data.data(), frame->data.size(), render::DecodeMode::kColor, &impl_->decoded);
  } catch (const render::ImageCodecError&) {
    return false;
  }
  const render::Image& image = impl_->decoded;
  if (image.width != frame->width || image.height != frame->height || image.bytes.size() != bytes) return false;
  frame->rgb.assign(image.bytes.begin(), image.bytes.end());
  return true;
}

void CameraClient::ThrowTimeout(double timeout_s) const {
  const AssemblerCounters& c = counters();
  throw TimeoutError(Label() + ": no whole frame within " + ErrorSeconds(timeout_s) + " (" + std::to_string(c.chunks) +
                     " chunks so far, " + std::to_string(c.frames_dropped) + " frames dropped incomplete, " +
                     std::to_string(c.refused) + " chunks refused)");
}

void CameraClient::Receive(double timeout_s, Frame* frame) {
  const Clock::time_point deadline = After(Clock::now(), std::max(0.0, timeout_s));
  for (;;) {
    if (!NextFrame(deadline, false, frame)) ThrowTimeout(timeout_s);
    if (Decode(frame)) break;
    ++undecodable_;
  }
  ++frames_returned_;
}

CameraClient::Frame CameraClient::Receive(double timeout_s) {
  Frame frame;
  Receive(timeout_s, &frame);
  return frame;
}

void CameraClient::ReceiveLatest(double timeout_s, Frame* frame) {
  const Clock::time_point deadline = After(Clock::now(), std::max(0.0, timeout_s));
  bool have = false;
  for (;;) {
    // wait for the first whole frame; then only take what is already queued
    CameraFrame& next = impl_->pending;
    if (!NextFrame(deadline, have, &next)) {
      if (!have) ThrowTimeout(timeout_s);
      if (Decode(frame)) break;
      ++undecodable_;
      have = false;  // wait again, up to the deadline
      continue;
    }
    if (have) ++frames_skipped_;
    have = true;
    static_cast<CameraFrame&>(*frame).id = next.id;
    frame->time_s = next.time_s;
    frame->width = next.width;
    frame->height = next.height;
    frame->encoding = next.encoding;
    frame->pose = next.pose;
    std::swap(frame->data, next.data);
  }
  ++frames_returned_;
}

}  // namespace vlab::bridge
