#include "visproxy/core/files.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "visproxy/core/errors.h"
#include "test_support.h"

namespace visproxy {
namespace {

using Files = testing::ScratchFolder;

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
