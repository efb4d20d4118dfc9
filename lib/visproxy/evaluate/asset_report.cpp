#include "visproxy/evaluate/asset_report.h"

#include <algorithm>
#include <array>
#include <string>
#include <vector>

#include "visproxy/core/files.h"
#include "visproxy/evaluate/recommendation.h"
#include "visproxy/folder/asset_folder.h"

namespace visproxy {
namespace {

using json = nlohmann::json;

}  // namespace

json write_asset_report(const std::filesystem::path& folder, const std::filesystem::path& asset,
                        const ReportOptions& options, const std::function<void(std::string_view)>& on_part) {
  const BuiltParts built = read_built_parts(folder, asset);
  const std::filesystem::path& source = built.source;
  std::array<std::string, 3> uses;
  for (std::size_t u = 0; u < kProxyUses.size(); ++u) uses[u] = use_key(kProxyUses[u]);

  json rows = json::array();
  std::size_t total = 0;
  std::array<std::size_t, 3> shipped{};
  for (const BuiltPart& part : built.parts) {
    const std::string& name = part.name;
    if (on_part) on_part(name);
    const json& manifest = part.manifest;
    const ReportFigures figures = report_figures(part.mesh, part.folder, manifest, options);
    write_report(part.folder, manifest, figures);
    const std::size_t instances = part.listing.at("instances").size();
    const std::size_t triangles = part.mesh.triangles.size();
    json row = {{"name", name}, {"instances", instances}, {"triangles", triangles}, {"uses", json::object()}};
    total += instances * triangles;
    const bool measured = !figures.recommendation.choices[0].sentence.empty();
    const std::vector<ShippingLine> lines = measured ? shipping_lines(figures, manifest) : std::vector<ShippingLine>{};
    for (std::size_t u = 0; u < uses.size(); ++u) {
      std::string file;
      std::size_t file_triangles = triangles;
      for (const ShippingLine& line : lines)
        if (line.use_key == uses[u] && !line.file.empty()) {
          for (const json& entry : manifest.at("proxies"))
            if (entry.value("file", std::string()) == line.file) {
              file = name + "/" + line.file;
              file_triangles = entry.value("triangles", std::size_t{0});
            }
        }
      row["uses"][uses[u]] = {{"file", file.empty() ? json(nullptr) : json(file)}, {"triangles", file_triangles}};
      shipped[u] += instances * file_triangles;
    }
    row["measured"] = measured;
    rows.push_back(std::move(row));
  }

  json totals = {{"triangles", total}, {"shipped_triangles", json::object()}};
  for (std::size_t u = 0; u < uses.size(); ++u) totals["shipped_triangles"][uses[u]] = shipped[u];
  const json summary = {{"format", "visproxy-asset-recommendation"},
                        {"format_version", 1},
                        {"source", source.string()},
                        {"parts", rows},
                        {"total", totals}};

  std::string md =
      "# visproxy report: " + source.string() + "\n\n" + std::to_string(rows.size()) +
      " meshes, each with its own report (MESH/report.md). Per use, the file to ship for each mesh, or the "
      "mesh itself where no proxy is predicted cheaper or the mesh's proxies are not measured. Triangles "
      "count every node that shows a mesh.\n\n| mesh | instances | triangles |";
  for (const std::string& use : uses) md += " " + use + " |";
  md += "\n|---|---|---|---|---|---|\n";
  for (const json& row : rows) {
    md += "| " + row["name"].get<std::string>() + (row["measured"].get<bool>() ? "" : " (not measured)") + " | " +
          std::to_string(row["instances"].get<std::size_t>()) + " | " +
          std::to_string(row["triangles"].get<std::size_t>()) + " |";
    for (const std::string& use : uses) {
      const json& choice = row["uses"][use];
      md += " " +
            (choice["file"].is_null() ? std::string("the mesh")
                                      : choice["file"].get<std::string>() + " (" +
                                            std::to_string(choice["triangles"].get<std::size_t>()) + ")") +
            " |";
    }
    md += "\n";
  }
  md += "| total | | " + std::to_string(total) + " |";
  for (const std::string& use : uses)
    md += " " + std::to_string(totals["shipped_triangles"][use].get<std::size_t>()) + " triangles |";
  md += "\n";
  write_file_atomically(folder / "report.md", md);
  write_file_atomically(folder / "recommendation.json", summary.dump(2) + "\n");
  return summary;
}

}  // namespace visproxy
