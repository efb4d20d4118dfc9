#pragma once
// Subcommands of the visproxy CLI. Each adds itself to the app; its callback throws
// visproxy::Error for bad input and stores the process exit code in `exit_code`.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <initializer_list>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "visproxy/core/choices.h"

namespace visproxy::cli {

/// Exit codes shared by every subcommand.
enum ExitCode : int { kSuccess = 0, kCheckFailed = 1, kBadInput = 2, kInternalError = 3 };

/// Prints a reader's warning on stderr as "visproxy: warning: WARNING": the
/// WarningHandler of every file the user gives.
void print_warning(const std::string& warning);

/// Makes `option` a choice of choice_names<Enum> (case-insensitive), or only of those in
/// `only` when given: the help shows "{auto, never, always}", and a bad value is refused as
/// "--weld: 'maybe' is not one of {auto, never, always}".
template <class Enum>
CLI::Option* as_choice(CLI::Option* option, std::initializer_list<Enum> only = {}) {
  std::vector<std::pair<std::string_view, Enum>> names;
  for (const auto& [name, value] : choice_names<Enum>())
    if (only.size() == 0 || std::find(only.begin(), only.end(), value) != only.end()) names.emplace_back(name, value);
  std::string list = "{";
  for (const auto& [name, value] : names) list += (list.size() > 1 ? ", " : "") + std::string(name);
  list += "}";
  option->type_name(list);
  option->transform(CLI::Validator(
      [names, list](std::string& text) -> std::string {
        std::string lower = text;
        for (char& c : lower) c = static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
        for (const auto& [name, value] : names)
          if (lower == name) {
            text = std::to_string(static_cast<std::underlying_type_t<Enum>>(value));  // what CLI11 reads an enum from
            return {};
          }
        return "'" + text + "' is not one of " + list;
      },
      "", "choice"));
  return option;
}

void add_info_command(CLI::App& app, int& exit_code);
void add_build_command(CLI::App& app, int& exit_code);
void add_verify_command(CLI::App& app, int& exit_code);
void add_measure_command(CLI::App& app, int& exit_code);
void add_report_command(CLI::App& app, int& exit_code);
void add_export_command(CLI::App& app, int& exit_code);
void add_render_command(CLI::App& app, int& exit_code);
void add_generate_command(CLI::App& app, int& exit_code);
void add_compare_command(CLI::App& app, int& exit_code);
void add_batch_command(CLI::App& app, int& exit_code);

}  // namespace visproxy::cli
