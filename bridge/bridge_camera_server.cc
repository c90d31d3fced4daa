#include "bridge/bridge_camera_server.h"

#include <sys/socket.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "render/image_codec.h"

namespace vlab::bridge {

struct FrameEncoder::Jpeg {
  int quality = 95;
};

FrameEncoder::FrameEncoder(CameraEncoding encoding, int jpeg_quality) : encoding_(encoding), jpeg_(new Jpeg) {
  jpeg_->quality = jpeg_quality;
}

FrameEncoder::~FrameEncoder() = default;

bool FrameEncoder::Encode(int width, int height, const std::uint8_t* rgb, std::vector<std::uint8_t>* out) {
  const std::size_t raw_bytes = 3u * static_cast<std::size_t>(width) * height;
  if (encoding_ == CameraEncoding::kRaw) {
    out->assign(rgb, rgb + raw_bytes);
    return true;
  }
  try {
    render::EncodeJpeg({width, height, 3, 8, rgb, 0}, jpeg_->quality, out);
  } catch (const render::ImageCodecError&) {
    return false;  // (never with a valid image; counted by the caller, never thrown)
  }
  return !out->empty();
}

std::string CameraDescribeJson(const CameraDescription& d, const std::string& address, int port,
                               std::size_t chunk_bytes) {
  using nlohmann::json;
  json j = {{"name", d.name},
            {"kind", "camera"},
            {"protocol", kProtocolVersion},
            {"server", d.server},
            {"clock", d.clock},
            {"source", d.source},
            {"endpoint", {{"address", address}, {"port", port}}},
            {"rates", {{"fps", d.fps}}},
            {"header", {"magic", "version", "kind", "type", "seq", "time", "length"}}};
  j["layout"] = {{"state",
                  {"chunk_index", "chunk_count", "width", "height", "encoding", "frame_bytes", "offset", "chunk_bytes",
                   "pose_valid", "px", "py", "pz", "qw", "qx", "qy", "qz", "bytes[chunk_bytes]"}},
                 {"command", json::array()}};
  j["units"] = {{"time", "s (middle of the exposure)"},
                {"width", "px"},
                {"height", "px"},
                {"position", "m (world)"},
                {"orientation", "unit quaternion w x y z (world)"},
                {"intrinsics", "px"}};
  j["width"] = d.width;
  j["height"] = d.height;
  j["fps"] = d.fps;
  j["encoding"] = EncodingName(d.encoding);
  j["encodings"] = {{"raw", 0}, {"jpeg", 1}};
  j["jpeg_quality"] = d.jpeg_quality;
  j["chunk_bytes"] = chunk_bytes;
  j["intrinsics"] = {{"model", "pinhole"}, {"width", d.width}, {"height", d.height}, {"fx", d.fx},
                     {"fy", d.fy},         {"cx", d.cx},       {"cy", d.cy},         {"source", d.intrinsics_source}};
  j["distortion"] = {{"model", "plumb_bob"},
                     {"k1", d.distortion[0]},
                     {"k2", d.distortion[1]},
                     {"p1", d.distortion[2]},
                     {"p2", d.distortion[3]}};
  j["exposure_s"] = d.exposure_s;
  j["latency_s"] = d.latency_s;
  j["noise"] = d.noise;
  j["pose"] = d.pose;
  j["camera_frame"] = "OpenCV: x right, y down, z forward";
  return j.dump();
}

namespace {

void Check(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("camera server: " + what);
}

}  // namespace

CameraServer::CameraServer(const CameraServerConfig& config)
    : config_(config), encoder_(new FrameEncoder(config.description.encoding, config.description.jpeg_quality)) {}
CameraServer::~CameraServer() = default;

std::unique_ptr<CameraServer> CameraServer::Create(const CameraServerConfig& config) {
  const CameraDescription& d = config.description;
  Check(d.width >= 1 && d.width <= kMaxImageSide, "width must be 1 to 16384 pixels");
  Check(d.height >= 1 && d.height <= kMaxImageSide, "height must be 1 to 16384 pixels");
  Check(d.fps > 0 && d.fps <= 1000, "fps must be > 0 and <= 1000 Hz");
  Check(d.jpeg_quality >= 1 && d.jpeg_quality <= 100, "jpeg_quality must be 1 to 100");
  Check(config.chunk_bytes >= 1 && config.chunk_bytes <= kMaxChunkBytes,
        "chunk_bytes must be 1 to " + std::to_string(kMaxChunkBytes));
  Check(3.0 * d.width * d.height / static_cast<double>(config.chunk_bytes) <= kMaxChunks,
        "chunk_bytes too small: a raw frame would need more than 65535 chunks");
  Check(config.subscriber_timeout_s > 0, "subscriber_timeout_s must be > 0");
  Check(config.max_subscribers >= 1, "max_subscribers must be >= 1");
  Check(config.test_drop_probability >= 0 && config.test_drop_probability <= 1, "test_drop_probability must be 0 to 1");

  std::unique_ptr<CameraServer> s(new CameraServer(config));
  DeviceServerConfig server;
  server.bind_address = config.bind_address;
  server.port = config.port;
  server.max_datagrams = 0;  // every datagram queued
  s->server_ = DeviceServer::Bind(server);
  s->send_buffer_bytes_ = SetSocketBuffer(s->server_->fd(), SO_SNDBUF, config.send_buffer_bytes);
  SessionConfig sessions;
  sessions.kind = DeviceKind::kCamera;
  sessions.max_subscribers = config.max_subscribers;
  sessions.subscriber_timeout_s = config.subscriber_timeout_s;
  s->server_->ServeSessions(sessions,
                            CameraDescribeJson(d, config.bind_address, s->server_->port(), config.chunk_bytes));
  s->chunk_.resize(ChunkDatagramBytes(config.chunk_bytes));
  s->drop_state_ = config.test_drop_seed;
  return s;
}

int CameraServer::port() const { return server_->port(); }

int CameraServer::fd() { return server_->fd(); }

void CameraServer::Poll(double timeout_s) {
  server_->Drain(timeout_s, [this](const unsigned char* data, std::size_t size, const Endpoint& from) {
    Handle(data, size, from);
  });
}

void CameraServer::DropSilent() {
  SessionTable& sessions = server_->sessions();
  const long before = sessions.counters().expired;
  sessions.Expire();
  counters_.subscribers_dropped += sessions.counters().expired - before;
}

void CameraServer::Handle(const unsigned char* data, std::size_t size, const Endpoint& from) {
  EndpointCounters& c = counters_.endpoint;
  ++c.received;
  // a camera takes no commands: one is refused as malformed, like a state or a broken datagram
  switch (server_->HandleRequest(data, size, from)) {
    case DeviceServer::Request::kDescribed:
      ++c.describes;
      break;
    case DeviceServer::Request::kSession:
      break;
    default:
      ++c.refused;
      ++c.refused_malformed;
      break;
  }
  c.sessions = server_->sessions().counters();
}

bool CameraServer::TestDrop() {
  if (config_.test_drop_probability <= 0) return false;
  // splitmix64: a seeded, platform-independent sequence
  std::uint64_t z = (drop_state_ += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1.0p-53 < config_.test_drop_probability;
}

bool CameraServer::SendBytes(const ChunkHeader& frame, const std::uint8_t* data) {
  DropSilent();
  std::vector<SessionTable::Session>& subscribers = server_->sessions().sessions();
  if (subscribers.empty()) return false;
  for (SessionTable::Session& s : subscribers) s.mark = false;
  const int count = ChunkCount(frame.frame_bytes, config_.chunk_bytes);
  ChunkHeader h = frame;
  h.chunk_count = count;
  bool damaged = false;
  for (int i = 0; i < count; ++i) {
    h.chunk_index = i;
    h.offset = static_cast<std::size_t>(i) * config_.chunk_bytes;
    h.chunk_bytes = std::min(config_.chunk_bytes, frame.frame_bytes - h.offset);
    const std::size_t size = EncodeCameraChunk(h, data + h.offset, chunk_.data());
    if (TestDrop()) {
      ++counters_.test_dropped_chunks;
      damaged = true;
      continue;
    }
    for (SessionTable::Session& s : subscribers) {
      if (server_->socket().SendTo(chunk_.data(), size, s.endpoint)) {
        ++counters_.chunks_sent;
        counters_.bytes_sent += static_cast<long>(h.chunk_bytes);
      } else {
        ++counters_.send_failures;
        s.mark = true;  // a chunk of this frame did not go out
      }
    }
  }
  if (damaged) {
    ++counters_.test_damaged_frames;
    return false;
  }
  const bool whole =
      std::any_of(subscribers.begin(), subscribers.end(), [](const SessionTable::Session& s) { return !s.mark; });
  if (whole) ++counters_.frames_sent;
  return whole;
}

bool CameraServer::Send(const CameraFrame& frame) {
  ++counters_.frames;
  const bool raw_ok = frame.encoding != CameraEncoding::kRaw ||
                      frame.data.size() == 3u * static_cast<std::size_t>(frame.width) * frame.height;
  const bool ok = frame.id > last_id_ && frame.width >= 1 && frame.width <= kMaxImageSide && frame.height >= 1 &&
                  frame.height <= kMaxImageSide && !frame.data.empty() && raw_ok &&
                  frame.data.size() <= 3.0 * kMaxImageSide * kMaxImageSide &&
                  ChunkCount(frame.data.size(), config_.chunk_bytes) <= kMaxChunks && std::isfinite(frame.time_s) &&
                  static_cast<double>(frame.id) <= 9007199254740992.0;
  if (!ok) {
    ++counters_.refused_frames;
    return false;
  }
  last_id_ = frame.id;
  ChunkHeader h;
  h.frame_id = frame.id;
  h.time_s = frame.time_s;
  h.width = frame.width;
  h.height = frame.height;
  h.encoding = frame.encoding;
  h.frame_bytes = frame.data.size();
  h.pose = frame.pose;
  if (h.pose.valid) h.pose.q_WC.normalize();
  return SendBytes(h, frame.data.data());
}

bool CameraServer::SendImage(std::int64_t id, double time_s, const std::uint8_t* rgb, const CameraPose& pose) {
  const CameraDescription& d = config_.description;
  if (id <= last_id_ || !std::isfinite(time_s) || rgb == nullptr) {
    ++counters_.frames;
    ++counters_.refused_frames;
    return false;
  }
  DropSilent();
  if (server_->sessions().sessions().empty()) {  // nobody listens: skip the encoding
    ++counters_.frames;
    last_id_ = id;
    return false;
  }
  ++counters_.frames;
  last_id_ = id;
  ChunkHeader h;
  h.frame_id = id;
  h.time_s = time_s;
  h.width = d.width;
  h.height = d.height;
  h.encoding = d.encoding;
  h.pose = pose;
  if (h.pose.valid) h.pose.q_WC.normalize();
  if (d.encoding == CameraEncoding::kRaw) {
    h.frame_bytes = 3u * static_cast<std::size_t>(d.width) * d.height;
    return SendBytes(h, rgb);
  }
  if (!encoder_->Encode(d.width, d.height, rgb, &encoded_)) {
    ++counters_.refused_frames;
    return false;
  }
  h.frame_bytes = encoded_.size();
  return SendBytes(h, encoded_.data());
}

}  // namespace vlab::bridge
