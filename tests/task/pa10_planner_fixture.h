// The PA10 of scenes/pa10.xml at its "ready" pose, a motion planner on its chain
// world -> tool (period kPeriod), and a second chain on the same model that checks
// planned samples independently (task_motion_test.cc, task_rates_test.cc).
#pragma once

#include <cmath>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "control/robot_model.h"
#include "mujoco_fixture.h"
#include "task/task_motion.h"
#include "task/task_units.h"
#include "task_test_period.h"

namespace vlab::task {

class Pa10PlannerTest : public test::MujocoTest {
 protected:
  void SetUp() override {
    model_ = LoadModel(std::string(VLAB_SOURCE_DIR) + "/scenes/pa10.xml");
    chain_ = control::RobotModel::Create(model_, {"world", "tool"});
    fk_ = control::RobotModel::Create(model_, {"world", "tool"});
    planner_ = std::make_unique<MotionPlanner>(chain_.get(), kPeriod);
    q0_.resize(7);
    q0_ << 0, 30 * kDeg, 0, 60 * kDeg, 0, 90 * kDeg, 0;  // the "ready" pose of scenes/pa10_reach.yaml
  }
  // the tool pose of q by the independent chain
  Frame Fk(const Eigen::VectorXd& q) {
    fk_->SetState(q, Eigen::VectorXd::Zero(7));
    const control::Pose p = fk_->TipPose();
    Frame f;
    f.p = p.p_W;
    f.q = Eigen::Quaterniond(p.R_W);
    return f;
  }

  mjModel* model_ = nullptr;  // owned by the fixture
  std::unique_ptr<control::RobotModel> chain_, fk_;
  std::unique_ptr<MotionPlanner> planner_;
  Eigen::VectorXd q0_;
};

}  // namespace vlab::task
