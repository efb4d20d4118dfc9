#include "core/errors.h"

namespace visproxy {
namespace {

std::string located(const std::filesystem::path& file, std::uint64_t line, std::string_view problem) {
  std::string message = file.string();
  if (line > 0) message += ":" + std::to_string(line);
  message += ": ";
  message += problem;
  return message;
}

}  // namespace

InvalidInputError::InvalidInputError(const std::filesystem::path& file, std::string_view problem,
                                     std::uint64_t line)
    : Error(located(file, line, problem)), file_(file), line_(line), problem_(problem) {}

IOError::IOError(const std::filesystem::path& file, std::string_view problem)
    : Error(located(file, 0, problem)), file_(file) {}

}  // namespace visproxy
