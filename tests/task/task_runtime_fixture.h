// The task runtime's test fixture: fake devices (a perfect position servo per
// arm: the state's q is the last commanded position; a settable wrench; a
// gripper) and RuntimeTest, which runs scripts on them in process.
#pragma once

#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "mujoco_fixture.h"
#include "task/task_runtime.h"
#include "task_test_period.h"
#include "test_util.h"

namespace vlab::task {

class FakeArm final : public Channel {
 public:
  /// `follow`: the fraction of the way to a position command the arm moves in a period (1: all of
  /// it at once; below 1: a first-order lag, as a servo behind its reference).
  FakeArm(std::string name, Eigen::VectorXd q, double follow = 1.0)
      : name_(std::move(name)), q_(std::move(q)), follow_(follow) {
    const int n = static_cast<int>(q_.size());
    state_names_.push_back("status");
    for (const char* g : {"q", "qd", "tau"}) {
      for (int i = 0; i < n; ++i) state_names_.push_back(std::string(g) + "[" + std::to_string(i) + "]");
    }
    command_names_.push_back("mode");
    for (int i = 0; i < n; ++i) command_names_.push_back("value[" + std::to_string(i) + "]");
  }
  const std::string& name() const override { return name_; }
  bridge::DeviceKind kind() const override { return bridge::DeviceKind::kArm; }
  const std::vector<std::string>& state_names() const override { return state_names_; }
  const std::vector<std::string>& command_names() const override { return command_names_; }
  std::vector<std::string> joint_names() const override { return {"S1", "S2", "S3", "E1", "E2", "W1", "W2"}; }
  bool Read(std::vector<double>* v) override {
    v->assign(1 + 3 * q_.size(), 0.0);
    for (int i = 0; i < q_.size(); ++i) (*v)[1 + i] = q_[i];
    return true;
  }
  bool Write(const std::vector<double>& v, std::string*) override {
    if (v[0] == 1) {
      commands_.emplace_back(Eigen::Map<const Eigen::VectorXd>(v.data() + 1, q_.size()));
      if (follow_ == 1.0) {
        q_ = commands_.back();
      } else {
        q_ += follow_ * (commands_.back() - q_);
      }
    }
    history_.push_back(q_);
    return true;
  }
  const Eigen::VectorXd& q() const { return q_; }
  const std::vector<Eigen::VectorXd>& history() const { return history_; }
  /// Every position command, rad, in the order written.
  const std::vector<Eigen::VectorXd>& commands() const { return commands_; }

 private:
  std::string name_;
  Eigen::VectorXd q_;
  double follow_ = 1.0;
  std::vector<Eigen::VectorXd> commands_;
  std::vector<std::string> state_names_, command_names_;
  std::vector<Eigen::VectorXd> history_;
};

class FakeWrench final : public Channel {
 public:
  const std::string& name() const override { return name_; }
  bridge::DeviceKind kind() const override { return bridge::DeviceKind::kWrench; }
  const std::vector<std::string>& state_names() const override { return names_; }
  const std::vector<std::string>& command_names() const override { return none_; }
  bool Read(std::vector<double>* v) override {
    v->assign({force.x(), force.y(), force.z(), torque.x(), torque.y(), torque.z(), 4, 0});
    return true;
  }
  bool Write(const std::vector<double>&, std::string*) override { return false; }
  Eigen::Vector3d force = Eigen::Vector3d(0, 0, 4.1);    // the tool's weight, N (any constant: it is tared)
  Eigen::Vector3d torque = Eigen::Vector3d(0.02, 0, 0);  // its moment, N m (tared as well)

 private:
  std::string name_ = "jr3";
  std::vector<std::string> names_ = {"Fx", "Fy", "Fz", "Mx", "My", "Mz", "filter", "saturated"}, none_;
};

// a gripper that closes at 0.1 m/s toward its set-point and reports a grasp at 0.05 m
class FakeGripper final : public Channel {
 public:
  const std::string& name() const override { return name_; }
  bridge::DeviceKind kind() const override { return bridge::DeviceKind::kGripper; }
  const std::vector<std::string>& state_names() const override { return state_; }
  const std::vector<std::string>& command_names() const override { return command_; }
  bool Read(std::vector<double>* v) override {
    v->assign({0, opening, 0, 0, opening <= 0.05 + 1e-12 ? 1.0 : 0.0});
    return true;
  }
  bool Write(const std::vector<double>& v, std::string*) override {
    commands.push_back(v);
    const double goal = v[0] == 0 ? v[1] : 0.05;  // force mode: closes on a 5 cm object
    opening += std::clamp(goal - opening, -0.1 * kPeriod, 0.1 * kPeriod);
    return true;
  }
  double opening = 0.08;
  std::vector<std::vector<double>> commands;

 private:
  std::string name_ = "gripper";
  std::vector<std::string> state_ = {"status", "opening", "opening_velocity", "force", "grasped"};
  std::vector<std::string> command_ = {"mode", "value"};
};

class FakeDevices final : public Devices {
 public:
  Channel* Find(const std::string& name) override {
    const auto it = channels.find(name);
    return it == channels.end() ? nullptr : it->second;
  }
  std::vector<std::string> Names() const override {
    std::vector<std::string> out;
    for (const auto& [name, c] : channels) out.push_back(name);
    return out;
  }
  std::map<std::string, Channel*> channels;
};

class RuntimeTest : public test::MujocoTest {
 protected:
  void SetUp() override {
    model_ = LoadModel(std::string(VLAB_SOURCE_DIR) + "/scenes/pa10.xml");
    Eigen::VectorXd ready(7);
    ready << 0, 0.523599, 0, 1.047198, 0, 1.570796, 0;
    arm_ = std::make_unique<FakeArm>("pa10", ready);
    arm2_ = std::make_unique<FakeArm>("pa10b", ready);
    devices_.channels = {{"pa10", arm_.get()}, {"pa10b", arm2_.get()}, {"jr3", &wrench_}, {"gripper", &gripper_}};
  }
  // a runtime of one program per script (robot "pa10", then "pa10b", then none)
  std::unique_ptr<Runtime> Make(const std::vector<std::pair<std::string, std::string>>& scripts, std::uint64_t seed = 1,
                                long budget = 1'000'000, const std::map<std::string, std::string>& params = {}) {
    RuntimeConfig c;
    c.period_s = kPeriod;
    c.seed = seed;
    c.instruction_budget = budget;
    c.print = [this](const std::string& who, double t, const std::string& text) {
      printed_.push_back(who + "@" + std::to_string(std::lround(t / kPeriod)) + ": " + text);
    };
    for (const auto& [robot, code] : scripts) {
      const std::string file = dir_ / ((robot.empty() ? "main" : robot) + ".lua");
      testing::WriteFile(file, code);
      ProgramConfig p;
      p.script = file;
      p.robot = robot;
      p.tip_site = robot.empty() ? "" : "tool";
      p.params = params;
      c.programs.push_back(p);
    }
    return Runtime::Create(c, model_, &devices_);
  }
  // steps until every program ended (or `periods` ran); false on an error
  static bool RunFor(Runtime& r, int periods, int* ran = nullptr) {
    for (int k = 0; k < periods; ++k) {
      if (!r.Step(k * kPeriod, nullptr)) return false;
      if (ran) *ran = k + 1;
      if (r.finished()) return true;
    }
    return true;
  }

  mjModel* model_ = nullptr;
  std::unique_ptr<FakeArm> arm_, arm2_;
  FakeWrench wrench_;
  FakeGripper gripper_;
  FakeDevices devices_;
  testing::TempDir dir_;
  std::vector<std::string> printed_;
};

}  // namespace vlab::task
