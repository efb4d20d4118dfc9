// visproxy: build, verify and measure visibility proxies of triangle meshes.

#include <cstdio>
#include <exception>
#include <iostream>

#include "commands.h"
#include "core/errors.h"

namespace visproxy::cli {

void print_warning(const std::string& warning) { std::cerr << "visproxy: warning: " << warning << "\n"; }

}  // namespace visproxy::cli

int main(int argc, char** argv) {
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
  add_render_command(app, exit_code);
  add_generate_command(app, exit_code);
  add_compare_command(app, exit_code);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    if (error.get_exit_code() == 0) return app.exit(error);  // --help, --version
    std::cerr << "visproxy: " << error.what() << " (see 'visproxy --help')\n";
    return kBadInput;
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
