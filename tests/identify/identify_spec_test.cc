// vlab identify's spec reader.
#include <gtest/gtest.h>

#include "identify/identify_spec.h"

namespace vlab::identify {
namespace {

TEST(IdentifySpec, MatchColumn) {
  EXPECT_TRUE(MatchColumn("pa10.q.*", "pa10.q.S1"));
  EXPECT_FALSE(MatchColumn("pa10.q.*", "pa10.qd.S1"));
  EXPECT_TRUE(MatchColumn("*.S1", "pa10.qd.S1"));
  EXPECT_TRUE(MatchColumn("pa10.q*", "pa10.qd.S1"));
  EXPECT_FALSE(MatchColumn("pa10.q.S1", "pa10.q.S12"));
}

}  // namespace
}  // namespace vlab::identify
