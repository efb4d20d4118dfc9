#pragma once
// Subcommands of the visproxy CLI. Each adds itself to the app; its callback throws
// visproxy::Error for bad input and stores the process exit code in `exit_code`.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <initializer_list>
#include <map>
#include <string>

#include "visproxy/core/choices.h"

namespace visproxy::cli {

/// Exit codes shared by every subcommand.
enum ExitCode : int { kSuccess = 0, kCheckFailed = 1, kBadInput = 2, kInternalError = 3 };

/// Prints a reader's warning on stderr as "visproxy: warning: WARNING": the
/// WarningHandler of every file the user gives.
void print_warning(const std::string& warning);

/// The CLI11 check and transform of a choice option: the names of choice_names<Enum>
/// (case-insensitive), or only those of `only` when given.
template <class Enum>
CLI::CheckedTransformer choice_transformer(std::initializer_list<Enum> only = {}) {
  std::map<std::string, Enum> names;
  for (const auto& [name, value] : choice_names<Enum>())
    if (only.size() == 0 || std::find(only.begin(), only.end(), value) != only.end()) names.emplace(name, value);
  return CLI::CheckedTransformer(names, CLI::ignore_case);
}

void add_info_command(CLI::App& app, int& exit_code);
void add_build_command(CLI::App& app, int& exit_code);
void add_verify_command(CLI::App& app, int& exit_code);
void add_measure_command(CLI::App& app, int& exit_code);
void add_report_command(CLI::App& app, int& exit_code);
void add_render_command(CLI::App& app, int& exit_code);
void add_generate_command(CLI::App& app, int& exit_code);
void add_compare_command(CLI::App& app, int& exit_code);
void add_batch_command(CLI::App& app, int& exit_code);

}  // namespace visproxy::cli
