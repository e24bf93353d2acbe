#include "exabricks/core/log.h"
#include "exabricks/core/math.h"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

using namespace exa;

TEST(Math, BoxAndVectorBasics) {
  box3i b;
  EXPECT_TRUE(b.empty());
  b.extend(vec3i(1, 2, 3));
  b.extend(vec3i(4, 6, 8));
  EXPECT_EQ(b.size(), vec3i(3, 4, 5));
  EXPECT_EQ(argMax(b.size()), 2);
  EXPECT_EQ(argMax(vec3i(5, 5, 1)), 0);
  EXPECT_FLOAT_EQ(length(vec3f(3, 4, 0)), 5.f);
  EXPECT_EQ(cross(vec3f(1, 0, 0), vec3f(0, 1, 0)), vec3f(0, 0, 1));
}

TEST(Math, WorldTransformRoundTrips) {
  WorldTransform t{vec3d(-1, 2, 0.5), vec3d(0.25, 2, 1)};
  const vec3d p(3, -4, 7);
  const vec3d back = t.toLattice(t.toWorld(p));
  EXPECT_DOUBLE_EQ(back.x, p.x);
  EXPECT_DOUBLE_EQ(back.y, p.y);
  EXPECT_DOUBLE_EQ(back.z, p.z);
  EXPECT_FALSE(t.isIdentity());
  EXPECT_TRUE(WorldTransform{}.isIdentity());
}

TEST(Math, RangeExtend) {
  range1f r;
  EXPECT_TRUE(r.empty());
  r.extend(2.f);
  r.extend(-1.f);
  EXPECT_EQ(r.lower, -1.f);
  EXPECT_EQ(r.upper, 2.f);
}

TEST(Log, LongWorkSaysItsProgressWhereStderrIsNoTerminal) {
  // Captured stderr is a file: after 5 s a line with the fraction, the time and the time left,
  // even though the work did not advance meanwhile; one line when it ends. Quiet says nothing.
  testing::internal::CaptureStderr();
  {
    Progress p("waiting", 4);
    p.advance(1);
    std::this_thread::sleep_for(std::chrono::milliseconds(6500));
    p.advance(1);
  }
  const std::string said = testing::internal::GetCapturedStderr();
  EXPECT_NE(said.find("exabricks: waiting: 25.0 % after "), std::string::npos) << said;
  EXPECT_NE(said.find("s left"), std::string::npos) << said;
  EXPECT_NE(said.find("exabricks: waiting: done in "), std::string::npos) << said;
  // Short work says nothing.
  testing::internal::CaptureStderr();
  {
    Progress p("quick", 2);
    p.advance(2);
  }
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
  setLogLevel(LogLevel::Quiet);
  testing::internal::CaptureStderr();
  {
    Progress p("silent", 2);
    std::this_thread::sleep_for(std::chrono::milliseconds(5500));
  }
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
  setLogLevel(LogLevel::Warning);
}
