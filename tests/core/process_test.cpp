#include "visproxy/core/process.h"

#include <gtest/gtest.h>

#include <cstdlib>

#if defined(__linux__)
#include <sys/prctl.h>
#endif

namespace visproxy {
namespace {

#if defined(__linux__) && defined(PR_GET_THP_DISABLE)
// The process's setting as the kernel reports it, restored when the test ends.
class TransparentHugePages : public ::testing::Test {
 protected:
  void SetUp() override { before_ = prctl(PR_GET_THP_DISABLE, 0, 0, 0, 0); }
  void TearDown() override {
    prctl(PR_SET_THP_DISABLE, before_, 0, 0, 0);
    unsetenv("VISPROXY_TRANSPARENT_HUGE_PAGES");
  }
  static int disabled() { return prctl(PR_GET_THP_DISABLE, 0, 0, 0, 0); }
  int before_ = 0;
};

TEST_F(TransparentHugePages, AreTurnedOffForTheProcess) {
  ASSERT_EQ(prctl(PR_SET_THP_DISABLE, 0, 0, 0, 0), 0);
  unsetenv("VISPROXY_TRANSPARENT_HUGE_PAGES");
  EXPECT_TRUE(disable_transparent_huge_pages());
  EXPECT_EQ(disabled(), 1);
}

TEST_F(TransparentHugePages, StayOnWhenTheEnvironmentAsks) {
  ASSERT_EQ(prctl(PR_SET_THP_DISABLE, 0, 0, 0, 0), 0);
  setenv("VISPROXY_TRANSPARENT_HUGE_PAGES", "1", 1);
  EXPECT_FALSE(disable_transparent_huge_pages());
  EXPECT_EQ(disabled(), 0);
  // Any other value turns them off as usual.
  setenv("VISPROXY_TRANSPARENT_HUGE_PAGES", "yes", 1);
  EXPECT_TRUE(disable_transparent_huge_pages());
  EXPECT_EQ(disabled(), 1);
}
#endif

}  // namespace
}  // namespace visproxy
