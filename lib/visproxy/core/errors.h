#pragma once
// Typed errors that visproxy reports to users. Every message names the file and what
// is wrong with it, on one line; the CLI prints what() and exits with code 2. Warnings
// (input read despite a harmless flaw) go to a WarningHandler the caller passes in.

#include <cstdint>
#include <filesystem>
#include <functional>
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

/// An option's value is not acceptable (a command-line option, a Python keyword, a field
/// of a job): what() reads "OPTION: problem". An InvalidInputError whose "file" is the option.
class OptionError : public InvalidInputError {
 public:
  OptionError(std::string_view option, std::string_view problem) : InvalidInputError(std::filesystem::path(option), problem) {}
};

/// A file could not be opened, read, created or renamed. what() reads "FILE: problem".
class IOError : public Error {
 public:
  IOError(const std::filesystem::path& file, std::string_view problem);
  const std::filesystem::path& file() const noexcept { return file_; }

 private:
  std::filesystem::path file_;
};

/// A located message as errors and warnings print it: "FILE: problem", or "FILE:LINE:
/// problem" when `line` is not 0; the problem alone when there is no file (an option).
std::string located_message(const std::filesystem::path& file, std::string_view problem, std::uint64_t line = 0);

/// Receives a reader's warnings about input it read despite a harmless flaw, one line each
/// in the form of an error's what(): "FILE:LINE: what was ignored". Readers never print;
/// the CLI passes a handler that prints to stderr. An empty handler drops the warnings.
using WarningHandler = std::function<void(const std::string& warning)>;

}  // namespace visproxy
