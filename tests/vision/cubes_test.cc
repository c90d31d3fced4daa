// The lettered cubes (vision_cubes.h) and `vlab cubes`: marker frames on the
// faces, the generated files, their equality with the committed mjcf/cubes and
// scenes/pa10_cubes.xml, and bad options refused with exit code 2.
#include <algorithm>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "core/core_errors.h"
#include "render/image_codec.h"
#include "test_util.h"
#include "vision/vision_cubes.h"

namespace vlab::vision::cubes_test {
namespace {

namespace fs = std::filesystem;
using testing::ReadFile;
using testing::RunVlab;
using testing::TempDir;

std::string ErrorOf(const CubeSetConfig& c) {
  try {
    CheckCubeSet(c);
  } catch (const vlab::InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Cubes, MarkerFramesLieOnTheirFacesFacingOut) {
  const CubeSetConfig cubes;
  const FaceGeometry g = FaceGeometryOf(cubes.layout, 4);
  const Eigen::Vector3d normals[kCubeFaces] = {Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitX(),
                                               Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitY(),
                                               Eigen::Vector3d::UnitZ(), -Eigen::Vector3d::UnitZ()};
  for (int f = 0; f < kCubeFaces; ++f) {
    const Eigen::Isometry3d X = CubeMarkerFrame(cubes, f);
    const Eigen::Matrix3d R = X.linear();
    EXPECT_TRUE((R.transpose() * R).isIdentity(1e-12)) << f;
    EXPECT_NEAR(R.determinant(), 1.0, 1e-12) << f;
    EXPECT_TRUE(R.col(2).isApprox(normals[f])) << CubeFaceName(f);
    EXPECT_NEAR(X.translation().dot(normals[f]), cubes.size_m / 2, 1e-12) << f;  // on the face plane
    // the marker's offset within the face: g.offset_up along the image's up axis (y)
    EXPECT_NEAR(X.translation().dot(R.col(1)), g.offset_up * cubes.size_m, 1e-12) << f;
    EXPECT_NEAR(X.translation().dot(R.col(0)), g.offset_right * cubes.size_m, 1e-12) << f;
  }
  EXPECT_DOUBLE_EQ(CubeMarkerSide(cubes), 0.025);
  EXPECT_EQ(CubeMarkerId(cubes, 5, 5), 35);
  EXPECT_EQ(CubeName(cubes, 2), "cube_C");
}

TEST(Cubes, FilesAreDeterministic) {
  const CubeSetConfig cubes;
  const std::vector<GeneratedFile> a = CubeSetFiles(cubes);
  const std::vector<GeneratedFile> b = CubeSetFiles(cubes);
  ASSERT_EQ(a.size(), 6u * 7 + 2);  // 6 faces + 1 body per cube, assets, README
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].name, b[i].name);
    EXPECT_EQ(a[i].bytes, b[i].bytes) << a[i].name;
  }
  EXPECT_EQ(a.front().name, "cube_A_right.png");
  EXPECT_EQ(a.back().name, "README.md");
}

TEST(Cubes, BadSetsNamed) {
  CubeSetConfig c;
  c.letters = "ABA";
  EXPECT_NE(ErrorOf(c).find("'A' appears twice"), std::string::npos);
  c.letters = "AB?";
  EXPECT_NE(ErrorOf(c).find("'?' is not A-Z or 0-9"), std::string::npos);
  c.letters = "ABCDEFGHI";  // 54 ids, 4X4_50 has 50
  EXPECT_NE(ErrorOf(c).find("need marker ids 0..53, dictionary 4X4_50 has 0..49"), std::string::npos);
  c.letters = "AB";
  c.size_m = 0.001;
  EXPECT_NE(ErrorOf(c).find("--size 0.001 m outside 0.01..0.5"), std::string::npos);
  c.size_m = 0.05;
  c.first_id = -1;
  EXPECT_NE(ErrorOf(c).find("need marker ids -1"), std::string::npos);
}

// regenerates the committed files with the command their README names
TEST(CubesCommand, RegeneratesTheCommittedFilesByteForByte) {
  TempDir tmp;
  fs::create_directories(tmp / "mjcf");
  fs::copy(VLAB_SOURCE_DIR "/mjcf/pa10", tmp / "mjcf/pa10", fs::copy_options::recursive);
  const auto r = RunVlab("cubes --out '" + (tmp / "mjcf/cubes") +
                         "' --letters ABCDEF --size 0.05 --dictionary 4X4_50 "
                         "--first-id 0 --scene '" +
                         (tmp / "scenes/pa10_cubes.xml") + "' --count 6 --seed 1 --pa10 '" + (tmp / "mjcf/pa10") + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  int compared = 0;
  for (const auto& entry : fs::directory_iterator(VLAB_SOURCE_DIR "/mjcf/cubes")) {
    if (entry.is_directory()) continue;  // blocks/: the alphabet blocks, below
    const std::string name = entry.path().filename().string();
    ASSERT_TRUE(fs::exists(tmp / ("mjcf/cubes/" + name))) << name << " is committed but not generated";
    EXPECT_TRUE(ReadFile(entry.path().string()) == ReadFile(tmp / ("mjcf/cubes/" + name))) << name << " differs";
    ++compared;
  }
  EXPECT_EQ(compared, static_cast<int>(testing::Entries(tmp / "mjcf/cubes").size()));  // nothing extra generated
  EXPECT_EQ(compared, 44);
  EXPECT_TRUE(ReadFile(VLAB_SOURCE_DIR "/scenes/pa10_cubes.xml") == ReadFile(tmp / "scenes/pa10_cubes.xml"))
      << "scenes/pa10_cubes.xml differs";
}

// the alphabet blocks of mjcf/cubes/blocks: one letter per face, A-F each on a different block
constexpr const char* kBlocks = "AGMSY4,BHNTZ5,CIOU06,DJPV17,EKQW28,FLRX39";

TEST(CubesCommand, RegeneratesTheCommittedBlocksByteForByte) {
  TempDir tmp;
  const auto r = RunVlab("cubes --out '" + (tmp / "blocks") + "' --faces " + kBlocks +
                         " --size 0.05 --dictionary 4X4_50 --first-id 0");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  int compared = 0;
  for (const auto& entry : fs::directory_iterator(VLAB_SOURCE_DIR "/mjcf/cubes/blocks")) {
    const std::string name = entry.path().filename().string();
    ASSERT_TRUE(fs::exists(tmp / ("blocks/" + name))) << name << " is committed but not generated";
    EXPECT_TRUE(ReadFile(entry.path().string()) == ReadFile(tmp / ("blocks/" + name))) << name << " differs";
    ++compared;
  }
  EXPECT_EQ(compared, static_cast<int>(testing::Entries(tmp / "blocks").size()));
  EXPECT_EQ(compared, 44);
}

TEST(Cubes, AlphabetBlocksCarryOneLetterPerFace) {
  CubeSetConfig c;
  c.faces = {"AGMSY4", "BHNTZ5"};
  EXPECT_EQ(CubeCount(c), 2);
  EXPECT_EQ(CubeName(c, 1), "cube_BHNTZ5");
  EXPECT_EQ(CubeFaceLetter(c, 0, kFaceMinusY), 'S');
  EXPECT_EQ(CubeSetOption(c), "--faces AGMSY4,BHNTZ5");
  const std::vector<GeneratedFile> files = CubeSetFiles(c);
  ASSERT_EQ(files.size(), 2u * 7 + 2);
  // each face image is the face drawn with its own letter and marker 6 i + f (in the block's
  // colour, read off the image's corner, and the generator's ink), and not with another letter
  for (int f = 0; f < kCubeFaces; ++f) {
    const std::string name = std::string("cube_BHNTZ5_") + CubeFaceName(f) + ".png";
    const auto file = std::find_if(files.begin(), files.end(), [&](const GeneratedFile& g) { return g.name == name; });
    ASSERT_NE(file, files.end()) << name;
    const std::vector<std::uint8_t> png(file->bytes.begin(), file->bytes.end());
    render::Image rgb = render::DecodeImage(png, render::DecodeMode::kColor);
    cv::Mat image;  // BGR, as OpenCV draws
    cv::cvtColor(cv::Mat(rgb.height, rgb.width, CV_8UC3, rgb.bytes.data()), image, cv::COLOR_RGB2BGR);
    ASSERT_FALSE(image.empty()) << name;
    FaceSpec spec;
    spec.id = 6 + f;
    const cv::Vec3b corner = image.at<cv::Vec3b>(1, 1);
    spec.background = cv::Scalar(corner[0], corner[1], corner[2]);
    spec.ink = cv::Scalar(100, 36, 24);  // vision_cubes.cc: dark blue ink
    spec.letter = "BHNTZ5"[f];
    EXPECT_EQ(cv::norm(image, DrawFace(spec, c.layout), cv::NORM_INF), 0) << name;
    spec.letter = 'X';
    EXPECT_GT(cv::norm(image, DrawFace(spec, c.layout), cv::NORM_INF), 0) << name;
  }
  // the assets name each block's face letters for the word device
  const auto assets =
      std::find_if(files.begin(), files.end(), [](const GeneratedFile& g) { return g.name == "cubes_assets.xml"; });
  ASSERT_NE(assets, files.end());
  EXPECT_NE(assets->bytes.find("<text name=\"cube_AGMSY4.faces\" data=\"AGMSY4\"/>"), std::string::npos);
  EXPECT_NE(assets->bytes.find("<text name=\"cube_BHNTZ5.faces\" data=\"BHNTZ5\"/>"), std::string::npos);
  // the default set has no such text: its assets stay as they were
  const std::vector<GeneratedFile> plain = CubeSetFiles(CubeSetConfig{});
  EXPECT_EQ(plain[plain.size() - 2].bytes.find("<custom>"), std::string::npos);
}

TEST(Cubes, BadBlocksNamed) {
  CubeSetConfig c;
  c.faces = {"AGMSY"};
  EXPECT_NE(ErrorOf(c).find("--faces: 'AGMSY' is not six letters"), std::string::npos);
  c.faces = {"AGMSY?"};
  EXPECT_NE(ErrorOf(c).find("--faces: 'AGMSY?': '?' is not A-Z or 0-9"), std::string::npos);
  c.faces = {"AGMSY4", "AGMSY4"};
  EXPECT_NE(ErrorOf(c).find("--faces: 'AGMSY4' appears twice"), std::string::npos);
  c.faces = std::vector<std::string>(9, "");
  for (int i = 0; i < 9; ++i) c.faces[static_cast<std::size_t>(i)] = std::string(5, 'A') + static_cast<char>('1' + i);
  EXPECT_NE(ErrorOf(c).find("9 cubes need marker ids 0..53"), std::string::npos);
}

TEST(CubesCommand, BadOptionsExitTwoAndWriteNothing) {
  TempDir tmp;
  const std::string out = " --out '" + (tmp / "cubes") + "'";
  const std::string scene = " --scene '" + (tmp / "scene.xml") + "' --pa10 '" VLAB_SOURCE_DIR "/mjcf/pa10'";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {out + " --dictionary 4X4_51", "--dictionary '4X4_51' is not one of 4X4_50,"},
      {out + " --letters AAB", "'A' appears twice"},
      {out + " --letters ABC --first-id 40", "need marker ids 40..57"},
      {out + " --size 0", "--size 0 m outside"},
      {out + " --seed 3", "--count and --seed need --scene FILE"},
      {out + scene + " --count 7", "--count 7 outside 1..6"},
      {out + scene + " --seed -2", "--seed: must be an integer from 0 to 9007199254740992 (2^53), got '-2'"},
      {out + " --scene '" + (tmp / "scene.xml") + "' --pa10 '" + (tmp / "nowhere") + "'", "has no pa10.xml"},
      {out + scene + " --size 0.2", "do not fit the table's free area"},
      {out + " --letters AB --faces AGMSY4", "--letters and --faces exclude each other"},
      {out + " --faces AGMSY4,BHN", "--faces: 'BHN' is not six letters"},
      {out + " --faces AGMSY4,", "--faces: '' is not six letters"},
  };
  for (const auto& [args, message] : cases) {
    const auto r = RunVlab("cubes" + args, 60);
    EXPECT_EQ(r.exit_code, 2) << args;
    EXPECT_NE(r.err.find(message), std::string::npos) << args << ": " << r.err;
    EXPECT_EQ(testing::Lines(r.err).size(), 1u) << r.err;
    EXPECT_TRUE(testing::Entries(tmp.path()).empty()) << args << " wrote something";
  }
}

}  // namespace
}  // namespace vlab::vision::cubes_test
