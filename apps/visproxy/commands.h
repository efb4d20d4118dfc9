#pragma once
// Subcommands of the visproxy CLI. Each adds itself to the app; its callback throws
// visproxy::Error for bad input and stores the process exit code in `exit_code`.

#include <CLI/CLI.hpp>
#include <string>

namespace visproxy::cli {

/// Exit codes shared by every subcommand.
enum ExitCode : int { kSuccess = 0, kCheckFailed = 1, kBadInput = 2, kInternalError = 3 };

/// Prints a reader's warning on stderr as "visproxy: warning: WARNING": the
/// WarningHandler of every file the user gives.
void print_warning(const std::string& warning);

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
