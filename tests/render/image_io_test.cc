// Image and video files: the PNG and JPEG codec (round trips, bad data
// refused with a message), encodings (RGB order, depth in mm, geom id + 1),
// atomic writes, MP4 frames readable by OpenCV, staged video files.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>
#include <opencv2/videoio.hpp>

#include "core/core_errors.h"
#include "render/image_codec.h"
#include "render/image_io.h"
#include "render/video.h"
#include "test_util.h"

namespace vlab::render {
namespace {

using vlab::testing::Entries;
using vlab::testing::TempDir;

RgbImage Gradient(int w, int h, int shift = 0) {
  RgbImage img;
  img.width = w;
  img.height = h;
  img.pixels.resize(static_cast<std::size_t>(w) * h * 3);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      std::uint8_t* p = img.pixels.data() + 3 * (static_cast<std::size_t>(y) * w + x);
      p[0] = static_cast<std::uint8_t>((x * 4 + shift) & 0xFF);  // red varies along x
      p[1] = static_cast<std::uint8_t>(y * 2);                   // green along y
      p[2] = 200;
    }
  }
  return img;
}

TEST(ImageIo, DepthInMillimetres) {
  EXPECT_EQ(DepthToMillimetres(1.2345f), 1235);  // 1234.5 mm, rounded
  EXPECT_EQ(DepthToMillimetres(0.0004f), 0);
  EXPECT_EQ(DepthToMillimetres(2.0f), 2000);
  EXPECT_EQ(DepthToMillimetres(65.5349f), 65535);
  EXPECT_EQ(DepthToMillimetres(100.0f), 65535);
  EXPECT_EQ(DepthToMillimetres(std::numeric_limits<float>::infinity()), 0);
  EXPECT_EQ(DepthToMillimetres(std::nanf("")), 0);
  EXPECT_EQ(DepthToMillimetres(-1.0f), 0);
}

TEST(ImageIo, PngFilesReadBackWithTheirValues) {
  TempDir dir;
  const RgbImage rgb = Gradient(64, 48);
  WritePng(dir / "rgb.png", rgb);
  const Image back = ReadImageFile(dir / "rgb.png", DecodeMode::kUnchanged);
  ASSERT_EQ(back.channels, 3);
  ASSERT_EQ(back.depth, 8);
  ASSERT_EQ(back.width, 64);
  ASSERT_EQ(back.height, 48);
  EXPECT_EQ(back.bytes, rgb.pixels);  // R, G, B; rows top-down

  DepthImage depth;
  depth.width = 3;
  depth.height = 2;
  depth.metres = {0.5f, 1.0f, std::numeric_limits<float>::infinity(), 2.25f, 0.0011f, 70.0f};
  WriteDepthPng(dir / "depth.png", depth);
  const Image mm = ReadImageFile(dir / "depth.png", DecodeMode::kUnchanged);
  ASSERT_EQ(mm.channels, 1);
  ASSERT_EQ(mm.depth, 16);
  EXPECT_EQ(std::vector<std::uint16_t>(mm.samples16(), mm.samples16() + 6),
            (std::vector<std::uint16_t>{500, 1000, 0, 2250, 1, 65535}));

  SegmentationImage seg;
  seg.width = 2;
  seg.height = 2;
  seg.geom = {-1, 0, 7, 300};
  WriteSegmentationPng(dir / "seg.png", seg);
  const Image ids = ReadImageFile(dir / "seg.png", DecodeMode::kUnchanged);
  ASSERT_EQ(ids.channels, 1);
  ASSERT_EQ(ids.depth, 16);
  EXPECT_EQ(std::vector<std::uint16_t>(ids.samples16(), ids.samples16() + 4),
            (std::vector<std::uint16_t>{0, 1, 8, 301}));
  // nothing but the three files: no temporary names left behind
  EXPECT_EQ(Entries(dir.path()), (std::set<std::string>{"rgb.png", "depth.png", "seg.png"}));
}

TEST(ImageIo, WriteIntoAMissingFolderFailsCleanly) {
  TempDir dir;
  EXPECT_THROW(WritePng(dir / "no/such/folder/rgb.png", Gradient(8, 8)), std::runtime_error);
  EXPECT_TRUE(Entries(dir.path()).empty());
}

TEST(ImageIo, JpegDecodesToTheSameSize) {
  std::vector<std::uint8_t> jpeg;
  EncodeJpeg(Gradient(64, 48), 90, &jpeg);
  ASSERT_GT(jpeg.size(), 100u);
  const Image back = DecodeImage(jpeg, DecodeMode::kColor);
  EXPECT_EQ(back.width, 64);
  EXPECT_EQ(back.height, 48);
  EXPECT_NEAR(back.bytes[3 * (10 * 64 + 20)], 80, 8);  // R
}

// ---- the codec on its own

// a message of the exception `f` throws ("" when none)
template <class F>
std::string ErrorOf(F f) {
  try {
    f();
  } catch (const ImageCodecError& e) {
    return e.what();
  }
  return "";
}

TEST(ImageCodec, PngRoundTripsEveryLayout) {
  const RgbImage rgb = Gradient(37, 21);
  std::vector<std::uint8_t> bytes(rgb.pixels.begin(), rgb.pixels.end());
  std::vector<std::uint8_t> png;
  for (int compression : {-1, 0, 1, 9}) {
    EncodePng(View(rgb), compression, &png);
    EXPECT_EQ(DecodeImage(png, DecodeMode::kUnchanged).bytes, bytes) << "compression " << compression;
  }
  // grey 8 and 16 bits, RGBA: pixels back as written
  std::vector<std::uint16_t> grey16(37 * 21);
  for (std::size_t i = 0; i < grey16.size(); ++i) grey16[i] = static_cast<std::uint16_t>(i * 157);
  EncodePng({37, 21, 1, 16, grey16.data(), 0}, -1, &png);
  const Image g16 = DecodeImage(png, DecodeMode::kUnchanged);
  ASSERT_EQ(g16.depth, 16);
  EXPECT_EQ(std::vector<std::uint16_t>(g16.samples16(), g16.samples16() + grey16.size()), grey16);
  // as 8 bits: the high byte
  EXPECT_EQ(DecodeImage(png, DecodeMode::kGray).bytes[1], 157 >> 8);
  std::vector<std::uint8_t> rgba(4 * 5 * 3);
  for (std::size_t i = 0; i < rgba.size(); ++i) rgba[i] = static_cast<std::uint8_t>(i * 5);
  EncodePng({5, 3, 4, 8, rgba.data(), 0}, 6, &png);
  const Image back = DecodeImage(png, DecodeMode::kUnchanged);
  EXPECT_EQ(back.channels, 4);
  EXPECT_EQ(back.bytes, rgba);
  // a strided view: only the pixels of each row
  EncodePng({2, 2, 1, 8, rgba.data(), 20}, -1, &png);
  EXPECT_EQ(DecodeImage(png, DecodeMode::kGray).bytes, (std::vector<std::uint8_t>{0, 5, 100, 105}));
}

TEST(ImageCodec, ColourAndGreyConversions) {
  std::vector<std::uint8_t> png;
  const std::uint8_t grey[4] = {0, 80, 160, 255};
  EncodePng({2, 2, 1, 8, grey, 0}, -1, &png);
  EXPECT_EQ(DecodeImage(png, DecodeMode::kColor).bytes,
            (std::vector<std::uint8_t>{0, 0, 0, 80, 80, 80, 160, 160, 160, 255, 255, 255}));
  const std::uint8_t red[3] = {255, 0, 0};
  EncodePng({1, 1, 3, 8, red, 0}, -1, &png);
  EXPECT_EQ(DecodeImage(png, DecodeMode::kGray).bytes[0], 76);  // 0.299 * 255
}

TEST(ImageCodec, JpegRoundTripIsClose) {
  const RgbImage rgb = Gradient(64, 48);
  std::vector<std::uint8_t> jpeg;
  EncodeJpeg(View(rgb), 95, &jpeg);
  ASSERT_TRUE(LooksLikeJpeg(jpeg.data(), jpeg.size()));
  const Image back = DecodeImage(jpeg, DecodeMode::kUnchanged);
  ASSERT_EQ(back.channels, 3);
  ASSERT_EQ(back.bytes.size(), rgb.pixels.size());
  for (std::size_t i = 0; i < rgb.pixels.size(); ++i) ASSERT_NEAR(back.bytes[i], rgb.pixels[i], 12) << i;
  EXPECT_EQ(DecodeImage(jpeg, DecodeMode::kGray).channels, 1);
  // lower quality, fewer bytes
  std::vector<std::uint8_t> small;
  EncodeJpeg(View(rgb), 20, &small);
  EXPECT_LT(small.size(), jpeg.size());
}

TEST(ImageCodec, TruncatedDataIsRefusedWithAMessage) {
  const RgbImage rgb = Gradient(64, 48);
  std::vector<std::uint8_t> png, jpeg;
  EncodePng(View(rgb), -1, &png);
  EncodeJpeg(View(rgb), 90, &jpeg);
  for (std::size_t keep : {png.size() - 20, png.size() / 2, std::size_t{40}, std::size_t{12}}) {
    const std::vector<std::uint8_t> cut(png.begin(), png.begin() + keep);
    EXPECT_NE(ErrorOf([&] { DecodeImage(cut, DecodeMode::kColor); }).find("PNG"), std::string::npos) << keep;
  }
  for (std::size_t keep : {jpeg.size() - 20, jpeg.size() / 2, std::size_t{100}, std::size_t{4}}) {
    const std::vector<std::uint8_t> cut(jpeg.begin(), jpeg.begin() + keep);
    EXPECT_NE(ErrorOf([&] { DecodeImage(cut, DecodeMode::kColor); }).find("JPEG"), std::string::npos) << keep;
  }
  // a corrupt PNG body (a checksum no longer matches)
  std::vector<std::uint8_t> bad = png;
  bad[bad.size() / 2] ^= 0x5a;
  EXPECT_NE(ErrorOf([&] { DecodeImage(bad, DecodeMode::kColor); }), "");
}

TEST(ImageCodec, NonImagesAndBadViewsAreRefused) {
  const std::string text = "this is not an image at all";
  const std::vector<std::uint8_t> bytes(text.begin(), text.end());
  EXPECT_EQ(ErrorOf([&] { DecodeImage(bytes, DecodeMode::kColor); }), "neither PNG nor JPEG data (27 bytes)");
  EXPECT_EQ(ErrorOf([&] { DecodeImage({}, DecodeMode::kColor); }), "no image data (0 bytes)");
  TempDir dir;
  vlab::testing::WriteFile(dir / "notes.png", text);
  EXPECT_NE(ErrorOf([&] { ReadImageFile(dir / "notes.png", DecodeMode::kColor); }).find("notes.png"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { ReadImageFile(dir / "missing.png", DecodeMode::kColor); }).find("missing.png"),
            std::string::npos);
  std::vector<std::uint8_t> out;
  const std::uint8_t px[4] = {};
  EXPECT_NE(ErrorOf([&] { EncodePng({0, 1, 3, 8, px, 0}, -1, &out); }), "");
  EXPECT_NE(ErrorOf([&] { EncodePng({1, 1, 2, 8, px, 0}, -1, &out); }), "");
  EXPECT_NE(ErrorOf([&] { EncodeJpeg({1, 1, 1, 16, px, 0}, 90, &out); }), "");
}

TEST(Video, Mp4HasEveryFrame) {
  TempDir dir;
  const std::string path = dir / "clip.mp4";
  auto video = VideoFile::Create(path, 10.0, 160, 120);
  for (int i = 0; i < 12; ++i) video->Add(Gradient(160, 120, 20 * i));
  EXPECT_EQ(video->frames(), 12);
  EXPECT_FALSE(std::filesystem::exists(path)) << "visible before Finish()";
  video->Finish();
  EXPECT_EQ(Entries(dir.path()), (std::set<std::string>{"clip.mp4"}));

  cv::VideoCapture capture(path);
  ASSERT_TRUE(capture.isOpened());
  EXPECT_NEAR(capture.get(cv::CAP_PROP_FPS), 10.0, 1e-6);
  int frames = 0;
  cv::Mat frame;
  while (capture.read(frame)) {
    EXPECT_EQ(frame.cols, 160);
    EXPECT_EQ(frame.rows, 120);
    ++frames;
  }
  EXPECT_EQ(frames, 12);
}

TEST(Video, UnfinishedVideoLeavesNothing) {
  TempDir dir;
  {
    auto video = VideoFile::Create(dir / "clip.mp4", 30.0, 64, 48);
    video->Add(Gradient(64, 48));
    EXPECT_THROW(video->Add(Gradient(32, 24)), std::invalid_argument);
  }
  EXPECT_TRUE(Entries(dir.path()).empty());
}

TEST(Video, BadNamesAreInputErrors) {
  TempDir dir;
  EXPECT_THROW(VideoFile::Create(dir / "clip.avi", 30.0, 64, 48), vlab::InputError);
  EXPECT_THROW(VideoFile::Create(dir / "missing/clip.mp4", 30.0, 64, 48), vlab::InputError);
  EXPECT_TRUE(Entries(dir.path()).empty());
}

}  // namespace
}  // namespace vlab::render
