#pragma once
// Benchmarks that measure one piece of work per process (its own peak memory, a fresh
// heap): this program is run again (fork and exec of /proc/self/exe) with other
// arguments, and the child writes a fixed-size report to descriptor 3.

#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include "visproxy/core/errors.h"

namespace visproxy::bench {

/// How a child ended.
struct ChildRun {
  bool reported = false;  ///< it wrote its whole report
  int status = 0;         ///< as wait4 gives it
  double peak_mb = 0;     ///< its peak resident memory, MiB (getrusage)
};

/// Runs this program with `arguments` (argv[0] first) in a fresh process and reads the
/// `size` bytes of `report` it writes to descriptor 3. With `time_limit` seconds (0: none)
/// it gets SIGALRM then; with `memory_limit_gib` (0: none) its address space is capped.
inline ChildRun run_self(const std::vector<std::string>& arguments, void* report, std::size_t size, int time_limit = 0,
                         double memory_limit_gib = 0) {
  int pipe_ends[2];
  if (::pipe(pipe_ends) != 0) throw Error(std::string("pipe: ") + std::strerror(errno));
  std::fflush(nullptr);
  const pid_t child = ::fork();
  if (child < 0) throw Error(std::string("fork: ") + std::strerror(errno));
  if (child == 0) {
    ::close(pipe_ends[0]);
    if (pipe_ends[1] != 3) ::dup2(pipe_ends[1], 3), ::close(pipe_ends[1]);
    if (memory_limit_gib > 0) {
      const auto bytes = static_cast<rlim_t>(memory_limit_gib * 1024 * 1024 * 1024);
      const rlimit limit{bytes, bytes};
      ::setrlimit(RLIMIT_AS, &limit);
    }
    if (time_limit > 0) ::alarm(static_cast<unsigned>(time_limit));  // kept across exec
    std::vector<const char*> argv;
    for (const std::string& argument : arguments) argv.push_back(argument.c_str());
    argv.push_back(nullptr);
    ::execv("/proc/self/exe", const_cast<char* const*>(argv.data()));
    ::_exit(127);
  }
  ::close(pipe_ends[1]);
  std::size_t got = 0;
  while (got < size) {
    const ssize_t n = ::read(pipe_ends[0], static_cast<char*>(report) + got, size - got);
    if (n <= 0) break;
    got += static_cast<std::size_t>(n);
  }
  ::close(pipe_ends[0]);
  ChildRun run;
  rusage usage{};
  ::wait4(child, &run.status, 0, &usage);
  run.reported = got == size;
  run.peak_mb = static_cast<double>(usage.ru_maxrss) / 1024.0;  // KiB on Linux
  return run;
}

/// The child's side: runs `work`, which fills `report` (a struct with a `char message[]`)
/// and sets its `ok`; a failure is recorded in `report.message` instead ("out of memory",
/// "failed: WHAT"). The report is written to descriptor 3 either way. Returns the child's
/// exit code, 0.
template <typename Report, typename Work>
int report_to_parent(Report& report, Work work) {
  try {
    work();
  } catch (const std::bad_alloc&) {
    std::snprintf(report.message, sizeof report.message, "out of memory");
  } catch (const std::exception& e) {
    std::snprintf(report.message, sizeof report.message, "failed: %s", e.what());
  }
  [[maybe_unused]] const ssize_t written = ::write(3, &report, sizeof report);
  return 0;
}

/// Why a child that wrote no report ended: out of time (SIGALRM after `time_limit` s),
/// killed (the system's out-of-memory killer, most likely), or crashed.
inline std::string child_failure(const ChildRun& run, int time_limit) {
  if (WIFSIGNALED(run.status) && WTERMSIG(run.status) == SIGALRM)
    return "out of time (" + std::to_string(time_limit) + " s)";
  if (WIFSIGNALED(run.status) && WTERMSIG(run.status) == SIGKILL) return "killed (out of memory?)";
  return "crashed: " + std::string(WIFSIGNALED(run.status) ? strsignal(WTERMSIG(run.status)) : "no report");
}

}  // namespace visproxy::bench
