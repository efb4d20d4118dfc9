#pragma once
// Typed errors that visproxy reports to users. Every message names the file and what
// is wrong with it, on one line; the CLI prints what() and exits with code 2.

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

namespace visproxy {

/// Base of every error caused by the user's input or environment (not a programming error).
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A file's content is not acceptable: malformed, truncated, out of range, non-finite.
/// what() reads "FILE: problem" or, for text formats, "FILE:LINE: problem".
class InvalidInputError : public Error {
 public:
  InvalidInputError(const std::filesystem::path& file, std::string_view problem, std::uint64_t line = 0);
  const std::filesystem::path& file() const noexcept { return file_; }
  std::uint64_t line() const noexcept { return line_; }
  /// What is wrong, without the location.
  const std::string& problem() const noexcept { return problem_; }

 private:
  std::filesystem::path file_;
  std::uint64_t line_;
  std::string problem_;
};

/// A file could not be opened, read, created or renamed. what() reads "FILE: problem".
class IOError : public Error {
 public:
  IOError(const std::filesystem::path& file, std::string_view problem);
  const std::filesystem::path& file() const noexcept { return file_; }

 private:
  std::filesystem::path file_;
};

}  // namespace visproxy
