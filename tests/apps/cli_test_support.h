#pragma once
// Runs the visproxy executable as a user would and captures what it prints.

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>

namespace visproxy::testing {

struct CommandResult {
  int exit_code = -1;
  std::string out;  // standard output
  std::string err;  // standard error
};

/// Runs `visproxy ARGUMENTS` through the shell; ARGUMENTS must already be quoted.
inline CommandResult run_visproxy(const std::string& arguments) {
  const auto err_path = std::filesystem::temp_directory_path() /
                        ("visproxy-cli-stderr-" + std::to_string(::getpid()) + ".txt");
  const std::string command = std::string("'") + VISPROXY_CLI + "' " + arguments + " 2>'" + err_path.string() + "'";
  CommandResult result;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return result;
  std::array<char, 4096> buffer{};
  for (std::size_t got; (got = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0;) result.out.append(buffer.data(), got);
  const int status = ::pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (FILE* err = std::fopen(err_path.c_str(), "rb")) {
    for (std::size_t got; (got = std::fread(buffer.data(), 1, buffer.size(), err)) > 0;) result.err.append(buffer.data(), got);
    std::fclose(err);
  }
  std::filesystem::remove(err_path);
  return result;
}

}  // namespace visproxy::testing
