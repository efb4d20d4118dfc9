// visproxy: build, verify and measure visibility proxies of triangle meshes.

#include <algorithm>
#include <cstdio>
#include <exception>
#include <iostream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "commands.h"
#include "visproxy/core/errors.h"
#include "visproxy/core/process.h"
#include "visproxy/proxy/build_proxies.h"

namespace visproxy::cli {

void print_warning(const std::string& warning) { std::cerr << "visproxy: warning: " << warning << "\n"; }

}  // namespace visproxy::cli

namespace {

// Optimal string alignment distance: insertions, deletions, substitutions and swaps of
// two adjacent characters ("biuld" is one from "build").
std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i)
    for (std::size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

// The first argument that is not an option names the subcommand, since the top level takes
// only flags; returns it when no subcommand has that name. CLI11 would take an unknown word
// for a stray positional argument and either print the top-level help (with --help) or
// complain that a subcommand is required.
std::optional<std::string> unknown_subcommand(CLI::App& app, int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string argument = argv[i];
    if (argument == "--") return std::nullopt;  // everything after is positional: CLI11's error
    if (argument.size() > 1 && argument.front() == '-') continue;
    for (const CLI::App* command : app.get_subcommands({}))
      if (command->check_name(argument)) return std::nullopt;
    return argument;
  }
  return std::nullopt;
}

// "unknown subcommand 'biuld' (did you mean 'build'?)": the nearest subcommand within two
// edits, when one is nearer than the word is long.
std::string unknown_subcommand_message(CLI::App& app, const std::string& word) {
  std::string nearest;
  std::size_t best = 3;
  for (const CLI::App* command : app.get_subcommands({})) {
    const std::size_t distance = edit_distance(word, command->get_name());
    if (distance < best && distance < word.size()) {
      best = distance;
      nearest = command->get_name();
    }
  }
  std::string shown;  // one line whatever the argument holds
  for (const char c : word) shown += (c >= 0x20 && c < 0x7f) ? c : '?';
  const std::string message = "unknown subcommand '" + shown + "'";
  return nearest.empty() ? message + " (see 'visproxy --help')" : message + " (did you mean '" + nearest + "'?)";
}

// "visproxy generate forest": the deepest subcommand the command line reached, for the
// help an error points at.
std::string command_path(const CLI::App& app) {
  for (const CLI::App* command : app.get_subcommands())
    if (command->parsed()) return app.get_name() + " " + command_path(*command);
  return app.get_name();
}

// Counts and seeds are unsigned; CLI11 would read "-3" as 2^64 - 3. Every unsigned option
// of every subcommand refuses a negative value instead.
void refuse_negative_values(CLI::App& app) {
  for (CLI::Option* option : app.get_options())
    if (option->get_type_name().rfind("UINT", 0) == 0)
      option->check(CLI::Validator(
          [](std::string& text) -> std::string {
            return text.find('-') == std::string::npos ? std::string() : "'" + text + "' is negative";
          },
          "", "non-negative"));
  for (CLI::App* command : app.get_subcommands({})) refuse_negative_values(*command);
}

}  // namespace

int main(int argc, char** argv) {
  visproxy::disable_transparent_huge_pages();  // see visproxy/core/process.h
  using namespace visproxy::cli;
  CLI::App app{"visproxy: visibility proxies for shadow rays (build, verify, measure, validate)", "visproxy"};
  app.set_version_flag("--version", VISPROXY_VERSION);
  app.require_subcommand(1);
  app.footer(
      "Exit codes: 0 success, 1 a check failed, 2 bad usage or bad input, 3 internal error.\n"
      "Run 'visproxy <subcommand> --help' for the options of each subcommand.");

  int exit_code = kSuccess;
  add_info_command(app, exit_code);
  add_build_command(app, exit_code);
  add_verify_command(app, exit_code);
  add_measure_command(app, exit_code);
  add_report_command(app, exit_code);
  add_export_command(app, exit_code);
  add_render_command(app, exit_code);
  add_generate_command(app, exit_code);
  add_compare_command(app, exit_code);
  add_batch_command(app, exit_code);

  refuse_negative_values(app);

  if (const std::optional<std::string> word = unknown_subcommand(app, argc, argv)) {
    std::cerr << "visproxy: " << unknown_subcommand_message(app, *word) << "\n";
    return kBadInput;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    if (error.get_exit_code() == 0) return app.exit(error);  // --help, --version
    std::cerr << "visproxy: " << error.what() << " (see '" << command_path(app) << " --help')\n";
    return kBadInput;
  } catch (const visproxy::OutOfMemoryError& error) {
    std::cerr << "visproxy: " << error.what() << "\n";
    return kInternalError;
  } catch (const visproxy::Error& error) {
    std::cerr << "visproxy: " << error.what() << "\n";
    return kBadInput;
  } catch (const std::bad_alloc&) {
    std::cerr << "visproxy: out of memory\n";
    return kInternalError;
  } catch (const std::exception& error) {
    std::cerr << "visproxy: internal error: " << error.what() << "\n";
    return kInternalError;
  }
  return exit_code;
}
