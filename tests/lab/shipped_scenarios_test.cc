// Every scenario shipped under scenes/ and cases/*/ binds: each device finds the MJCF joints,
// actuators, sensors, sites, bodies and cameras it names (Lab::Create throws
// InputError naming the missing one otherwise), the scene loads without a
// MuJoCo warning, and the log has the columns of every device. Running them to
// pass their checks is the scenario_* ctests' part.
#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/core_errors.h"
#include "core/core_mujoco.h"
#include "lab/run/lab_runner.h"
#include "lab/scenario/lab_scenario.h"

namespace vlab::lab::shipped_scenarios_test {
namespace {

// scenes/*.yaml and every case study's cases/NAME/*.yaml, sorted
std::vector<std::string> ShippedScenarios() {
  std::vector<std::string> out;
  const auto add_scenarios_in = [&out](const std::filesystem::path& dir) {
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
      if (entry.path().extension() == ".yaml") out.push_back(entry.path().string());
    }
  };
  add_scenarios_in(VLAB_SOURCE_DIR "/scenes");
  for (const auto& entry : std::filesystem::directory_iterator(VLAB_SOURCE_DIR "/cases")) {
    if (entry.is_directory()) add_scenarios_in(entry.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(ShippedScenarios, EveryDeviceBindsToItsScene) {
  InstallMujocoHandlers();
  const std::vector<std::string> files = ShippedScenarios();
  ASSERT_GE(files.size(),
            7u);  // pa10_reach, pa10_joint_pd, pa10_serve, pa10_cubes, pa10_nomad_reach, hoap3_stand, head_track, ...
  ASSERT_TRUE(std::any_of(files.begin(), files.end(), [](const std::string& f) {
    return f.find("/cases/yoyo/stage1.yaml") != std::string::npos;
  }));  // and the case studies' (cases/yoyo/stage1.yaml, ...)
  for (const std::string& file : files) {
    SCOPED_TRACE(file);
    const Scenario scenario = LoadScenario(file);
    std::unique_ptr<Lab> lab;
    try {
      lab = Lab::Create(scenario);
    } catch (const InputError& e) {
      ADD_FAILURE() << e.what();
      continue;
    }
    EXPECT_TRUE(TakeMujocoWarningTexts().empty());
    // every device that logs has its columns, named after it
    const std::vector<std::string> columns = lab->Columns();
    for (const DeviceConfig& d : scenario.devices) {
      if (d.kind == bridge::DeviceKind::kSim || d.kind == bridge::DeviceKind::kCamera ||
          d.kind == bridge::DeviceKind::kScene) {
        continue;  // served only: nothing to log
      }
      bool found = false;
      for (const std::string& c : columns) found = found || c.rfind(d.name + ".", 0) == 0;
      EXPECT_TRUE(found) << "no log column of device '" << d.name << "'";
    }
  }
}

}  // namespace
}  // namespace vlab::lab::shipped_scenarios_test
