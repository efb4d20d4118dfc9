#include "visproxy/core/errors.h"

namespace visproxy {

std::string located_message(const std::filesystem::path& file, std::string_view problem, std::uint64_t line) {
  if (file.empty() && line == 0) return std::string(problem);  // not about a file: the problem alone
  std::string message = file.string();
  if (line > 0) message += ":" + std::to_string(line);
  message += ": ";
  message += problem;
  return message;
}

InvalidInputError::InvalidInputError(const std::filesystem::path& file, std::string_view problem, std::uint64_t line)
    : Error(located_message(file, problem, line)), file_(file), line_(line), problem_(problem) {}

IOError::IOError(const std::filesystem::path& file, std::string_view problem)
    : Error(located_message(file, problem)), file_(file) {}

}  // namespace visproxy
