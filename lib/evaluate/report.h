#pragma once
// `visproxy report`: the proxy folder as a document a person reads.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <cmath>
#include <string>
#include <vector>

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

/// Text with the characters HTML reserves (< > & ") escaped.
std::string escape_html(const std::string& text);

/// One cell of a sortable HTML table: the text a person reads, the number it sorts by (NaN:
/// by the text), right-aligned when a number, an optional CSS class ("fails") and link.
struct HtmlCell {
  std::string text;
  double sort_value = std::nan("");
  bool number = false;
  std::string css_class;
  std::string link;
};

/// A self-contained HTML page (no external file, script or font): the title, the HTML
/// before the table, a table sortable by any column (click a header; the table's
/// data-sortable attribute reads "ready" once the script ran), the HTML after it.
std::string sortable_table_page(const std::string& title, const std::string& before_table,
                                const std::vector<std::string>& headers, const std::vector<std::vector<HtmlCell>>& rows,
                                const std::string& after_table);

/// Writes report.md, report.html and f_miss.svg into `folder`, each atomically.
void write_report(const std::filesystem::path& folder, const nlohmann::json& manifest);

}  // namespace visproxy
