#include "core/files.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "core/errors.h"

namespace visproxy {
namespace {

class Files : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_ = std::filesystem::temp_directory_path() /
              ("visproxy-files-" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    std::filesystem::remove_all(folder_);
    std::filesystem::create_directories(folder_);
  }
  void TearDown() override { std::filesystem::remove_all(folder_); }
  std::size_t entries() const {
    return static_cast<std::size_t>(std::distance(std::filesystem::directory_iterator(folder_), {}));
  }
  std::filesystem::path folder_;
};

TEST_F(Files, WriteThenReadReturnsTheSameBytes) {
  const std::string bytes("binary\0data\n", 12);
  write_file_atomically(folder_ / "a.bin", bytes);
  EXPECT_EQ(read_file(folder_ / "a.bin"), bytes);
  write_file_atomically(folder_ / "a.bin", "shorter");
  EXPECT_EQ(read_file(folder_ / "a.bin"), "shorter");
  EXPECT_EQ(entries(), 1u) << "no temporary file is left behind";
}

TEST_F(Files, FailedRenameLeavesNoTemporaryFile) {
  // The bytes reach the temporary file, then the rename onto a non-empty folder fails.
  std::filesystem::create_directories(folder_ / "occupied" / "child");
  try {
    write_file_atomically(folder_ / "occupied", "bytes");
    FAIL() << "wrote over a directory";
  } catch (const IOError& error) {
    EXPECT_NE(std::string(error.what()).find("occupied"), std::string::npos) << error.what();
  }
  EXPECT_EQ(entries(), 1u) << "the temporary file was removed";
}

TEST_F(Files, MissingFolderIsAnIOError) {
  EXPECT_THROW(write_file_atomically(folder_ / "no-such-folder" / "a.txt", "bytes"), IOError);
  EXPECT_EQ(entries(), 0u);
}

TEST_F(Files, ReadErrorsNameTheFile) {
  EXPECT_THROW(read_file(folder_ / "missing"), IOError);
  EXPECT_THROW(read_file(folder_), IOError);  // a directory
  try {
    read_file(folder_ / "missing");
  } catch (const IOError& error) {
    EXPECT_EQ(error.file(), folder_ / "missing");
    EXPECT_NE(std::string(error.what()).find("cannot open"), std::string::npos);
  }
}

}  // namespace
}  // namespace visproxy
