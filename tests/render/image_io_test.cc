// Image and video files: encodings (RGB order, depth in mm, geom id + 1),
// atomic writes, MP4 frames readable by OpenCV, staged video files.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "core/core_errors.h"
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
  const cv::Mat bgr = cv::imread(dir / "rgb.png", cv::IMREAD_UNCHANGED);
  ASSERT_EQ(bgr.type(), CV_8UC3);
  ASSERT_EQ(bgr.cols, 64);
  ASSERT_EQ(bgr.rows, 48);
  EXPECT_EQ(bgr.at<cv::Vec3b>(10, 20)[2], 80);  // R (OpenCV stores B, G, R)
  EXPECT_EQ(bgr.at<cv::Vec3b>(10, 20)[1], 20);  // G: row 10, rows top-down
  EXPECT_EQ(bgr.at<cv::Vec3b>(10, 20)[0], 200);

  DepthImage depth;
  depth.width = 3;
  depth.height = 2;
  depth.metres = {0.5f, 1.0f, std::numeric_limits<float>::infinity(), 2.25f, 0.0011f, 70.0f};
  WriteDepthPng(dir / "depth.png", depth);
  const cv::Mat mm = cv::imread(dir / "depth.png", cv::IMREAD_UNCHANGED);
  ASSERT_EQ(mm.type(), CV_16UC1);
  EXPECT_EQ(mm.at<std::uint16_t>(0, 0), 500);
  EXPECT_EQ(mm.at<std::uint16_t>(0, 1), 1000);
  EXPECT_EQ(mm.at<std::uint16_t>(0, 2), 0);
  EXPECT_EQ(mm.at<std::uint16_t>(1, 0), 2250);
  EXPECT_EQ(mm.at<std::uint16_t>(1, 1), 1);
  EXPECT_EQ(mm.at<std::uint16_t>(1, 2), 65535);

  SegmentationImage seg;
  seg.width = 2;
  seg.height = 2;
  seg.geom = {-1, 0, 7, 300};
  WriteSegmentationPng(dir / "seg.png", seg);
  const cv::Mat ids = cv::imread(dir / "seg.png", cv::IMREAD_UNCHANGED);
  ASSERT_EQ(ids.type(), CV_16UC1);
  EXPECT_EQ(ids.at<std::uint16_t>(0, 0), 0);
  EXPECT_EQ(ids.at<std::uint16_t>(0, 1), 1);
  EXPECT_EQ(ids.at<std::uint16_t>(1, 0), 8);
  EXPECT_EQ(ids.at<std::uint16_t>(1, 1), 301);
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
  const cv::Mat back = cv::imdecode(jpeg, cv::IMREAD_COLOR);
  EXPECT_EQ(back.cols, 64);
  EXPECT_EQ(back.rows, 48);
  EXPECT_NEAR(back.at<cv::Vec3b>(10, 20)[2], 80, 8);
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
