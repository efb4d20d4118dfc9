// visproxy report DIR

#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "visproxy/evaluate/proxy_folder.h"
#include "visproxy/evaluate/report.h"

namespace visproxy::cli {

void add_report_command(CLI::App& app, int& exit_code) {
  auto folder = std::make_shared<std::filesystem::path>();
  CLI::App* command = app.add_subcommand(
      "report",
      "Write DIR/report.md and a self-contained DIR/report.html (sortable table, one row per proxy: kind, primitives, "
      "build time, verdict, f_hit, f_miss, V_avg, GSSA ratio, p1/p2/p3, variance, cost ratio) and DIR/f_miss.svg "
      "(f_miss against primitive count) from DIR/manifest.json. Run 'verify' and 'measure' first to fill the columns.");
  command->add_option("dir", *folder, "Proxy folder written by 'visproxy build'")->required();
  command->callback([folder, &exit_code] {
    const nlohmann::json manifest = read_manifest(*folder);
    write_report(*folder, manifest);
    std::printf("visproxy report: %zu proxies of %s\n  %s\n  %s\n  %s\n", manifest["proxies"].size(),
                manifest["mesh"]["path"].get<std::string>().c_str(), (*folder / "report.html").string().c_str(),
                (*folder / "report.md").string().c_str(), (*folder / "f_miss.svg").string().c_str());
    exit_code = kSuccess;
  });
}

}  // namespace visproxy::cli
