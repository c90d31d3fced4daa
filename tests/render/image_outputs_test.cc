// Image outputs (src/lab/outputs/lab_images.h) on their own: the flat layout of
// `vlab render`, and a frame that cannot be written: an error naming the file,
// nothing half-written, the frames before it kept, nothing rendered after it.
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/core_mujoco.h"
#include "lab/outputs/lab_images.h"
#include "lab/outputs/lab_output.h"
#include "render/video.h"
#include "test_util.h"

namespace vlab::lab {
namespace {

using vlab::testing::Entries;
using vlab::testing::Lines;
using vlab::testing::ReadFile;
using vlab::testing::TempDir;

ImageOutputConfig Overview() {
  ImageOutputConfig c;
  c.camera = "overview";
  c.width = 64;
  c.height = 48;
  c.every_s = 0.1;
  c.depth = true;
  c.profile = render::Profile::kFast;
  c.where = "test.yaml:1";
  return c;
}

TEST(ImageOutputsTest, FlatLayoutWritesTheFramesInTheFolderItself) {
  TempDir dir;
  ModelPtr m = LoadModel(VLAB_SOURCE_DIR "/scenes/pa10.xml");
  DataPtr d = MakeData(m.get());
  mj_forward(m.get(), d.get());
  ImageOptions options;
  options.flat = true;
  options.max_frames = 2;
  options.log_renderer = false;
  std::unique_ptr<ImageOutputs> images = ImageOutputs::Create(m.get(), {Overview()}, "pa10.xml", 0.01, options);
  std::unique_ptr<OutputDir> out = OutputDir::Create(dir / "frames");
  images->Open(*out);
  for (int k = 0; k <= 30; ++k) images->Observe(k * 0.01, d.get());
  images->Finish();
  out->Commit();
  EXPECT_EQ(images->frame_times(0), (std::vector<double>{0.0, 0.1}));  // max_frames: 2
  EXPECT_EQ(Entries(dir / "frames"), (std::set<std::string>{"rgb_000000.png", "rgb_000001.png", "depth_000000.png",
                                                            "depth_000001.png", "frames.csv", ".vlab-output"}));
  EXPECT_EQ(Lines(ReadFile(dir / "frames/frames.csv")), (std::vector<std::string>{"frame,time", "0,0", "1,0.1"}));
}

TEST(ImageOutputsTest, AFrameThatCannotBeWrittenIsReportedByFileAndEndsTheOutputs) {
  TempDir dir;
  ModelPtr m = LoadModel(VLAB_SOURCE_DIR "/scenes/pa10.xml");
  DataPtr d = MakeData(m.get());
  mj_forward(m.get(), d.get());
  ImageOptions options;
  options.log_renderer = false;
  std::unique_ptr<ImageOutputs> images = ImageOutputs::Create(m.get(), {Overview()}, "pa10.xml", 0.01, options);
  std::unique_ptr<OutputDir> out = OutputDir::Create(dir / "run");
  images->Open(*out);
  // frame 1's depth PNG cannot be put in place: a folder holds its name (root or not)
  const std::string camera = out->File("overview");
  std::filesystem::create_directories(camera + "/depth_000001.png/x");
  images->Observe(0.0, d.get());
  EXPECT_FALSE(images->failed());
  try {
    images->Observe(0.1, d.get());
    ADD_FAILURE() << "a frame that cannot be written must be reported";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("depth_000001.png"), std::string::npos) << e.what();
  }
  ASSERT_TRUE(images->failed());
  EXPECT_NE(images->error().find(camera + "/depth_000001.png"), std::string::npos) << images->error();
  // nothing half-written: frame 1's RGB PNG went out first and is removed again
  EXPECT_FALSE(std::filesystem::exists(camera + "/rgb_000001.png"));
  // nothing more is rendered, and frames.csv holds the frame written whole
  EXPECT_NO_THROW(images->Observe(0.2, d.get()));
  EXPECT_FALSE(std::filesystem::exists(camera + "/rgb_000002.png"));
  images->Finish();
  EXPECT_EQ(Lines(ReadFile(camera + "/frames.csv")), (std::vector<std::string>{"frame,time", "0,0"}));
  EXPECT_EQ(images->frame_times(0).size(), 1u);
}

// this program does not link the MP4 writer (vlab_render_video): a video is refused by name,
// and nothing is written
TEST(ImageOutputsTest, AProgramWithoutTheVideoWriterRefusesAVideoAndWritesNothing) {
  TempDir dir;
  const std::string path = dir / "clip.mp4";
  try {
    render::VideoFile::Create(path, 30, 64, 48);
    FAIL() << "a video was opened without a writer";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "video '" + path +
                                         "': this program has no video writer (it is built without "
                                         "vlab_render_video)");
  }
  EXPECT_TRUE(Entries(dir.path()).empty());
}

}  // namespace
}  // namespace vlab::lab
