#include "bridge/bridge_camera.h"

#include <cmath>

#include "bridge/bridge_protocol.h"

namespace vlab::bridge {

namespace {

constexpr double kMaxSeq = 9007199254740992.0;  // 2^53
// a raw frame of the largest image; any frame must be smaller than this
constexpr double kMaxFrameBytes = 3.0 * kMaxImageSide * kMaxImageSide;

}  // namespace

const char* EncodingName(CameraEncoding encoding) { return encoding == CameraEncoding::kJpeg ? "jpeg" : "raw"; }

bool EncodingFromName(const std::string& name, CameraEncoding* encoding) {
  if (name == "raw") {
    *encoding = CameraEncoding::kRaw;
  } else if (name == "jpeg") {
    *encoding = CameraEncoding::kJpeg;
  } else {
    return false;
  }
  return true;
}

const char* ChunkErrorName(ChunkError e) {
  switch (e) {
    case ChunkError::kNone:
      return "ok";
    case ChunkError::kTooShort:
      return "too short";
    case ChunkError::kBadMagic:
      return "bad magic";
    case ChunkError::kBadVersion:
      return "bad version";
    case ChunkError::kBadKind:
      return "wrong device kind";
    case ChunkError::kBadType:
      return "wrong message type";
    case ChunkError::kBadLength:
      return "bad length";
    case ChunkError::kNotFinite:
      return "non-finite value";
    case ChunkError::kBadValue:
      return "value out of domain";
    case ChunkError::kBadImage:
      return "bad image size or encoding";
    case ChunkError::kBadLayout:
      return "bad chunk layout";
    case ChunkError::kBadPose:
      return "bad pose";
    case ChunkError::kInconsistent:
      return "inconsistent with its frame";
    case ChunkError::kTooLarge:
      return "frame too large";
  }
  return "unknown";
}

std::size_t EncodeCameraChunk(const ChunkHeader& h, const std::uint8_t* bytes, unsigned char* out) {
  const Eigen::Vector3d& p = h.pose.p_WC;
  const Eigen::Quaterniond& q = h.pose.q_WC;
  const double values[7 + kChunkValues] = {
      kMagic, static_cast<double>(kProtocolVersion), static_cast<double>(DeviceKind::kCamera),
      static_cast<double>(MessageType::kState), static_cast<double>(h.frame_id), h.time_s,
      static_cast<double>(kChunkValues),
      // chunk values
      static_cast<double>(h.chunk_index), static_cast<double>(h.chunk_count), static_cast<double>(h.width),
      static_cast<double>(h.height), static_cast<double>(h.encoding), static_cast<double>(h.frame_bytes),
      static_cast<double>(h.offset), static_cast<double>(h.chunk_bytes), h.pose.valid ? 1.0 : 0.0,
      // an unknown pose travels as the origin and the identity
      h.pose.valid ? p.x() : 0.0, h.pose.valid ? p.y() : 0.0, h.pose.valid ? p.z() : 0.0, h.pose.valid ? q.w() : 1.0,
      h.pose.valid ? q.x() : 0.0, h.pose.valid ? q.y() : 0.0, h.pose.valid ? q.z() : 0.0};
  unsigned char* at = out;
  for (double v : values) {
    PutDouble(v, at);
    at += sizeof(double);
  }
  for (std::size_t i = 0; i < h.chunk_bytes; ++i) at[i] = bytes[i];
  return kChunkHeaderBytes + h.chunk_bytes;
}

ChunkError DecodeCameraChunk(const unsigned char* data, std::size_t size, ChunkHeader* h, const unsigned char** bytes) {
  // framing: the 7-value header, then `length` values, then the bytes
  if (size < kHeaderBytes) return ChunkError::kTooShort;
  double header[kHeaderValues];
  for (int i = 0; i < kHeaderValues; ++i) header[i] = GetDouble(data + 8 * i);
  if (header[0] != kMagic) return ChunkError::kBadMagic;
  if (header[1] != kProtocolVersion) return ChunkError::kBadVersion;
  for (double v : header) {
    if (!std::isfinite(v)) return ChunkError::kNotFinite;
  }
  if (header[2] != static_cast<double>(DeviceKind::kCamera)) return ChunkError::kBadKind;
  if (header[3] != static_cast<double>(MessageType::kState)) return ChunkError::kBadType;
  if (!IsWhole(header[4], 0, kMaxSeq)) return ChunkError::kBadValue;
  if (!IsWhole(header[6], kChunkValues, kMaxPacketValues - kHeaderValues)) return ChunkError::kBadLength;
  const std::size_t values = static_cast<std::size_t>(header[6]);
  const std::size_t head = (kHeaderValues + values) * sizeof(double);
  if (size < head) return ChunkError::kTooShort;
  double c[kChunkValues];
  for (int i = 0; i < kChunkValues; ++i) c[i] = GetDouble(data + kHeaderBytes + 8 * i);
  for (std::size_t i = 0; i < values; ++i) {
    if (!std::isfinite(GetDouble(data + kHeaderBytes + 8 * i))) return ChunkError::kNotFinite;
  }

  // the image: size, encoding, byte count
  if (!IsWhole(c[2], 1, kMaxImageSide) || !IsWhole(c[3], 1, kMaxImageSide)) return ChunkError::kBadImage;
  if (!IsWhole(c[4], 0, 1)) return ChunkError::kBadImage;
  if (!IsWhole(c[5], 1, kMaxFrameBytes)) return ChunkError::kBadImage;
  if (c[4] == 0 && c[5] != 3.0 * c[2] * c[3]) return ChunkError::kBadImage;

  // the layout rule: chunks of P bytes, the last one ends at frame_bytes
  if (!IsWhole(c[1], 1, kMaxChunks) || !IsWhole(c[0], 0, c[1] - 1)) return ChunkError::kBadLayout;
  if (!IsWhole(c[6], 0, c[5] - 1) || !IsWhole(c[7], 1, c[5] - c[6])) return ChunkError::kBadLayout;
  if (c[7] != static_cast<double>(size - head)) return ChunkError::kBadLength;
  const double count = c[1], index = c[0], frame = c[5], offset = c[6], chunk = c[7];
  if (index < count - 1) {
    // a full chunk: P = chunk_bytes, and P must give exactly `count` chunks
    if (offset != index * chunk || std::ceil(frame / chunk) != count) return ChunkError::kBadLayout;
  } else {
    if (offset + chunk != frame || (count == 1 && offset != 0)) return ChunkError::kBadLayout;
    // P = offset / (count - 1) must be whole and at least this chunk's size
    if (count > 1 && (std::fmod(offset, count - 1) != 0 || offset / (count - 1) < chunk)) {
      return ChunkError::kBadLayout;
    }
  }

  // the pose
  if (!IsWhole(c[8], 0, 1)) return ChunkError::kBadPose;
  const bool pose_valid = c[8] == 1;
  const Eigen::Quaterniond q(c[12], c[13], c[14], c[15]);
  if (pose_valid && std::abs(q.squaredNorm() - 1.0) > 2e-6) return ChunkError::kBadPose;

  h->frame_id = static_cast<std::int64_t>(header[4]);
  h->time_s = header[5];
  h->chunk_index = static_cast<int>(index);
  h->chunk_count = static_cast<int>(count);
  h->width = static_cast<int>(c[2]);
  h->height = static_cast<int>(c[3]);
  h->encoding = static_cast<CameraEncoding>(static_cast<int>(c[4]));
  h->frame_bytes = static_cast<std::size_t>(frame);
  h->offset = static_cast<std::size_t>(offset);
  h->chunk_bytes = static_cast<std::size_t>(chunk);
  h->pose.valid = pose_valid;
  h->pose.p_WC = Eigen::Vector3d(c[9], c[10], c[11]);
  h->pose.q_WC = q;
  *bytes = data + head;
  return ChunkError::kNone;
}

}  // namespace vlab::bridge
