// visproxy batch LIST -o DIR [--proxy SPEC]... [--shard I/N] [--jobs J] [--rays N] [--seed S] [--retry-failed]
// visproxy batch --merge DIR
//
// Each asset runs in a child process (this program again, `batch --one`), so a crash or an
// exhausted memory takes down one asset, not the batch: the parent records the failure.

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "commands.h"
#include "visproxy/core/errors.h"
#include "visproxy/evaluate/batch.h"
#include "visproxy/proxy/proxy_spec.h"

extern char** environ;

namespace visproxy::cli {
namespace {

struct BatchCommandOptions {
  std::filesystem::path list;
  std::filesystem::path folder;
  std::filesystem::path merge;
  std::filesystem::path one;  // internal: process this one asset in this process
  std::string shard = "0/1";
  std::size_t jobs = 1;
  bool retry_failed = false;
  BatchOptions batch;
};

std::string clock_text(double seconds) {
  const auto s = static_cast<long long>(seconds + 0.5);
  char text[32];
  if (s >= 3600) std::snprintf(text, sizeof text, "%lld:%02lld:%02lld", s / 3600, s / 60 % 60, s % 60);
  else std::snprintf(text, sizeof text, "%lld:%02lld", s / 60, s % 60);
  return text;
}

void draw_progress(std::size_t done, std::size_t total, std::size_t failed, double elapsed) {
  const double fraction = total > 0 ? static_cast<double>(done) / static_cast<double>(total) : 1.0;
  const int filled = static_cast<int>(30 * fraction);
  const std::string eta = done > 0 && done < total ? ", ETA " + clock_text(elapsed / static_cast<double>(done) * static_cast<double>(total - done)) : "";
  std::fprintf(stderr, "\r\033[Kvisproxy batch: [%s%s] %zu/%zu assets, %zu failed, %s%s",
               std::string(static_cast<std::size_t>(filled), '#').c_str(), std::string(static_cast<std::size_t>(30 - filled), '.').c_str(),
               done, total, failed, clock_text(elapsed).c_str(), eta.c_str());
}

std::string describe(const nlohmann::json& record) {
  const std::string status = record.value("status", "failed");
  char text[160];
  if (status == "failed") return "failed: " + record.value("error", std::string("?"));
  std::snprintf(text, sizeof text, "%s: %d of %d claims hold, %.1f s%s", status.c_str(), record.value("claims_holding", 0),
                record.value("proxies", 0), record.value("seconds", 0.0), record.value("resumed", false) ? " (done before)" : "");
  return text;
}

// The child's command line: this program, `batch --one MESH -o DIR` and the batch options.
std::vector<std::string> child_arguments(const BatchCommandOptions& options, const std::filesystem::path& mesh) {
  std::vector<std::string> args{"visproxy", "batch", "--one", mesh.string(), "-o", options.folder.string()};
  for (const std::string& proxy : options.batch.proxies) args.insert(args.end(), {"--proxy", proxy});
  args.insert(args.end(), {"--seed", std::to_string(options.batch.seed), "--rays", std::to_string(options.batch.rays),
                           "--timed-rays", std::to_string(options.batch.timed_rays), "--hausdorff-samples",
                           std::to_string(options.batch.hausdorff_samples), "--gssa-lines", std::to_string(options.batch.gssa_lines)});
  if (options.retry_failed) args.push_back("--retry-failed");
  return args;
}

pid_t spawn_child(const std::vector<std::string>& args, const std::filesystem::path& log) {
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = 0;
  const int status = posix_spawn(&pid, "/proc/self/exe", &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (status != 0) throw Error("visproxy batch: cannot start a worker process: " + std::string(std::strerror(status)));
  return pid;
}

int run_batch(const BatchCommandOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const auto [index, count] = parse_shard(options.shard);
  const std::vector<std::filesystem::path> all = read_asset_list(options.list);
  const std::vector<std::filesystem::path> assets = shard_assets(all, index, count);
  std::filesystem::create_directories(options.folder / "logs");
  std::printf("visproxy batch: %zu of the %zu assets of %s (shard %zu/%zu) into %s, %zu job%s, seed %llu\n", assets.size(),
              all.size(), options.list.string().c_str(), index, count, options.folder.string().c_str(), options.jobs,
              options.jobs == 1 ? "" : "s", static_cast<unsigned long long>(options.batch.seed));
  std::fflush(stdout);
  const bool terminal = ::isatty(STDERR_FILENO);
  std::size_t done = 0, failed = 0, next = 0;
  // An asset's folder name hashes its bytes: computed once per asset, kept with it.
  struct Asset {
    std::filesystem::path mesh;
    std::string name;
  };
  auto finish = [&](const Asset& asset, const nlohmann::json& record) {
    ++done;
    if (record.value("status", "failed") != "ok") ++failed;
    if (terminal) std::fprintf(stderr, "\r\033[K");
    std::printf("visproxy batch: [%zu/%zu] %s -> %s: %s\n", done, assets.size(), asset.mesh.string().c_str(),
                (options.folder / (record["folder"].is_string() ? record["folder"].get<std::string>() : asset.name + ".failed.json"))
                    .string().c_str(),
                describe(record).c_str());
    std::fflush(stdout);
    if (terminal) draw_progress(done, assets.size(), failed, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  };
  std::map<pid_t, Asset> running;
  while (next < assets.size() || !running.empty()) {
    while (next < assets.size() && running.size() < options.jobs) {
      const Asset asset{assets[next], asset_folder_name(assets[next], options.batch)};
      ++next;
      nlohmann::json record = find_asset_record(options.folder, asset.name);
      if (!record.is_null() && (record.value("status", "") != "failed" || !options.retry_failed)) {
        record["resumed"] = true;
        finish(asset, record);
        continue;
      }
      running[spawn_child(child_arguments(options, asset.mesh), options.folder / "logs" / (asset.name + ".log"))] = asset;
    }
    if (running.empty()) break;
    int status = 0;
    const pid_t pid = ::waitpid(-1, &status, 0);
    if (pid < 0) throw Error("visproxy batch: waiting for a worker failed: " + std::string(std::strerror(errno)));
    const auto it = running.find(pid);
    if (it == running.end()) continue;
    const Asset asset = it->second;
    running.erase(it);
    // The worker writes the record; none means it died before it could.
    nlohmann::json record = find_asset_record(options.folder, asset.name);
    if (record.is_null()) {
      const std::string why = WIFSIGNALED(status) ? "the worker was ended by signal " + std::to_string(WTERMSIG(status)) +
                                                        " (" + strsignal(WTERMSIG(status)) + ")"
                                                  : "the worker exited with code " + std::to_string(WEXITSTATUS(status));
      record = record_failure(asset.mesh, options.folder, asset.name, options.batch,
                              asset.mesh.string() + ": " + why + " before recording the asset; its log: " +
                                  (options.folder / "logs" / (asset.name + ".log")).string());
    }
    finish(asset, record);
  }
  if (terminal) std::fprintf(stderr, "\r\033[K");
  const nlohmann::json summary = batch_merge(options.folder);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("visproxy batch: %zu assets processed in %.1f s, %zu not ok. Summary of all %zu assets in %s: %s, %s, %s\n",
              assets.size(), seconds, failed, summary["assets"].get<std::size_t>(), options.folder.string().c_str(),
              (options.folder / "summary.json").string().c_str(), (options.folder / "summary.csv").string().c_str(),
              (options.folder / "summary.html").string().c_str());
  return failed == 0 ? kSuccess : kCheckFailed;
}

}  // namespace

void add_batch_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<BatchCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "batch",
      "Process an asset library: for every mesh of LIST (a text file of paths, or a folder searched for meshes) build, "
      "verify and measure its proxies and write its report into DIR/STEM-KEY (KEY: a hash of the mesh bytes, the options "
      "and visproxy's version), each asset in its own worker process. Complete folders are skipped, so a stopped run "
      "resumes; a failing asset is recorded in DIR/STEM-KEY.failed.json with its one-line error and the batch goes on. "
      "--shard I/N takes every N-th asset from the I-th (0-based), for job arrays and GNU parallel. Ends by writing "
      "DIR/summary.json, summary.csv and summary.html over every asset in DIR (all shards); --merge DIR only writes "
      "them. Exits 0 when every asset of this run is ok, 1 when one failed or has a failing claim.");
  command->add_option("list", options->list, "Text file of mesh paths (one per line, relative to the file; # comments) or a folder");
  command->add_option("-o,--output", options->folder, "Batch folder (created if missing)");
  command->add_option("--merge", options->merge, "Only write the summary of the batch folder DIR (from every shard's records)");
  command->add_option("--one", options->one, "Process one asset in this process (what each worker runs)")->group("");
  command->add_option("--proxy", options->batch.proxies,
                      "Proxy to build (repeatable), as for 'visproxy build'. Default: its default set, with its notes (inside:40 only for closed meshes, no proxy over 10 % of the mesh)");
  command->add_option("--shard", options->shard, "This run's share of LIST: I/N, 0 <= I < N [default: 0/1, everything]");
  command->add_option("--jobs,-j", options->jobs, "Assets processed at once, each in its own process [default: 1]")
      ->check(CLI::Range(std::size_t{1}, std::size_t{256}));
  command->add_option("--seed", options->batch.seed, "Seed of every random choice of build, verify and measure [default: 1]");
  command->add_option("--rays", options->batch.rays, "Isotropic lines per asset for measure [default: 200000]")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1'000'000'000}));
  command->add_option("--timed-rays", options->batch.timed_rays, "Of them, lines timed on one core for the cost per ray [default: 50000]")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1'000'000'000}));
  command->add_option("--hausdorff-samples", options->batch.hausdorff_samples, "Samples per surface for the Hausdorff error [default: 20000]")
      ->check(CLI::Range(std::size_t{100}, std::size_t{100'000'000}));
  command->add_option("--gssa-lines", options->batch.gssa_lines, "Isotropic lines for the GSSA ratio of sphere proxies [default: 100000]")
      ->check(CLI::Range(std::size_t{1000}, std::size_t{100'000'000}));
  command->add_flag("--retry-failed", options->retry_failed, "Process assets again whose failure is recorded");

  command->callback([options, &exit_code] {
    if (!options->merge.empty()) {
      if (!options->list.empty() || !options->folder.empty())
        throw CLI::ValidationError("--merge", "takes no LIST and no -o");
      const nlohmann::json summary = batch_merge(options->merge);
      std::printf("visproxy batch --merge: %zu assets in %s (%zu ok, %zu with a failing claim, %zu failed, %zu proxies): %s, %s, %s\n",
                  summary["assets"].get<std::size_t>(), options->merge.string().c_str(), summary["ok"].get<std::size_t>(),
                  summary["claims_failed"].get<std::size_t>(), summary["failed"].get<std::size_t>(),
                  summary["proxies"].get<std::size_t>(), (options->merge / "summary.json").string().c_str(),
                  (options->merge / "summary.csv").string().c_str(), (options->merge / "summary.html").string().c_str());
      exit_code = kSuccess;
      return;
    }
    if (options->folder.empty()) throw CLI::ValidationError("-o", "batch needs -o DIR (or --merge DIR)");
    // Specs are checked before any asset is read: a bad one fails the run, not every asset.
    if (!options->batch.proxies.empty()) (void)parse_proxy_specs(options->batch.proxies);
    if (!options->one.empty()) {
      (void)process_asset(options->one, options->folder, options->batch, options->retry_failed);
      exit_code = kSuccess;  // the record it wrote says how the asset went
      return;
    }
    if (options->list.empty()) throw CLI::ValidationError("list", "batch needs LIST (a text file of mesh paths or a folder)");
    exit_code = run_batch(*options);
  });
}

}  // namespace visproxy::cli
