// The PA10 scene for physics tests, loaded with no compiler warning allowed.
#pragma once

#include <memory>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

namespace vlab::testing {

using Pa10ModelPtr = std::unique_ptr<mjModel, decltype(&mj_deleteModel)>;

inline Pa10ModelPtr LoadPa10Scene() {
  char error[1000] = "";
  mjModel* m = mj_loadXML(VLAB_SOURCE_DIR "/scenes/pa10.xml", nullptr, error, sizeof(error));
  EXPECT_STREQ(error, "") << "load error or compiler warning";
  return Pa10ModelPtr(m, mj_deleteModel);
}

}  // namespace vlab::testing
