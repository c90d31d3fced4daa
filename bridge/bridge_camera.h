// Camera frames on the wire (device kind 4): the chunk format and its codec.
// docs/protocol_camera.md is the contract; this header implements it.
//
// A frame (raw RGB8 rows top-down, or one JPEG file) is too big for one
// datagram, so it travels in numbered chunks. Each chunk is one datagram:
//
//   float64 header (7 values, little-endian, as every vlab datagram)
//     magic, version, kind 4, type 1 (state), seq = frame id,
//     time = exposure stamp (s), length = number of chunk values that follow
//   float64 chunk values (length >= kChunkValues; values beyond are reserved)
//     0 chunk_index   1 chunk_count   2 width (px)   3 height (px)
//     4 encoding (0 raw RGB8, 1 JPEG)  5 frame_bytes  6 offset (bytes)
//     7 chunk_bytes   8 pose_valid (0/1)
//     9..11 camera position in the world (m)
//     12..15 camera orientation in the world, quaternion w x y z
//   the frame's bytes [offset, offset + chunk_bytes)
//
// Layout rule: every chunk but the last carries the same number of bytes P,
// chunk i starts at byte i * P, and the last one ends at frame_bytes. The
// camera frame whose pose is given is OpenCV's: x right, y down, z forward.
//
// Decoding never trusts the datagram: every value is checked before it is
// used, and a chunk that breaks a rule is refused with a reason.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace vlab::bridge {

/// Chunk values after the 7-value header (the minimum `length`).
inline constexpr int kChunkValues = 16;
/// Bytes before a chunk's frame bytes: (7 + 16) float64.
inline constexpr std::size_t kChunkHeaderBytes = (7 + kChunkValues) * sizeof(double);
/// Frame bytes per chunk by default: a 60184-byte datagram, under the 65507
/// bytes an IPv4 UDP datagram can carry (docs/protocol_camera.md says why).
inline constexpr std::size_t kDefaultChunkBytes = 60000;
/// Most frame bytes one chunk may carry so that the datagram fits IPv4 UDP.
inline constexpr std::size_t kMaxChunkBytes = 65507 - kChunkHeaderBytes;
/// Largest image side (pixels) and number of chunks of a frame.
inline constexpr int kMaxImageSide = 16384;
inline constexpr int kMaxChunks = 65535;

/// How a frame's bytes encode its image.
enum class CameraEncoding : int {
  kRaw = 0,   ///< RGB8, rows top-down, 3 bytes per pixel, no padding: width * height * 3 bytes
  kJpeg = 1,  ///< one baseline JPEG file (JFIF), colour
};
/// "raw" / "jpeg"; and back (false for anything else).
const char* EncodingName(CameraEncoding encoding);
bool EncodingFromName(const std::string& name, CameraEncoding* encoding);

/// The camera's pose in the world at exposure: the OpenCV camera frame C
/// (x right, y down, z forward) in the world frame W.
struct CameraPose {
  bool valid = false;  ///< false: unknown (a camera without --pose); the values are then meaningless
  Eigen::Vector3d p_WC = Eigen::Vector3d::Zero();            ///< position of C's origin, m
  Eigen::Quaterniond q_WC = Eigen::Quaterniond::Identity();  ///< orientation of C in W (unit)
};

/// One whole frame as it travels: what the device sends and a client receives.
struct CameraFrame {
  std::int64_t id = 0;  ///< frame id, increasing by one per frame the device produces
  double time_s = 0;    ///< exposure stamp, s (middle of the exposure; the device's clock)
  int width = 0;        ///< pixels
  int height = 0;       ///< pixels
  CameraEncoding encoding = CameraEncoding::kRaw;
  std::vector<std::uint8_t> data;  ///< the frame's bytes (raw RGB8 or a JPEG file)
  CameraPose pose;
};

/// The decoded fields of one chunk.
struct ChunkHeader {
  std::int64_t frame_id = 0;  ///< header seq
  double time_s = 0;          ///< header time: the exposure stamp, s
  int chunk_index = 0;
  int chunk_count = 1;
  int width = 0;
  int height = 0;
  CameraEncoding encoding = CameraEncoding::kRaw;
  std::size_t frame_bytes = 0;
  std::size_t offset = 0;       ///< first frame byte in this chunk
  std::size_t chunk_bytes = 0;  ///< frame bytes in this chunk
  CameraPose pose;
};

/// Why a chunk was refused (names: ChunkErrorName).
enum class ChunkError {
  kNone = 0,
  kTooShort,  ///< fewer bytes than the 7-value header plus `length` values
  kBadMagic,
  kBadVersion,
  kBadKind,       ///< not kind 4 (camera)
  kBadType,       ///< not type 1 (state)
  kBadLength,     ///< length below kChunkValues or not a whole number; chunk_bytes != the bytes that follow
  kNotFinite,     ///< a NaN or infinity among the float64 values
  kBadValue,      ///< seq not a whole number in 0..2^53, or a field that is not a whole number
  kBadImage,      ///< width/height outside 1..16384, unknown encoding, raw frame_bytes != w*h*3, frame_bytes 0
  kBadLayout,     ///< chunk_count/index/offset/chunk_bytes break the layout rule
  kBadPose,       ///< pose_valid not 0/1, or a valid pose whose quaternion is not unit length (1e-6)
  kInconsistent,  ///< (assembler) the chunk disagrees with earlier chunks of its frame
  kTooLarge,      ///< (assembler) frame_bytes above the receiver's limit
};
inline constexpr int kChunkErrorCount = 14;
const char* ChunkErrorName(ChunkError error);

/// Bytes of the datagram that carries `chunk_bytes` frame bytes.
inline std::size_t ChunkDatagramBytes(std::size_t chunk_bytes) { return kChunkHeaderBytes + chunk_bytes; }

/// Writes one chunk datagram (header, chunk values, then h.chunk_bytes bytes
/// from `bytes`) into `out`, which must hold ChunkDatagramBytes(h.chunk_bytes).
/// Returns the datagram's size. No allocation; the caller keeps the layout rule.
std::size_t EncodeCameraChunk(const ChunkHeader& h, const std::uint8_t* bytes, unsigned char* out);

/// Checks one datagram and splits it: fills `h` and points `*bytes` at the
/// chunk's frame bytes inside `data`. Returns kNone or why it is refused
/// (*h is then unspecified). Never reads beyond `size`.
ChunkError DecodeCameraChunk(const unsigned char* data, std::size_t size, ChunkHeader* h, const unsigned char** bytes);

/// Number of chunks a frame of `frame_bytes` needs at `chunk_bytes` per chunk.
inline int ChunkCount(std::size_t frame_bytes, std::size_t chunk_bytes) {
  return static_cast<int>((frame_bytes + chunk_bytes - 1) / chunk_bytes);
}

}  // namespace vlab::bridge
