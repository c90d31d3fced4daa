// markers("vision") end to end (tests/data/task/markers.yaml): the lab's webcam over the
// lettered cubes, a real `vlab vision` beside the lab, `vlab task` reading the vision
// program's markers in a lockstep run.
//   - accuracy: every valid marker the script printed is, in the world frame, within the
//     vision accuracy of docs/vision.md (3 mm, 1 deg: the scene's webcam, vision_scene_test)
//     of the true pose of that marker (its cube's pose in the run, poses.bin, composed with
//     the face's marker frame, src/vision/vision_cubes.h)
//   - determinism: a second run gives the same log.csv and the same script output, byte
//     for byte, although the vision program runs asynchronously beside the lab
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "test_util.h"
#include "vision/vision_cubes.h"

namespace vlab::testing {
namespace {

constexpr double kPositionBound_m = 0.003;  // docs/vision.md: the cube scene's webcam, world frame
constexpr double kRotationBound_deg = 1.0;

struct Pose {
  Eigen::Vector3d p;
  Eigen::Quaterniond q;
};

// the bodies' poses of the recorded frame at time t (poses.bin, src/lab/outputs/lab_poses.h)
std::map<std::string, Pose> PosesAt(const std::string& dir, double t) {
  const nlohmann::json scene = nlohmann::json::parse(ReadFile(dir + "/scene.json"));
  const std::vector<std::string> names = scene.at("bodies").get<std::vector<std::string>>();
  const std::string bytes = ReadFile(dir + "/poses.bin");
  const std::size_t frame = 16 + 28 * names.size();
  std::map<std::string, Pose> out;
  for (std::size_t at = 0; at + frame <= bytes.size(); at += frame) {
    double time;
    std::memcpy(&time, bytes.data() + at, 8);
    if (std::fabs(time - t) > 1e-6) continue;
    for (std::size_t b = 0; b < names.size(); ++b) {
      float v[7];
      std::memcpy(v, bytes.data() + at + 16 + 28 * b, 28);
      out[names[b]] = {Eigen::Vector3d(v[0], v[1], v[2]), Eigen::Quaterniond(v[3], v[4], v[5], v[6]).normalized()};
    }
  }
  return out;
}

// the script's print() lines ("[pa10 t=...] ..."): the vision program's own summary line
// (frames per wall second) differs from run to run
std::string ScriptLines(const std::string& text) {
  std::string out;
  for (const std::string& line : Lines(text)) {
    if (line.rfind("[pa10 t=", 0) == 0) out += line + "\n";
  }
  return out;
}

TEST(TaskMarkers, ScriptReadsCubeMarkersWithinVisionAccuracyAndRunsRepeat) {
  TempDir a, b;  // the vision program on a free port of each run ({port:vision})
  const ProcessResult ra = RunVlab("run tests/data/task/markers.yaml --out '" + a.path() + "'", 300);
  ASSERT_EQ(ra.exit_code, 0) << ra.out << ra.err << ReadFile(a / "controller.log");
  const std::string output = ReadFile(a / "controller.log");

  // what the script printed: "frame SEQ TIME COUNT DESCRIBED", "marker DICT ID TIME x y z qw qx qy qz ERROR"
  const vision::CubeSetConfig cubes;  // mjcf/cubes: the default set (ABCDEF, 50 mm, 4X4_50 from id 0)
  int frames = 0, checked = 0, of_cube_c = 0;
  double worst_mm = 0, worst_deg = 0;
  std::istringstream lines(output);
  std::string line;
  while (std::getline(lines, line)) {
    const auto at = line.find("] ");
    if (line.rfind("[pa10 t=", 0) != 0 || at == std::string::npos) continue;
    std::istringstream in(line.substr(at + 2));
    std::string word;
    in >> word;
    if (word == "frame") {
      long seq, count, described;
      double time;
      in >> seq >> time >> count >> described;
      EXPECT_EQ(described, 36) << line;  // --marker 4X4_50:0-35
      ++frames;
    } else if (word == "marker") {
      std::string dictionary;
      int id;
      double time, x, y, z, qw, qx, qy, qz, error;
      in >> dictionary >> id >> time >> x >> y >> z >> qw >> qx >> qy >> qz >> error;
      ASSERT_FALSE(in.fail()) << line;
      ASSERT_EQ(dictionary, "4X4_50");
      const int cube = id / 6, face = id % 6;
      const std::map<std::string, Pose> truth = PosesAt(a.path(), time);
      const auto body = truth.find(vision::CubeName(cubes, cube));
      ASSERT_NE(body, truth.end()) << "no recorded pose of cube " << cube << " at t = " << time;
      const Eigen::Isometry3d marker_in_cube = vision::CubeMarkerFrame(cubes, face);
      const Eigen::Vector3d p_true = body->second.p + body->second.q * marker_in_cube.translation();
      const Eigen::Quaterniond q_true = body->second.q * Eigen::Quaterniond(marker_in_cube.rotation());
      const double mm = (Eigen::Vector3d(x, y, z) - p_true).norm() * 1000;
      const double deg = q_true.angularDistance(Eigen::Quaterniond(qw, qx, qy, qz).normalized()) * 180 / M_PI;
      EXPECT_LT(mm, kPositionBound_m * 1000) << line;
      EXPECT_LT(deg, kRotationBound_deg) << line;
      worst_mm = std::max(worst_mm, mm);
      worst_deg = std::max(worst_deg, deg);
      ++checked;
      if (cube == 2) ++of_cube_c;
    }
  }
  EXPECT_EQ(frames, 2) << output;
  EXPECT_GE(of_cube_c, 1) << output;
  EXPECT_GE(checked, 6) << output;  // docs/vision.md: 6 valid markers per frame of this webcam
  std::printf("%d valid markers checked: worst %.3f mm, %.3f deg\n", checked, worst_mm, worst_deg);

  // a second run, the same bytes
  const ProcessResult rb = RunVlab("run tests/data/task/markers.yaml --out '" + b.path() + "'", 300);
  ASSERT_EQ(rb.exit_code, 0) << rb.out << rb.err << ReadFile(b / "controller.log");
  EXPECT_EQ(ReadFile(a / "log.csv"), ReadFile(b / "log.csv"));
  EXPECT_EQ(ScriptLines(output), ScriptLines(ReadFile(b / "controller.log")));
}

}  // namespace
}  // namespace vlab::testing
