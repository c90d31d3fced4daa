// The test fixture of every test that loads a MuJoCo model: it loads through
// src/core (vlab::LoadModel, vlab::LoadModelFromString, vlab::MakeData), owns
// what it loads, and fails the test on any MuJoCo warning the test did not
// declare (after mujoco's test/fixture.h, which fails on any warning).
//
// A warning is seen two ways, both checked at TearDown:
//   - its text, through the process-global handler of vlab::InstallMujocoHandlers
//     (every mjData, also those made by the code under test);
//   - the counters mjData::warning[i].number of every mjData the fixture made or
//     was asked to watch (WatchData), which survive a handler replaced behind
//     the fixture's back.
// vlab::LoadModel drops the warning MuJoCo's compiler returns with a model (the
// compiler takes one step from qpos0 and reports what it raised), so LoadModel
// and LoadModelFromString take that step again on a scratch mjData and count
// what it raises.
//
// Threading: MuJoCo's warning handler is process-global; gtest runs the tests
// of one executable on one thread.
#pragma once

#include <array>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include "core/core_mujoco.h"

namespace vlab::test {

/// Absolute path of a file of the source tree ("scenes/pa10.xml"); an absolute
/// path comes back unchanged.
std::string SourcePath(const std::string& path);

/// True once MuJoCo has counted any warning in `data` (simulation loops stop on it:
/// on divergence MuJoCo also resets the data, time included).
bool AnyWarning(const mjData& data);

/// Index of the MuJoCo warning a handler text reports ("Pre-allocated contact
/// buffer is full. ..." -> mjWARN_CONTACTFULL), or -1 for a text that is none of
/// mjData's warnings (e.g. the XML parser's).
int WarningIndexOfText(const std::string& text);

/// Base of MuJoCo test fixtures. Derived fixtures set up in SetUp (no need to call
/// this class's) and clean up in their destructors: TearDown is the warning check.
class MujocoTest : public ::testing::Test {
 protected:
  /// Installs vlab's MuJoCo handlers and drops warning texts left by earlier tests.
  MujocoTest();

  /// Fails the test (one ADD_FAILURE per warning, naming it as vlab::WarningName
  /// does, with MuJoCo's text) on every warning raised since construction that
  /// was not declared with AllowWarning.
  void TearDown() final;

  /// Declares that this test expects the MuJoCo warning `name` (a vlab::WarningName:
  /// "contactfull", "badqacc", ...); it then does not fail the test, and need not
  /// happen. An unknown name fails the test.
  void AllowWarning(const std::string& name);

  /// Loads an MJCF file (a relative path is taken from the source tree's root).
  /// Throws vlab::InputError when it is missing or does not compile. The model
  /// lives as long as the fixture.
  mjModel* LoadModel(const std::string& path);

  /// Loads an MJCF document held in memory (it must not include other files);
  /// `name` appears in error messages. Throws vlab::InputError on failure.
  mjModel* LoadModelFromString(const std::string& name, const std::string& xml);
  mjModel* LoadModelFromString(const std::string& xml) { return LoadModelFromString("inline.xml", xml); }

  /// A fresh mjData for `model`, owned by the fixture; its warning counters are
  /// checked at TearDown.
  mjData* MakeData(const mjModel* model);

  /// Also checks the warning counters of an mjData owned elsewhere (e.g. the
  /// scratch data of a control::RobotModel). It must outlive TearDown: a member
  /// of the derived fixture does.
  void WatchData(const mjData* data);

 private:
  // the compiler's check vlab::LoadModel drops: one step from qpos0 on scratch data
  void CountFirstStep(const mjModel* model);

  std::vector<ModelPtr> models_;
  std::vector<DataPtr> data_;
  std::vector<const mjData*> watched_;
  std::array<long, mjNWARNING> first_step_counts_{};  // summed over the models loaded
  std::set<int> allowed_;
};

}  // namespace vlab::test
