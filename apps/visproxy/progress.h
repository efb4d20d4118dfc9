#pragma once
// Progress of a command's long steps on stderr: on a terminal one line rewritten in place,
// in a log (stderr not a terminal, --progress always) one plain line per step.

#include <chrono>
#include <cstddef>
#include <mutex>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "visproxy/core/choices.h"

namespace visproxy::cli {

/// auto: on a terminal only; always: also as plain lines when stderr is a file or a pipe;
/// never: not at all.
enum class ProgressMode { automatic, always, never };

/// Adds --progress {auto, always, never} to `command` (default auto).
void add_progress_option(CLI::App* command, ProgressMode& mode);

class Progress {
 public:
  /// `command` names the lines ("visproxy build"); `total` is the number of steps.
  Progress(std::string command, std::size_t total, ProgressMode mode);
  /// Clears the terminal line.
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  /// Step i of total starts: "visproxy build: 3/10 (20 % done) hull:32, 1.4 s so far, about
  /// 5.6 s left". Safe to call from several threads; steps are counted in call order.
  void step(std::string_view what);

  /// Clears the terminal's progress line, before other output shares the terminal.
  void clear();

 private:
  std::string command_;
  std::size_t total_;
  std::size_t started_ = 0;
  bool shown_ = false, terminal_ = false;
  std::chrono::steady_clock::time_point start_;
  std::mutex mutex_;
};

}  // namespace visproxy::cli

namespace visproxy {
template <>
const std::vector<std::pair<std::string_view, cli::ProgressMode>>& choice_names<cli::ProgressMode>();
}  // namespace visproxy
