#pragma once
// Helpers shared by the test suites: scratch folders and readable parameter names.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>

namespace visproxy::testing {

/// A fresh, empty folder for one test, removed when the test ends. The name holds the
/// process id, so tests that CTest runs in parallel never share one.
class ScratchFolder : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_ = std::filesystem::temp_directory_path() /
              ("visproxy-" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "-" +
               std::to_string(::getpid()));
    std::filesystem::remove_all(folder_);
    std::filesystem::create_directories(folder_);
  }
  void TearDown() override { std::filesystem::remove_all(folder_); }
  std::size_t entries() const {
    return static_cast<std::size_t>(std::distance(std::filesystem::directory_iterator(folder_), {}));
  }
  std::filesystem::path folder_;
};

/// A parameterised test's name made from a file name: every character that is not a
/// letter or digit becomes '_'.
inline std::string test_name_from(std::string text) {
  for (char& c : text)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return text;
}

/// Whether the closed segment from `from` to `to` meets the axis-aligned box [lo, hi]: the
/// slab test, an independent answer for checks of other segment queries.
template <typename Point>
bool segment_meets_box(const Point& from, const Point& to, const Point& lo, const Point& hi) {
  double enter = 0, leave = 1;
  for (int a = 0; a < 3; ++a) {
    const double d = to[a] - from[a];
    if (d == 0) {
      if (from[a] < lo[a] || from[a] > hi[a]) return false;
      continue;
    }
    double t0 = (lo[a] - from[a]) / d, t1 = (hi[a] - from[a]) / d;
    if (t0 > t1) std::swap(t0, t1);
    enter = std::max(enter, t0), leave = std::min(leave, t1);
  }
  return enter <= leave;
}

}  // namespace visproxy::testing
