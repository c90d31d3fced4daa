// servoj (task_api_servo.cc): one streamed reference per period, sent as the
// arm's command as computed; a reference beyond a joint's range, speed or
// acceleration limit is an error at its line naming the joint.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "task/task_units.h"
#include "task_runtime_fixture.h"

namespace vlab::task {
namespace {

#define EXPECT_HAS(text, part) EXPECT_NE((text).find(part), std::string::npos) << (text)

using ServoTest = RuntimeTest;

TEST_F(ServoTest, StreamsOneReferenceAPeriodAsComputed) {
  // S1: 5·(1 - cos(pi t)) deg over 2 s (at most 15.7 deg/s and 49.3 deg/s²)
  auto r = Make({{"pa10", R"(
local q0 = joints()
for k = 1, 1000 do
  local q = {table.unpack(q0)}
  q[1] = q0[1] + 5 * (1 - math.cos(math.pi * k * PERIOD))
  servoj(q)
end
)"}});
  int ran = 0;
  ASSERT_TRUE(RunFor(*r, 2000, &ran)) << r->error();
  EXPECT_EQ(ran, 1001);  // a reference each period, then the end
  ASSERT_GE(arm_->commands().size(), 1000u);
  for (int k = 1; k <= 1000; k += 111) {
    EXPECT_DOUBLE_EQ(arm_->commands()[k - 1][0], 5 * (1 - std::cos(3.14159265358979323846 * k * kPeriod)) * kDeg) << k;
    EXPECT_DOUBLE_EQ(arm_->commands()[k - 1][3], 1.047198) << k;
  }
}

TEST_F(ServoTest, AfterAMoveTheStreamStartsFromItsEnd) {
  auto r = Make({{"pa10", R"(
movej({0, 30, 0, 60, 0, 90, 10})
local q = planned_joints()
for k = 1, 100 do
  q[7] = q[7] + 0.0001 * k   -- speeding up from rest at 25 deg/s^2
  servoj(q)
end
)"}});
  ASSERT_TRUE(RunFor(*r, 20000)) << r->error();
  EXPECT_NEAR(arm_->commands().back()[6], (10 + 0.0001 * 5050) * kDeg, 1e-12);
}

TEST_F(ServoTest, RefusesAReferenceBeyondALimitNamingTheJoint) {
  // one period's jump of 1 deg: 500 deg/s
  auto jump = Make({{"pa10", "local q = joints()\nq[4] = q[4] + 1\nservoj(q)\n"}});
  EXPECT_FALSE(RunFor(*jump, 10));
  EXPECT_HAS(jump->error(),
             "pa10.lua:3: servoj: joint E1 needs 500 deg/s (from 60 to 61 deg in one period); its "
             "limit is 180 deg/s");
  // 100 deg/s from rest in one period: within the speed limit, 5e4 deg/s² beyond the acceleration's
  auto kick = Make({{"pa10", "local q = joints()\nq[2] = q[2] + 0.2\nservoj(q)\n"}});
  EXPECT_FALSE(RunFor(*kick, 10));
  EXPECT_HAS(kick->error(),
             "pa10.lua:3: servoj: joint S2 needs 50000 deg/s^2 (its speed from 0 to 100 deg/s in one "
             "period); its limit is 180 deg/s^2");
  // beyond the range (S2: +-94 deg)
  auto range = Make({{"pa10", "local q = joints()\nq[2] = 95\nservoj(q)\n"}});
  EXPECT_FALSE(RunFor(*range, 10));
  EXPECT_HAS(range->error(), "pa10.lua:3: servoj: joint S2 = 95 deg is beyond its upper limit 94 deg");
  auto count = Make({{"pa10", "servoj({1, 2, 3})\n"}});
  EXPECT_FALSE(RunFor(*count, 10));
  EXPECT_HAS(count->error(), "servoj: expected 7 joint angles (deg), got 3");
  auto nan = Make({{"pa10", "local q = joints()\nq[5] = 0/0\nservoj(q)\n"}});
  EXPECT_FALSE(RunFor(*nan, 10));
  EXPECT_HAS(nan->error(), "servoj: joint 5 is");
  // the arm kept its last reference: the refused ones were never sent
  for (const Eigen::VectorXd& c : arm_->commands()) EXPECT_NEAR(c[3], 1.047198, 1e-12);
}

}  // namespace
}  // namespace vlab::task
