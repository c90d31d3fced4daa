// Tests bridge/bridge_camera.cc: a chunk round-trips, every malformed chunk is
// refused with its reason, and the worked example of docs/protocol_camera.md
// is exactly what EncodeCameraChunk writes.
#include "bridge/bridge_camera.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "bridge/bridge_protocol.h"

namespace vlab::bridge::camera_codec_test {
namespace {

using Bytes = std::vector<unsigned char>;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

std::string Hex(const Bytes& bytes) {
  std::string s;
  char two[3];
  for (unsigned char b : bytes) {
    std::snprintf(two, sizeof(two), "%02x", b);
    s += two;
  }
  return s;
}

// the last chunk of the worked example: a 4x2 raw frame (bytes 0..23) in chunks of 16 bytes
ChunkHeader Example() {
  ChunkHeader h;
  h.frame_id = 7;
  h.time_s = 0.25;
  h.chunk_index = 1;
  h.chunk_count = 2;
  h.width = 4;
  h.height = 2;
  h.encoding = CameraEncoding::kRaw;
  h.frame_bytes = 24;
  h.offset = 16;
  h.chunk_bytes = 8;
  h.pose.valid = true;
  h.pose.p_WC = Eigen::Vector3d(0.5, 0, 1.2);
  h.pose.q_WC = Eigen::Quaterniond(0, 1, 0, 0);  // looking straight down
  return h;
}

Bytes Encode(const ChunkHeader& h) {
  std::vector<std::uint8_t> frame(h.frame_bytes);
  for (std::size_t i = 0; i < frame.size(); ++i) frame[i] = static_cast<std::uint8_t>(i);
  Bytes out(ChunkDatagramBytes(h.chunk_bytes));
  EXPECT_EQ(EncodeCameraChunk(h, frame.data() + h.offset, out.data()), out.size());
  return out;
}

ChunkError Decode(const Bytes& b, ChunkHeader* h = nullptr) {
  ChunkHeader scratch;
  const unsigned char* bytes = nullptr;
  return DecodeCameraChunk(b.data(), b.size(), h ? h : &scratch, &bytes);
}

// the example with float64 value `index` (0 = magic; 7 = chunk_index; ...) replaced
Bytes With(int index, double value, ChunkHeader h = Example()) {
  Bytes b = Encode(h);
  PutDouble(value, b.data() + 8 * index);
  return b;
}

TEST(CameraCodecTest, WorkedExampleOfTheDocsMatchesTheEncoder) {
  const std::string documented =
      "000080501093d54100000000000000400000000000001040000000000000f03f"
      "0000000000001c40000000000000d03f0000000000003040000000000000f03f"
      "0000000000000040000000000000104000000000000000400000000000000000"
      "000000000000384000000000000030400000000000002040000000000000f03f"
      "000000000000e03f0000000000000000333333333333f33f0000000000000000"
      "000000000000f03f000000000000000000000000000000001011121314151617";
  EXPECT_EQ(Hex(Encode(Example())), documented);
}

TEST(CameraCodecTest, RoundTrip) {
  const ChunkHeader in = Example();
  const Bytes b = Encode(in);
  ChunkHeader out;
  const unsigned char* bytes = nullptr;
  ASSERT_EQ(DecodeCameraChunk(b.data(), b.size(), &out, &bytes), ChunkError::kNone);
  EXPECT_EQ(out.frame_id, 7);
  EXPECT_EQ(out.time_s, 0.25);
  EXPECT_EQ(out.chunk_index, 1);
  EXPECT_EQ(out.chunk_count, 2);
  EXPECT_EQ(out.width, 4);
  EXPECT_EQ(out.height, 2);
  EXPECT_EQ(out.encoding, CameraEncoding::kRaw);
  EXPECT_EQ(out.frame_bytes, 24u);
  EXPECT_EQ(out.offset, 16u);
  EXPECT_EQ(out.chunk_bytes, 8u);
  EXPECT_TRUE(out.pose.valid);
  EXPECT_EQ(out.pose.p_WC, in.pose.p_WC);
  EXPECT_EQ(out.pose.q_WC.coeffs(), in.pose.q_WC.coeffs());
  ASSERT_EQ(bytes, b.data() + kChunkHeaderBytes);
  for (int i = 0; i < 8; ++i) EXPECT_EQ(bytes[i], 16 + i);
}

TEST(CameraCodecTest, UnknownPoseTravelsAsIdentity) {
  ChunkHeader in = Example();
  in.pose.valid = false;
  in.pose.p_WC = Eigen::Vector3d(9, 9, 9);
  ChunkHeader out;
  ASSERT_EQ(Decode(Encode(in), &out), ChunkError::kNone);
  EXPECT_FALSE(out.pose.valid);
  EXPECT_EQ(out.pose.p_WC, Eigen::Vector3d::Zero());
  EXPECT_EQ(out.pose.q_WC.w(), 1.0);
}

TEST(CameraCodecTest, JpegAndSingleChunkFrames) {
  ChunkHeader h = Example();
  h.encoding = CameraEncoding::kJpeg;  // any byte count
  h.frame_bytes = 5;
  h.chunk_count = 1;
  h.chunk_index = 0;
  h.offset = 0;
  h.chunk_bytes = 5;
  ChunkHeader out;
  ASSERT_EQ(Decode(Encode(h), &out), ChunkError::kNone);
  EXPECT_EQ(out.encoding, CameraEncoding::kJpeg);
}

TEST(CameraCodecTest, ExtraChunkValuesAreReservedAndIgnored) {
  // length 18: two more values before the bytes (a later minor revision may add fields)
  Bytes b = Encode(Example());
  Bytes longer(b.begin(), b.begin() + kChunkHeaderBytes);
  longer.resize(longer.size() + 16, 0);
  longer.insert(longer.end(), b.begin() + kChunkHeaderBytes, b.end());
  PutDouble(18, longer.data() + 48);
  ChunkHeader out;
  const unsigned char* bytes = nullptr;
  ASSERT_EQ(DecodeCameraChunk(longer.data(), longer.size(), &out, &bytes), ChunkError::kNone);
  EXPECT_EQ(bytes[0], 16);
}

TEST(CameraCodecTest, RefusesFraming) {
  Bytes b = Encode(Example());
  EXPECT_EQ(Decode(Bytes(b.begin(), b.begin() + 55)), ChunkError::kTooShort);
  EXPECT_EQ(Decode(Bytes(b.begin(), b.begin() + 100)), ChunkError::kTooShort);  // header says 16 values
  EXPECT_EQ(Decode(With(0, 1447838019)), ChunkError::kBadMagic);
  EXPECT_EQ(Decode(With(1, 1)), ChunkError::kBadVersion);
  EXPECT_EQ(Decode(With(2, 1)), ChunkError::kBadKind);
  EXPECT_EQ(Decode(With(3, 2)), ChunkError::kBadType);
  EXPECT_EQ(Decode(With(3, 3)), ChunkError::kBadType);
  EXPECT_EQ(Decode(With(4, -1)), ChunkError::kBadValue);
  EXPECT_EQ(Decode(With(4, 7.5)), ChunkError::kBadValue);
  EXPECT_EQ(Decode(With(6, 15)), ChunkError::kBadLength);
  EXPECT_EQ(Decode(With(6, 16.5)), ChunkError::kBadLength);
  EXPECT_EQ(Decode(With(6, 1018)), ChunkError::kBadLength);
  Bytes extra = b;
  extra.push_back(0);  // one byte more than chunk_bytes says
  EXPECT_EQ(Decode(extra), ChunkError::kBadLength);
  EXPECT_EQ(Decode(Bytes(b.begin(), b.end() - 1)), ChunkError::kBadLength);
}

TEST(CameraCodecTest, RefusesNonFiniteValues) {
  EXPECT_EQ(Decode(With(5, kNaN)), ChunkError::kNotFinite);  // time
  EXPECT_EQ(Decode(With(5, kInf)), ChunkError::kNotFinite);
  EXPECT_EQ(Decode(With(16, kNaN)), ChunkError::kNotFinite);   // px
  EXPECT_EQ(Decode(With(22, -kInf)), ChunkError::kNotFinite);  // qz
}

TEST(CameraCodecTest, RefusesBadImages) {
  EXPECT_EQ(Decode(With(9, 0)), ChunkError::kBadImage);       // width
  EXPECT_EQ(Decode(With(10, 16385)), ChunkError::kBadImage);  // height
  EXPECT_EQ(Decode(With(9, 4.5)), ChunkError::kBadImage);
  EXPECT_EQ(Decode(With(11, 2)), ChunkError::kBadImage);  // encoding
  EXPECT_EQ(Decode(With(11, -1)), ChunkError::kBadImage);
  EXPECT_EQ(Decode(With(12, 0)), ChunkError::kBadImage);  // frame_bytes
  ChunkHeader h = Example();                              // raw frame_bytes must be w*h*3
  h.frame_bytes = 25;
  h.chunk_bytes = 9;
  EXPECT_EQ(Decode(Encode(h)), ChunkError::kBadImage);
}

TEST(CameraCodecTest, RefusesBadLayouts) {
  EXPECT_EQ(Decode(With(7, 2)), ChunkError::kBadLayout);  // index >= count
  EXPECT_EQ(Decode(With(7, -1)), ChunkError::kBadLayout);
  EXPECT_EQ(Decode(With(8, 0)), ChunkError::kBadLayout);  // count 0
  EXPECT_EQ(Decode(With(8, 1.5)), ChunkError::kBadLayout);
  EXPECT_EQ(Decode(With(13, 15)), ChunkError::kBadLayout);  // last chunk does not end at frame_bytes
  EXPECT_EQ(Decode(With(13, 24)), ChunkError::kBadLayout);  // offset beyond the frame
  EXPECT_EQ(Decode(With(14, 0)), ChunkError::kBadLayout);   // empty chunk
  ChunkHeader h = Example();                                // a full chunk at the wrong offset
  h.chunk_index = 0;
  h.offset = 8;
  h.chunk_bytes = 16;
  EXPECT_EQ(Decode(Encode(h)), ChunkError::kBadLayout);
  h.offset = 0;  // 16-byte chunks make 2 chunks of 24 bytes, not 3
  h.chunk_count = 3;
  EXPECT_EQ(Decode(Encode(h)), ChunkError::kBadLayout);
  h = Example();  // last chunk larger than the others: P = 16 / 1 < 20
  h.frame_bytes = 24;
  h.offset = 4;
  h.chunk_bytes = 20;
  EXPECT_EQ(Decode(Encode(h)), ChunkError::kBadLayout);
  h = Example();  // a single chunk must start at 0
  h.chunk_count = 1;
  h.chunk_index = 0;
  EXPECT_EQ(Decode(Encode(h)), ChunkError::kBadLayout);
  h.offset = 0;  // ...and then it is fine once it carries the whole frame
  h.chunk_bytes = 24;
  EXPECT_EQ(Decode(Encode(h)), ChunkError::kNone);
}

TEST(CameraCodecTest, RefusesBadPoses) {
  EXPECT_EQ(Decode(With(15, 2)), ChunkError::kBadPose);  // pose_valid
  EXPECT_EQ(Decode(With(15, 0.5)), ChunkError::kBadPose);
  EXPECT_EQ(Decode(With(19, 0.9)), ChunkError::kBadPose);  // |q| != 1
  ChunkHeader h = Example();                               // an invalid pose carries anything finite
  h.pose.valid = false;
  Bytes b = Encode(h);
  PutDouble(5, b.data() + 8 * 19);
  EXPECT_EQ(Decode(b), ChunkError::kNone);
}

TEST(CameraCodecTest, EveryReasonHasAName) {
  for (int e = 0; e < kChunkErrorCount; ++e) {
    EXPECT_STRNE(ChunkErrorName(static_cast<ChunkError>(e)), "unknown") << e;
  }
  EXPECT_STREQ(ChunkErrorName(ChunkError::kInconsistent), "inconsistent with its frame");
}

TEST(CameraCodecTest, ChunkSizesFitAnIpv4Datagram) {
  EXPECT_EQ(kChunkHeaderBytes, 184u);
  EXPECT_EQ(ChunkDatagramBytes(kDefaultChunkBytes), 60184u);
  EXPECT_EQ(ChunkDatagramBytes(kMaxChunkBytes), 65507u);
  EXPECT_EQ(ChunkCount(640 * 480 * 3, kDefaultChunkBytes), 16);
  EXPECT_EQ(ChunkCount(60000, kDefaultChunkBytes), 1);
  EXPECT_EQ(ChunkCount(60001, kDefaultChunkBytes), 2);
}

}  // namespace
}  // namespace vlab::bridge::camera_codec_test
