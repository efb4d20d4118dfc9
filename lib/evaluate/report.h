#pragma once
// `visproxy report`: the proxy folder as a document a person reads.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace visproxy {

/// report.md: the mesh summary, the ray set, one table row per proxy (kind, primitives,
/// build time, verdict, f_hit, f_miss, V_avg, GSSA ratio, p1/p2/p3, variance, cost
/// ratio), the column definitions, and a link to the plot.
std::string report_markdown(const nlohmann::json& manifest);

/// report.html: the same, self-contained (no external file, script or font), with a
/// table sortable by any column and the plot inline.
std::string report_html(const nlohmann::json& manifest);

/// An SVG plot of f_miss (with its 95 % interval) against primitive count, log scale,
/// one point per measured proxy, coloured by kind; a note instead of points when no
/// proxy has been measured.
std::string f_miss_plot_svg(const nlohmann::json& manifest);

/// Writes report.md, report.html and f_miss.svg into `folder`, each atomically.
void write_report(const std::filesystem::path& folder, const nlohmann::json& manifest);

}  // namespace visproxy
