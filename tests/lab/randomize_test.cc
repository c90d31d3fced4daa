// Seeded layouts at reset (lab_randomize.h, the scenario's `randomize:` key): the keys are
// read strictly; the layout obeys every constraint it was given (closed forms for a 50 mm
// cube); the same seed gives the same layout, another seed another; a run puts the layout
// in place at its start and the cubes rest there.
#include "lab/scenario/lab_randomize.h"

#include <cmath>
#include <set>

#include <gtest/gtest.h>

#include "core/core_errors.h"
#include "core/core_mujoco.h"
#include "lab/run/lab_runner.h"
#include "lab/scenario/lab_scenario.h"
#include "test_util.h"

namespace vlab::lab::randomize_test {
namespace {

using vlab::testing::ReadFile;
using vlab::testing::RunVlab;
using vlab::testing::TempDir;
using vlab::testing::WriteFile;

const std::string kScene = VLAB_SOURCE_DIR "/scenes/pa10_cubes_gripper.xml";
constexpr double kHalfEdge = 0.025;                    // m, mjcf/cubes: 50 mm cubes
const double kFootprint = kHalfEdge * std::sqrt(2.0);  // m, circumscribed circle of a face
constexpr const char* kCubes = "[cube_A, cube_B, cube_C, cube_D, cube_E, cube_F]";

// a scenario on the cube scene with this randomize block (indented two spaces)
std::string ScenarioText(const std::string& randomize) {
  return "scene: " + kScene + "\nduration: 0.01\ncontrol_period: 0.01\nkeyframe: park\nrandomize:\n" + randomize;
}

std::string LoadError(const std::string& text) {
  TempDir dir;
  WriteFile(dir / "s.yaml", text);
  try {
    LoadScenario(dir / "s.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

RandomizeConfig StageOne() {
  RandomizeConfig c;
  for (const char* b : {"cube_A", "cube_B", "cube_C", "cube_D", "cube_E", "cube_F"}) c.bodies.push_back(b);
  c.region = {0.40, 0.80, -0.40, 0.40};
  c.has_within = true;
  c.within_radius = 0.78;
  c.exclude.push_back({0.655, 0.705, -0.13, 0.13});
  c.clearance_m = 0.04;
  c.surface_z = 0.20;
  c.where = "test";
  return c;
}

TEST(RandomizeTest, ReadsEveryKey) {
  TempDir dir;
  WriteFile(dir / "s.yaml", ScenarioText(std::string("  bodies: ") + kCubes +
                                         "\n  region: {x: [0.4, 0.8], y: [-0.4, 0.4]}\n"
                                         "  within: {center: [0, 0.1], radius: 0.78}\n"
                                         "  exclude: [{x: [0.655, 0.705], y: [-0.13, 0.13]}]\n"
                                         "  clearance: 0.03\n  surface: 0.2\n  drop: 0.0002\n"
                                         "  resting_face: 4\n  yaw: [-10, 10]\n"));
  const Scenario s = LoadScenario(dir / "s.yaml");
  const RandomizeConfig& c = s.randomize;
  ASSERT_EQ(c.bodies.size(), 6u);
  EXPECT_EQ(c.bodies[5], "cube_F");
  EXPECT_DOUBLE_EQ(c.region.x_max, 0.8);
  EXPECT_DOUBLE_EQ(c.region.y_min, -0.4);
  EXPECT_TRUE(c.has_within);
  EXPECT_DOUBLE_EQ(c.within_center.y(), 0.1);
  ASSERT_EQ(c.exclude.size(), 1u);
  EXPECT_DOUBLE_EQ(c.exclude[0].x_min, 0.655);
  EXPECT_DOUBLE_EQ(c.clearance_m, 0.03);
  EXPECT_DOUBLE_EQ(c.surface_z, 0.2);
  EXPECT_DOUBLE_EQ(c.drop_m, 0.0002);
  EXPECT_EQ(c.resting_face, 4);
  EXPECT_DOUBLE_EQ(c.yaw_min_deg, -10);
  EXPECT_DOUBLE_EQ(c.yaw_max_deg, 10);
  EXPECT_NE(c.where.find("s.yaml:6"), std::string::npos) << c.where;
}

TEST(RandomizeTest, BadKeysNameFileLineAndKey) {
  const std::string ok = std::string("  bodies: ") + kCubes + "\n  surface: 0.2\n";
  const std::string region = "  region: {x: [0.4, 0.8], y: [-0.4, 0.4]}\n";
  EXPECT_NE(
      LoadError(ScenarioText(ok + region + "  clearence: 0.04\n")).find("s.yaml:9: randomize.clearence: unknown key"),
      std::string::npos);
  EXPECT_NE(LoadError(ScenarioText(ok)).find("randomize.region: required"), std::string::npos);
  EXPECT_NE(LoadError(ScenarioText(ok + "  region: {x: [0.8, 0.4], y: [-0.4, 0.4]}\n"))
                .find("randomize.region.x: expected [min, max]"),
            std::string::npos);
  EXPECT_NE(LoadError(ScenarioText(ok + region + "  resting_face: 6\n"))
                .find("randomize.resting_face: expected any, or a face 0-5"),
            std::string::npos);
  EXPECT_NE(LoadError(ScenarioText(ok + region + "  resting_face: top\n"))
                .find("randomize.resting_face: expected any, or a face 0-5"),
            std::string::npos);
  EXPECT_NE(LoadError(ScenarioText(ok + region + "  yaw: [10]\n")).find("randomize.yaw: expected any, or [min, max]"),
            std::string::npos);
  EXPECT_NE(LoadError(ScenarioText(ok + region + "  exclude: [{x: [0, 1]}]\n"))
                .find("randomize.exclude[0].y: expected [min, max]"),
            std::string::npos);
  EXPECT_NE(LoadError(ScenarioText(ok + region + "  within: {center: [0, 0], radius: -1}\n"))
                .find("randomize.within.radius: must be > 0"),
            std::string::npos);
  EXPECT_NE(LoadError(ScenarioText("  bodies: [cube_A, cube_A]\n  surface: 0.2\n" + region))
                .find("body 'cube_A' named twice"),
            std::string::npos);
  EXPECT_NE(LoadError(ScenarioText(std::string("  bodies: ") + kCubes + "\n" + region)).find("randomize.surface"),
            std::string::npos);
}

TEST(RandomizeTest, BindingErrorsNameTheBody) {
  ModelPtr m = LoadModel(kScene);
  RandomizeConfig c = StageOne();
  c.bodies = {"cube_A", "cube_Z"};
  try {
    Randomizer::Create(m.get(), c, 1);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("test: randomize: bodies: the scene has no body 'cube_Z'"), std::string::npos)
        << e.what();
  }
  c.bodies = {"pa10_link2"};  // a body on a hinge, not a free body
  try {
    Randomizer::Create(m.get(), c, 1);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("body 'pa10_link2' must have one joint, a free joint"), std::string::npos)
        << e.what();
  }
  c = StageOne();
  c.clearance_m = 0.3;  // six cubes 0.37 m apart cannot share a 0.4 x 0.8 m region
  try {
    Randomizer::Create(m.get(), c, 1);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("does not fit"), std::string::npos) << e.what();
  }
}

// every constraint of the configuration, for 50 seeds, with the closed forms of a 50 mm cube
TEST(RandomizeTest, LayoutsKeepEveryConstraint) {
  ModelPtr m = LoadModel(kScene);
  const RandomizeConfig c = StageOne();
  std::set<int> faces;
  const double eps = 1e-12;
  for (std::uint64_t seed = 0; seed < 50; ++seed) {
    const auto r = Randomizer::Create(m.get(), c, seed);
    const auto& p = r->placements();
    ASSERT_EQ(p.size(), 6u);
    for (std::size_t i = 0; i < p.size(); ++i) {
      const Eigen::Vector2d xy = p[i].position.head<2>();
      EXPECT_GE(xy.x(), c.region.x_min + kFootprint - eps);
      EXPECT_LE(xy.x(), c.region.x_max - kFootprint + eps);
      EXPECT_GE(xy.y(), c.region.y_min + kFootprint - eps);
      EXPECT_LE(xy.y(), c.region.y_max - kFootprint + eps);
      EXPECT_LE(xy.norm(), c.within_radius + eps);
      // outside the slot rectangle by a footprint and the clearance
      const RandomizeRect& x = c.exclude[0];
      const double dx = std::max({x.x_min - xy.x(), 0.0, xy.x() - x.x_max});
      const double dy = std::max({x.y_min - xy.y(), 0.0, xy.y() - x.y_max});
      EXPECT_GE(std::hypot(dx, dy), kFootprint + c.clearance_m - eps);
      for (std::size_t j = 0; j < i; ++j) {
        EXPECT_GE((xy - p[j].position.head<2>()).norm(), 2 * kFootprint + c.clearance_m - eps) << seed;
      }
      // resting: centre half an edge + the drop above the surface, face_down's normal pointing down
      EXPECT_NEAR(p[i].position.z(), c.surface_z + kHalfEdge + c.drop_m, eps);
      Eigen::Vector3d normal = Eigen::Vector3d::Zero();
      normal[p[i].face_down / 2] = p[i].face_down % 2 == 0 ? 1 : -1;
      EXPECT_LT((p[i].orientation * normal - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);
      EXPECT_GE(p[i].yaw_deg, 0);
      EXPECT_LT(p[i].yaw_deg, 360);
      faces.insert(p[i].face_down);
    }
  }
  EXPECT_EQ(faces.size(), 6u);  // 300 draws: every face comes up (P(a face never) = 6 (5/6)^300 ~ 1e-23)
}

TEST(RandomizeTest, SameSeedSameLayoutOtherSeedAnother) {
  ModelPtr m = LoadModel(kScene);
  const auto a = Randomizer::Create(m.get(), StageOne(), 7);
  const auto b = Randomizer::Create(m.get(), StageOne(), 7);
  const auto c = Randomizer::Create(m.get(), StageOne(), 8);
  for (std::size_t i = 0; i < 6; ++i) {
    EXPECT_EQ(a->placements()[i].position, b->placements()[i].position);
    EXPECT_EQ(a->placements()[i].orientation.coeffs(), b->placements()[i].orientation.coeffs());
    EXPECT_GT((a->placements()[i].position - c->placements()[i].position).norm(), 1e-6);
  }
}

TEST(RandomizeTest, FixedFaceAndYawRange) {
  ModelPtr m = LoadModel(kScene);
  RandomizeConfig c = StageOne();
  c.resting_face = 5;  // -Z down: the body's own frame, yawed
  c.yaw_min_deg = -10;
  c.yaw_max_deg = 10;
  const auto r = Randomizer::Create(m.get(), c, 3);
  for (const RandomPlacement& p : r->placements()) {
    EXPECT_EQ(p.face_down, 5);
    EXPECT_GE(p.yaw_deg, -10);
    EXPECT_LT(p.yaw_deg, 10);
    const Eigen::Quaterniond yaw(Eigen::AngleAxisd(p.yaw_deg * M_PI / 180, Eigen::Vector3d::UnitZ()));
    EXPECT_NEAR(p.orientation.angularDistance(yaw), 0, 1e-12);
  }
}

// the lab puts the layout of its seed in place at every reset, over the keyframe
TEST(RandomizeTest, LabStartsFromTheLayout) {
  TempDir dir;
  WriteFile(dir / "s.yaml", ScenarioText(std::string("  bodies: ") + kCubes +
                                         "\n  region: {x: [0.4, 0.8], y: [-0.4, 0.4]}\n"
                                         "  within: {center: [0, 0], radius: 0.78}\n"
                                         "  exclude: [{x: [0.655, 0.705], y: [-0.13, 0.13]}]\n"
                                         "  surface: 0.2\n"));
  Scenario s = LoadScenario(dir / "s.yaml");
  s.seed = 11;
  const auto lab = Lab::Create(s);
  DataPtr d = MakeData(lab->model());
  lab->InitialState(d.get());
  const auto expected = Randomizer::Create(lab->model(), s.randomize, 11);
  const mjModel* m = lab->model();
  for (const RandomPlacement& p : expected->placements()) {
    const double* q = d->qpos + m->jnt_qposadr[m->body_jntadr[p.body]];
    EXPECT_EQ(Eigen::Vector3d(q[0], q[1], q[2]), p.position);
    EXPECT_EQ(Eigen::Vector4d(q[3], q[4], q[5], q[6]),
              Eigen::Vector4d(p.orientation.w(), p.orientation.x(), p.orientation.y(), p.orientation.z()));
  }
  // the arm and the gripper keep the keyframe's pose (park: S2 = -40 deg)
  EXPECT_NEAR(d->qpos[1], -40 * M_PI / 180, 1e-6);
}

// `vlab run --seed N`: the same seed writes the same log (the cubes' poses from the start),
// another seed another table; every cube rests where it was put (the scenario's checks)
TEST(RandomizeTest, RunSeedGivesTheTable) {
  TempDir dir;
  const std::string scenario = "tests/data/cubes/layout.yaml";
  const auto a = RunVlab("run " + scenario + " --seed 4 --quiet --out " + (dir / "a"));
  const auto b = RunVlab("run " + scenario + " --seed 4 --quiet --out " + (dir / "b"));
  const auto c = RunVlab("run " + scenario + " --seed 5 --quiet --out " + (dir / "c"));
  ASSERT_EQ(a.exit_code, 0) << a.err;
  ASSERT_EQ(b.exit_code, 0) << b.err;
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const std::string log_a = ReadFile(dir / "a/log.csv");
  EXPECT_FALSE(log_a.empty());
  EXPECT_EQ(log_a, ReadFile(dir / "b/log.csv"));
  EXPECT_NE(log_a, ReadFile(dir / "c/log.csv"));
}

}  // namespace
}  // namespace vlab::lab::randomize_test
