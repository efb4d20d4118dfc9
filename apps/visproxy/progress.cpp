#include "progress.h"

#include <unistd.h>

#include <cstdio>

#include "commands.h"

namespace visproxy {

template <>
const std::vector<std::pair<std::string_view, cli::ProgressMode>>& choice_names<cli::ProgressMode>() {
  static const std::vector<std::pair<std::string_view, cli::ProgressMode>> names{
      {"auto", cli::ProgressMode::automatic}, {"always", cli::ProgressMode::always}, {"never", cli::ProgressMode::never}};
  return names;
}

namespace cli {

void add_progress_option(CLI::App* command, ProgressMode& mode) {
  as_choice<ProgressMode>(command->add_option(
      "--progress", mode,
      "Progress of the long steps on stderr (step i/N, share done, time left): auto on a terminal only, always also as "
      "plain lines in a log, never [default: auto]"));
}

Progress::Progress(std::string command, std::size_t total, ProgressMode mode)
    : command_(std::move(command)), total_(total), start_(std::chrono::steady_clock::now()) {
  terminal_ = ::isatty(STDERR_FILENO) != 0;
  shown_ = mode == ProgressMode::always || (mode == ProgressMode::automatic && terminal_);
}

Progress::~Progress() { clear(); }

void Progress::clear() {
  const std::lock_guard lock(mutex_);
  if (shown_ && terminal_ && started_ > 0) std::fprintf(stderr, "\r\033[K");
}

void Progress::step(std::string_view what) {
  const std::lock_guard lock(mutex_);
  const std::size_t done = started_++;
  if (!shown_) return;
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double share = total_ > 0 ? static_cast<double>(done) / static_cast<double>(total_) : 0.0;
  std::string left;
  if (done > 0 && total_ >= done) {
    char text[64];
    std::snprintf(text, sizeof text, ", about %.1f s left", elapsed * static_cast<double>(total_ - done) / static_cast<double>(done));
    left = text;
  }
  std::fprintf(stderr, "%s%s: %zu/%zu (%.0f %% done) %.*s, %.1f s so far%s%s", terminal_ ? "\r\033[K" : "", command_.c_str(),
               done + 1, total_, 100 * share, static_cast<int>(what.size()), what.data(), elapsed, left.c_str(),
               terminal_ ? "" : "\n");
  std::fflush(stderr);
}

}  // namespace cli
}  // namespace visproxy
