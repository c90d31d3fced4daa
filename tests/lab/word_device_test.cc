// Tests the word scorer (src/lab/devices/device_word.cc) against closed forms:
// two 50 mm cubes on free joints and two slot sites, the second slot turned
// 90 deg about z. A cube exactly at its slot scores 0; moved by (dx, dy, dz)
// its position error is hypot(dx, dy); turned by a about z its yaw error is
// |a| (wrapped to 0..180); tipped by b < 45 deg its tilt is b, by 90 deg onto
// a side it is 0 again with another face on top. The reading direction of
// each face ("up" of its letter) is taken here from the face table of
// mjcf/cubes/README.md (MuJoCo's cube texture on a box, measured there) and
// worked out by hand for each rotation; tests/vision/word_render_test.cc
// checks the same against markers detected in rendered images. An alphabet
// block (custom text "<body>.faces") counts only with its letter on top.
#include <cmath>
#include <filesystem>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bridge/bridge_layouts.h"
#include "core/core_errors.h"
#include "lab/devices/device_kinds.h"
#include "lab/devices/device_word.h"
#include "lab/scenario/lab_scenario.h"
#include "mujoco_fixture.h"
#include "test_util.h"

namespace vlab::lab::word_device_test {
namespace {

constexpr double kDeg = M_PI / 180.0;

// cube_F (plain: F on every face) and block (faces H O T E L S on +X -X +Y -Y
// +Z -Z); slot_1 at (0.5, 0, 0.425) reading along +y, slot_2 at (0.5, 0.2,
// 0.425) turned 90 deg about z: reading along -x. No gravity: poses stay put.
constexpr const char* kXml = R"(
<mujoco>
  <option timestep="0.001" gravity="0 0 0"/>
  <custom>
    <text name="block.faces" data="HOTELS"/>
    <text name="bad.faces" data="HOT"/>
  </custom>
  <worldbody>
    <site name="slot_1" pos="0.5 0 0.425"/>
    <site name="slot_2" pos="0.5 0.2 0.425" euler="0 0 90"/>
    <body name="cube_F" pos="0.5 0 0.425">
      <freejoint/>
      <geom type="box" size="0.025 0.025 0.025" mass="0.0875"/>
    </body>
    <body name="block" pos="0.5 0.2 0.425">
      <freejoint/>
      <geom type="box" size="0.025 0.025 0.025" mass="0.0875"/>
    </body>
    <body name="bad" pos="0 1 0.425">
      <freejoint/>
      <geom type="box" size="0.025 0.025 0.025" mass="0.0875"/>
    </body>
    <body name="fixed" pos="0 -1 0.425">
      <geom type="box" size="0.025 0.025 0.025" mass="0.0875"/>
    </body>
  </worldbody>
</mujoco>)";

struct Score {
  double spelled, pos_error, yaw_error, tilt, speed, on_top;
};

DeviceConfig Word(const std::string& word, std::vector<std::string> slots, std::vector<std::string> bodies) {
  DeviceConfig c;
  c.name = "word";
  c.kind = bridge::DeviceKind::kWord;
  c.where = "test.yaml:1";
  WordParams& p = c.EditParams<WordParams>();
  p.word = word;
  p.slots = std::move(slots);
  p.bodies = std::move(bodies);
  return c;
}

Eigen::Quaterniond About(const Eigen::Vector3d& axis, double deg) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(deg * kDeg, axis));
}

class WordDeviceTest : public test::MujocoTest {
 protected:
  void SetUp() override {
    m_ = LoadModelFromString("word.xml", kXml);
    d_ = MakeData(m_);
  }
  // free body b (0: cube_F, 1: block) at p with orientation q and linear velocity v
  void Place(int b, const Eigen::Vector3d& p, const Eigen::Quaterniond& q,
             const Eigen::Vector3d& v = Eigen::Vector3d::Zero()) {
    double* x = d_->qpos + 7 * b;
    for (int i = 0; i < 3; ++i) x[i] = p[i];
    x[3] = q.w(), x[4] = q.x(), x[5] = q.y(), x[6] = q.z();
    for (int i = 0; i < 6; ++i) d_->qvel[6 * b + i] = i < 3 ? v[i] : 0.0;
  }
  // the first letter's score, after mj_forward
  Score ScoreOf(const DeviceConfig& c) {
    mj_forward(m_, d_);
    auto device = MakeDevice({m_, 0.002, 1, "word.xml"}, c);
    device->Sample(*d_, 0.0);
    std::vector<double> state;
    device->State(&state);
    EXPECT_EQ(static_cast<int>(state.size()), device->ColumnCount());
    std::vector<double> row(state.size());
    device->Row(*d_, row.data());
    EXPECT_EQ(row, state);
    return {state[0], state[1], state[2], state[3], state[4], state[5]};
  }
  Score F() { return ScoreOf(Word("F", {"slot_1"}, {"cube_F"})); }
  std::string ErrorOf(const DeviceConfig& c) {
    try {
      MakeDevice({m_, 0.002, 1, "word.xml"}, c);
    } catch (const InputError& e) {
      return e.what();
    }
    return "no error";
  }

  const Eigen::Vector3d slot1_ = Eigen::Vector3d(0.5, 0, 0.425);
  mjModel* m_ = nullptr;
  mjData* d_ = nullptr;
};

TEST_F(WordDeviceTest, CubeExactlyAtItsSlotScoresZeroAndSpells) {
  Place(0, slot1_, Eigen::Quaterniond::Identity());
  const Score s = F();
  EXPECT_NEAR(s.pos_error, 0, 1e-12);
  EXPECT_NEAR(s.yaw_error, 0, 1e-9);
  EXPECT_NEAR(s.tilt, 0, 1e-6);
  EXPECT_EQ(s.speed, 0);
  EXPECT_EQ(s.on_top, 1);
  EXPECT_EQ(s.spelled, 1);
}

TEST_F(WordDeviceTest, PositionErrorIsTheHorizontalDistance) {
  Place(0, slot1_ + Eigen::Vector3d(0.003, -0.004, 0.2), Eigen::Quaterniond::Identity());
  const Score s = F();
  EXPECT_NEAR(s.pos_error, 0.005, 1e-12);  // hypot(3, 4) mm; the 0.2 m of height does not count
  EXPECT_EQ(s.spelled, 1);
  // the default bound, 10 mm: 9.9 mm spells, 10.1 mm does not
  Place(0, slot1_ + Eigen::Vector3d(0.0, 0.0099, 0), Eigen::Quaterniond::Identity());
  EXPECT_EQ(F().spelled, 1);
  Place(0, slot1_ + Eigen::Vector3d(0.0, 0.0101, 0), Eigen::Quaterniond::Identity());
  EXPECT_EQ(F().spelled, 0);
}

TEST_F(WordDeviceTest, TurnedAboutZTheYawErrorIsTheTurn) {
  for (double a : {30.0, -30.0, 14.9, 15.1, 90.0, 170.0, -170.0, 180.0}) {
    Place(0, slot1_, About(Eigen::Vector3d::UnitZ(), a));
    const Score s = F();
    const double expected = std::abs(a);
    EXPECT_NEAR(s.yaw_error, expected, 1e-9) << a;
    EXPECT_NEAR(s.tilt, 0, 1e-6) << a;
    EXPECT_EQ(s.spelled, expected <= 15 ? 1 : 0) << a;
  }
}

TEST_F(WordDeviceTest, TheSlotsOwnReadingDirectionCounts) {
  // slot_2 reads along -x (turned +90 deg about z): the cube must be turned the same
  const DeviceConfig c = Word("F", {"slot_2"}, {"cube_F"});
  Place(0, Eigen::Vector3d(0.5, 0.2, 0.425), Eigen::Quaterniond::Identity());
  EXPECT_NEAR(ScoreOf(c).yaw_error, 90, 1e-9);
  Place(0, Eigen::Vector3d(0.5, 0.2, 0.425), About(Eigen::Vector3d::UnitZ(), 90));
  EXPECT_NEAR(ScoreOf(c).yaw_error, 0, 1e-9);
  EXPECT_EQ(ScoreOf(c).spelled, 1);
}

TEST_F(WordDeviceTest, TippedTheTiltIsTheTipUntilAnotherFaceIsOnTop) {
  for (double b : {3.0, 4.9, 5.1, 40.0}) {
    Place(0, slot1_, About(Eigen::Vector3d::UnitX(), b));
    EXPECT_NEAR(F().tilt, b, 1e-9) << b;
    EXPECT_NEAR(F().yaw_error, 0, 1e-9) << b;  // tipped about x: the letter's up still projects onto +y
    EXPECT_EQ(F().spelled, b <= 5 ? 1 : 0) << b;
  }
  // past 45 deg the +Y face is on top, 90 - 50 = 40 deg from level
  Place(0, slot1_, About(Eigen::Vector3d::UnitX(), 50));
  EXPECT_NEAR(F().tilt, 40, 1e-9);
}

TEST_F(WordDeviceTest, OnASideTheFaceOnTopReadsAsTheFaceTableSays) {
  // Rotation -> face on top -> its "up" (README face table) -> in the world:
  //   Rx(+90): (x, y, z) -> (x, -z, y): +Y on top, up -Z -> +y: reads along the slot, 0 deg
  //   Rx(-90): (x, y, z) -> (x, z, -y): -Y on top, up +Z -> +y: 0 deg
  //   Ry(+90): (x, y, z) -> (z, y, -x): -X on top, up +Y -> +y: 0 deg
  //   Ry(-90): (x, y, z) -> (-z, y, x): +X on top, up +Y -> +y: 0 deg
  //   Rx(180): (x, y, z) -> (x, -y, -z): -Z on top, up +Y -> -y: 180 deg
  //   Rz(90) Ry(90): -X on top, up +Y -> Rz(90) +y = -x: 90 deg
  const struct {
    Eigen::Quaterniond q;
    double yaw;
  } cases[] = {{About(Eigen::Vector3d::UnitX(), 90), 0},
               {About(Eigen::Vector3d::UnitX(), -90), 0},
               {About(Eigen::Vector3d::UnitY(), 90), 0},
               {About(Eigen::Vector3d::UnitY(), -90), 0},
               {About(Eigen::Vector3d::UnitX(), 180), 180},
               {About(Eigen::Vector3d::UnitZ(), 90) * About(Eigen::Vector3d::UnitY(), 90), 90}};
  for (const auto& c : cases) {
    Place(0, slot1_, c.q);
    const Score s = F();
    EXPECT_NEAR(s.tilt, 0, 1e-6) << c.q.coeffs().transpose();
    EXPECT_NEAR(s.yaw_error, c.yaw, 1e-6) << c.q.coeffs().transpose();
    EXPECT_EQ(s.on_top, 1);  // F on every face
    EXPECT_EQ(s.spelled, c.yaw == 0 ? 1 : 0);
  }
}

TEST_F(WordDeviceTest, SpeedIsTheCentresSpeed) {
  Place(0, slot1_, Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.003, 0, -0.004));
  EXPECT_NEAR(F().speed, 0.005, 1e-12);
  // the default bound, 5 mm/s: 4.9 mm/s spells, 5.1 mm/s does not
  Place(0, slot1_, Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 0.0049));
  EXPECT_EQ(F().spelled, 1);
  Place(0, slot1_, Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 0.0051));
  EXPECT_EQ(F().spelled, 0);
}

TEST_F(WordDeviceTest, AnAlphabetBlockCountsOnlyWithItsLetterOnTop) {
  // block faces: H +X, O -X, T +Y, E -Y, L +Z, S -Z; slot_2 reads along -x
  const Eigen::Vector3d slot2(0.5, 0.2, 0.425);
  const DeviceConfig e = Word("E", {"slot_2"}, {"block"});
  // upright: L on top, not E
  Place(1, slot2, About(Eigen::Vector3d::UnitZ(), 90));
  Score s = ScoreOf(e);
  EXPECT_EQ(s.on_top, 0);
  EXPECT_EQ(s.spelled, 0);
  EXPECT_NEAR(s.yaw_error, 0, 1e-9);
  // Rx(-90): -Y (E) on top, up +Z -> +y; then Rz(90): +y -> -x, the slot's direction
  Place(1, slot2, About(Eigen::Vector3d::UnitZ(), 90) * About(Eigen::Vector3d::UnitX(), -90));
  s = ScoreOf(e);
  EXPECT_EQ(s.on_top, 1);
  EXPECT_NEAR(s.yaw_error, 0, 1e-9);
  EXPECT_EQ(s.spelled, 1);
  // Rx(+90) puts T on top
  Place(1, slot2, About(Eigen::Vector3d::UnitZ(), 90) * About(Eigen::Vector3d::UnitX(), 90));
  EXPECT_EQ(ScoreOf(e).on_top, 0);
  EXPECT_EQ(ScoreOf(Word("T", {"slot_2"}, {"block"})).on_top, 1);
}

TEST_F(WordDeviceTest, SpelledNeedsEveryLetter) {
  const DeviceConfig c = Word("FE", {"slot_1", "slot_2"}, {"cube_F", "block"});
  Place(0, slot1_, Eigen::Quaterniond::Identity());
  Place(1, Eigen::Vector3d(0.5, 0.2, 0.425),
        About(Eigen::Vector3d::UnitZ(), 90) * About(Eigen::Vector3d::UnitX(), -90));
  EXPECT_EQ(ScoreOf(c).spelled, 1);
  Place(0, slot1_ + Eigen::Vector3d(0.02, 0, 0), Eigen::Quaterniond::Identity());
  EXPECT_EQ(ScoreOf(c).spelled, 0);
}

TEST_F(WordDeviceTest, ColumnsAndDescribeNameEveryLetter) {
  auto device = MakeDevice({m_, 0.002, 1, "word.xml"}, Word("FE", {"slot_1", "slot_2"}, {"cube_F", "block"}));
  EXPECT_EQ(device->kind(), bridge::DeviceKind::kWord);
  EXPECT_EQ(device->command_input(), nullptr);  // output only: no command input
  const std::vector<std::string> columns = device->Columns();
  ASSERT_EQ(columns.size(), 11u);
  EXPECT_EQ(columns[0], "word.spelled");
  EXPECT_EQ(columns[1], "word.F.pos_error");
  EXPECT_EQ(columns[5], "word.F.on_top");
  EXPECT_EQ(columns[8], "word.E.tilt");
  const nlohmann::json j = nlohmann::json::parse(device->DescribeFacts());
  EXPECT_EQ(j["layout"]["state"].size(), 11u);
  EXPECT_EQ(j["layout"]["state"][0], "spelled");
  EXPECT_EQ(j["layout"]["state"][2], "F.yaw_error");
  EXPECT_EQ(j["word"], "FE");
  EXPECT_EQ(j["bounds"]["angle_deg"], 15.0);
}

TEST_F(WordDeviceTest, BindingErrorsNameTheDeviceTheLetterAndTheElement) {
  EXPECT_EQ(ErrorOf(Word("F", {"slot_9"}, {"cube_F"})),
            "test.yaml:1: device 'word': letter 'F': the scene has no site 'slot_9' (slot)");
  EXPECT_EQ(ErrorOf(Word("F", {"slot_1"}, {"cube_G"})),
            "test.yaml:1: device 'word': letter 'F': the scene has no body 'cube_G'");
  EXPECT_EQ(ErrorOf(Word("F", {"slot_1"}, {"fixed"})),
            "test.yaml:1: device 'word': letter 'F': body 'fixed' needs one free joint and nothing else");
  EXPECT_EQ(ErrorOf(Word("A", {"slot_1"}, {"block"})),
            "test.yaml:1: device 'word': letter 'A': block 'block' has no face with it (its faces: HOTELS)");
  EXPECT_NE(ErrorOf(Word("H", {"slot_1"}, {"bad"})).find("text 'bad.faces' is 'HOT', not six letters"),
            std::string::npos);
}

TEST_F(WordDeviceTest, ReadsTheCommittedBlocksFaceLetters) {
  // mjcf/cubes/blocks, as generated: cube_EKQW28 carries E K Q W 2 8 on +X -X +Y -Y +Z -Z
  vlab::testing::TempDir dir;
  // MuJoCo 2.2.2 resolves include and texture paths against the model's folder, absolute or not
  const std::string blocks =
      std::filesystem::relative(VLAB_SOURCE_DIR "/mjcf/cubes/blocks", dir.path()).generic_string() + "/";
  vlab::testing::WriteFile(dir / "blocks.xml", "<mujoco>\n  <compiler texturedir=\"" + blocks +
                                                   "\"/>\n  <option gravity=\"0 0 0\"/>\n  <include file=\"" + blocks +
                                                   "cubes_assets.xml\"/>\n  <worldbody>\n"
                                                   "    <site name=\"slot\" pos=\"0.5 0 0.425\"/>\n"
                                                   "    <body name=\"cube_EKQW28\" pos=\"0.5 0 0.425\">\n"
                                                   "      <include file=\"" +
                                                   blocks +
                                                   "cube_EKQW28.xml\"/>\n"
                                                   "    </body>\n  </worldbody>\n</mujoco>\n");
  m_ = LoadModel(dir / "blocks.xml");
  d_ = MakeData(m_);
  const DeviceConfig e = Word("E", {"slot"}, {"cube_EKQW28"});
  Place(0, slot1_, Eigen::Quaterniond::Identity());  // +Z on top: '2'
  EXPECT_EQ(ScoreOf(e).on_top, 0);
  EXPECT_EQ(ScoreOf(Word("2", {"slot"}, {"cube_EKQW28"})).on_top, 1);
  Place(0, slot1_, About(Eigen::Vector3d::UnitY(), -90));  // Ry(-90): +X on top, its up +Y -> +y
  const Score s = ScoreOf(e);
  EXPECT_EQ(s.on_top, 1);
  EXPECT_NEAR(s.yaw_error, 0, 1e-9);
  EXPECT_EQ(s.spelled, 1);
  EXPECT_EQ(ErrorOf(Word("A", {"slot"}, {"cube_EKQW28"})),
            "test.yaml:1: device 'word': letter 'A': block 'cube_EKQW28' has no face with it (its faces: EKQW28)");
}

TEST(WordScenario, KeysAreReadAndCheckedByTheKindsReader) {
  vlab::testing::TempDir dir;
  vlab::testing::WriteFile(dir / "word.xml", kXml);
  const std::string head = "scene: word.xml\nduration: 0.1\ncontrol_period: 0.01\ndevices:\n";
  auto load = [&](const std::string& device) {
    vlab::testing::WriteFile(dir / "s.yaml", head + "  - " + device + "\n");
    return LoadScenario(dir / "s.yaml");
  };
  const Scenario s = load(
      "{name: word, kind: word, word: FE, slots: [slot_1, slot_2], letters: {E: block}, "
      "bounds: {position: 0.02, angle_deg: 10, tilt_deg: 4, speed: 0.01}}");
  ASSERT_EQ(s.devices.size(), 1u);
  const WordParams& p = s.devices[0].ParamsAs<WordParams>();
  EXPECT_EQ(p.word, "FE");
  EXPECT_EQ(p.bodies, (std::vector<std::string>{"cube_F", "block"}));  // F: the default cube_F
  EXPECT_EQ(p.bounds.position_m, 0.02);
  EXPECT_EQ(p.bounds.angle_deg, 10);
  EXPECT_EQ(p.bounds.tilt_deg, 4);
  EXPECT_EQ(p.bounds.speed_m_s, 0.01);
  auto error = [&](const std::string& device) {
    try {
      load(device);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error("{name: w, kind: word, word: FEF, slots: [a, b, c]}").find("word: 'F' appears twice"),
            std::string::npos);
  EXPECT_NE(error("{name: w, kind: word, word: F-, slots: [a, b]}").find("word: '-' is not A-Z or 0-9"),
            std::string::npos);
  EXPECT_NE(
      error("{name: w, kind: word, word: FE, slots: [a]}").find("slots: needs one site per letter of 'FE' (2), got 1"),
      std::string::npos);
  EXPECT_NE(
      error("{name: w, kind: word, word: FE, slots: [a, b], letters: {X: cube_X}}").find("letters.X: unknown key"),
      std::string::npos);
  EXPECT_NE(error("{name: w, kind: word, word: FE, slots: [a, b], bounds: {angle_deg: 0}}")
                .find("bounds.angle_deg: must be > 0"),
            std::string::npos);
}

}  // namespace
}  // namespace vlab::lab::word_device_test
