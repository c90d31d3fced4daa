// The MuJoCo test fixture (mujoco_fixture.h) fails a test on an undeclared MuJoCo warning,
// seen by its text or by mjData's counters alone, and passes on a declared one. Each case
// runs a fixture object of its own and calls its TearDown under gtest's failure catchers.
#include "mujoco_fixture.h"

#include <string>
#include <vector>

#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include "core/core_errors.h"

namespace vlab::test {
namespace {

// a sphere on a slide joint: a huge velocity raises "badqvel" on the next step
constexpr char kSlideXml[] = R"(
<mujoco model="slide">
  <worldbody>
    <body name="ball">
      <joint name="slide" type="slide" axis="1 0 0"/>
      <geom type="sphere" size="0.1" mass="1"/>
    </body>
  </worldbody>
</mujoco>
)";

// a box sunk into the floor with room for one contact: its four contacts overflow the
// buffer ("contactfull") from the first step, the one MuJoCo's compiler takes
constexpr char kOverflowXml[] = R"(
<mujoco model="overflow">
  <size nconmax="1"/>
  <worldbody>
    <geom name="floor" type="plane" size="1 1 0.1"/>
    <body name="box" pos="0 0 0.04">
      <freejoint/>
      <geom type="box" size="0.05 0.05 0.05" mass="1"/>
    </body>
  </worldbody>
</mujoco>
)";

// one test's fixture, run by hand: the cases below call its TearDown themselves
class Probe : public MujocoTest {
 public:
  using MujocoTest::AllowWarning;
  using MujocoTest::LoadModel;
  using MujocoTest::LoadModelFromString;
  using MujocoTest::MakeData;
  using MujocoTest::TearDown;
  using MujocoTest::WatchData;

  // loads the slide, makes its data and steps it once at 1e11 m/s
  mjData* RaiseBadQvel() {
    const mjModel* m = LoadModelFromString("slide.xml", kSlideXml);
    mjData* d = MakeData(m);
    d->qvel[0] = 1e11;
    mj_step(m, d);
    return d;
  }

 private:
  void TestBody() override {}
};

// the failures TearDown reports, intercepted
std::vector<std::string> TearDownFailures(Probe& probe) {
  ::testing::TestPartResultArray results;
  {
    ::testing::ScopedFakeTestPartResultReporter reporter(
        ::testing::ScopedFakeTestPartResultReporter::INTERCEPT_ONLY_CURRENT_THREAD, &results);
    probe.TearDown();
  }
  std::vector<std::string> messages;
  for (int i = 0; i < results.size(); ++i) messages.push_back(results.GetTestPartResult(i).message());
  return messages;
}

TEST(MujocoTest, QuietModelPasses) {
  Probe probe;
  const mjModel* m = probe.LoadModelFromString(kSlideXml);
  mjData* d = probe.MakeData(m);
  for (int i = 0; i < 100; ++i) mj_step(m, d);
  EXPECT_TRUE(TearDownFailures(probe).empty());
}

TEST(MujocoTest, UndeclaredWarningFailsWithItsNameAndText) {
  Probe probe;
  const mjData* d = probe.RaiseBadQvel();
  ASSERT_EQ(d->warning[mjWARN_BADQVEL].number, 1) << "the model no longer raises the warning";
  EXPECT_NONFATAL_FAILURE(probe.TearDown(),
                          "MuJoCo warning 'badqvel' not declared with AllowWarning(\"badqvel\"): "
                          "Nan, Inf or huge value in QVEL at DOF 0.");
}

TEST(MujocoTest, CountersAloneFailTheTest) {
  Probe probe;
  probe.RaiseBadQvel();
  TakeMujocoWarningTexts();  // as if another handler had taken the text
  EXPECT_NONFATAL_FAILURE(probe.TearDown(),
                          "'badqvel' not declared with AllowWarning(\"badqvel\"): mjData::warning counts 1");
}

TEST(MujocoTest, TextAloneFailsTheTest) {
  Probe probe;
  const mjModel* m = probe.LoadModelFromString(kSlideXml);
  {
    // data the fixture neither made nor watches, gone before TearDown
    const DataPtr d = vlab::MakeData(m);
    d->qvel[0] = 1e11;
    mj_step(m, d.get());
  }
  EXPECT_NONFATAL_FAILURE(probe.TearDown(), "'badqvel' not declared with AllowWarning(\"badqvel\"): Nan, Inf");
}

TEST(MujocoTest, WatchedDataCountersFailTheTest) {
  Probe probe;
  const mjModel* m = probe.LoadModelFromString(kSlideXml);
  const DataPtr d = vlab::MakeData(m);  // owned elsewhere, outlives TearDown
  probe.WatchData(d.get());
  d->qvel[0] = 1e11;
  mj_step(m, d.get());
  TakeMujocoWarningTexts();
  EXPECT_NONFATAL_FAILURE(probe.TearDown(),
                          "'badqvel' not declared with AllowWarning(\"badqvel\"): mjData::warning counts 1");
}

TEST(MujocoTest, CompilerWarningOfALoadedModelFailsTheTest) {
  Probe probe;
  probe.LoadModelFromString("overflow.xml", kOverflowXml);  // no data made, no step taken
  EXPECT_NONFATAL_FAILURE(probe.TearDown(),
                          "'contactfull' not declared with AllowWarning(\"contactfull\"): Pre-allocated contact buffer "
                          "is full. Increase nconmax above 1.");
}

TEST(MujocoTest, DeclaredWarningPasses) {
  Probe probe;
  probe.AllowWarning("badqvel");
  const mjData* d = probe.RaiseBadQvel();
  ASSERT_EQ(d->warning[mjWARN_BADQVEL].number, 1);
  EXPECT_TRUE(TearDownFailures(probe).empty());

  Probe overflow;
  overflow.AllowWarning("contactfull");
  const mjModel* m = overflow.LoadModelFromString(kOverflowXml);
  mjData* data = overflow.MakeData(m);
  for (int i = 0; i < 10; ++i) mj_step(m, data);
  ASSERT_GT(data->warning[mjWARN_CONTACTFULL].number, 0);
  EXPECT_TRUE(TearDownFailures(overflow).empty());
}

TEST(MujocoTest, DeclaredWarningThatNeverHappensPasses) {
  Probe probe;
  probe.AllowWarning("contactfull");
  probe.LoadModelFromString(kSlideXml);
  EXPECT_TRUE(TearDownFailures(probe).empty());
}

TEST(MujocoTest, DeclaringOneWarningStillFailsOnAnother) {
  Probe probe;
  probe.AllowWarning("contactfull");
  probe.RaiseBadQvel();
  const std::vector<std::string> failures = TearDownFailures(probe);
  ASSERT_EQ(failures.size(), 1u);
  EXPECT_NE(failures[0].find("MuJoCo warning 'badqvel' not declared"), std::string::npos) << failures[0];
}

TEST(MujocoTest, UnknownWarningNameFails) {
  Probe probe;
  EXPECT_NONFATAL_FAILURE(probe.AllowWarning("contact_full"),
                          "AllowWarning: no MuJoCo warning 'contact_full' (known: inertia, contactfull,");
  EXPECT_TRUE(TearDownFailures(probe).empty());
}

TEST(MujocoTest, WarningsBeforeTheTestAreNotItsOwn) {
  {
    // an earlier test without the fixture leaves a text behind
    InstallMujocoHandlers();
    const ModelPtr m = vlab::LoadModelFromString("slide.xml", kSlideXml);
    const DataPtr d = vlab::MakeData(m.get());
    d->qvel[0] = 1e11;
    mj_step(m.get(), d.get());
  }
  Probe probe;
  EXPECT_TRUE(TearDownFailures(probe).empty());
}

TEST(MujocoTest, LoadErrorsThrowInputErrorNamingTheScene) {
  Probe probe;
  try {
    probe.LoadModel("tests/data/no_such_scene.xml");
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("tests/data/no_such_scene.xml': cannot open file"), std::string::npos)
        << e.what();
  }
  try {
    probe.LoadModelFromString("broken.xml", "<mujoco><worldbody><geom type='nonsense'/></worldbody></mujoco>");
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("scene 'broken.xml': "), std::string::npos) << e.what();
  }
  EXPECT_TRUE(TearDownFailures(probe).empty());
}

TEST(MujocoTest, LoadModelTakesPathsFromTheSourceTree) {
  EXPECT_EQ(SourcePath("scenes/pa10.xml"), VLAB_SOURCE_DIR "/scenes/pa10.xml");
  EXPECT_EQ(SourcePath("/tmp/scene.xml"), "/tmp/scene.xml");
  Probe probe;
  const mjModel* m = probe.LoadModel("scenes/pa10.xml");
  EXPECT_EQ(m->nq, 7);
  EXPECT_TRUE(TearDownFailures(probe).empty());
}

TEST(MujocoTest, WarningTextsMapToTheirWarnings) {
  for (int i = 0; i < mjNWARNING; ++i) {
    const std::string text = std::string(mju_warningText(i, 12)) + " Time = 0.5000.";
    EXPECT_EQ(WarningIndexOfText(text), i) << text;
  }
  EXPECT_EQ(WarningIndexOfText("XML contains a 'NaN'. Please check it carefully."), -1);
}

TEST(MujocoTest, AnyWarningReadsTheCounters) {
  Probe probe;
  const mjData* d = probe.RaiseBadQvel();
  EXPECT_TRUE(AnyWarning(*d));
  EXPECT_FALSE(AnyWarning(*probe.MakeData(probe.LoadModelFromString(kSlideXml))));
  probe.AllowWarning("badqvel");
  EXPECT_TRUE(TearDownFailures(probe).empty());
}

}  // namespace
}  // namespace vlab::test
