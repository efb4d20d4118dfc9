#pragma once
// `visproxy report`: the proxy folder as a document a person reads: which proxy to ship
// for each use (recommendation.h), every proxy drawn over the mesh with the shadow it casts
// beside the mesh's (render/proxy_pictures.h), the measured figures in a sortable table,
// and plots of f_miss and of predicted efficiency against primitive count.

#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "visproxy/evaluate/proxy_flags.h"
#include "visproxy/evaluate/recommendation.h"
#include "visproxy/mesh/triangle_mesh.h"
#include "visproxy/render/proxy_pictures.h"

namespace visproxy {

/// One proxy's pictures as PNG files' bytes, and the shadow fractions the difference shows.
struct ProxyPictureFiles {
  std::string overlay_png, shadow_png, difference_png;
  double missed_shadow = 0, extra_shadow = 0;  ///< ProxyPictures' (NaN: the mesh casts no shadow)
};

/// What the report computes from the files rather than reads from the manifest.
struct ReportFigures {
  Recommendation recommendation;
  std::vector<ProxyFlag> flags;  ///< proxy_flags of the manifest
  bool pictured = false;         ///< the pictures were made
  std::string mesh_shadow_png;   ///< the ground with the mesh's shadow
  std::map<std::string, ProxyPictureFiles> pictures;  ///< by proxy name
  ProxyPictureOptions picture_options;
};

/// One line per use in shipping terms, the report's first: "For exact shadow rays through
/// bounds, ship obb.ply (1 box) beside the mesh: shadow rays are predicted 1.06x [1.02,
/// 1.09] cheaper, the shadows unchanged (cast on its own, it would miss 0.0 % of the
/// mesh's shadow and add 31.2 %)." or "..., keep the mesh: no proxy is shown cheaper than
/// it ...". The shadow figures come from the pictures, when they were made.
struct ShippingLine {
  std::string use_key;  ///< use_key of the use
  std::string text;
  std::string file;  ///< relative to the folder; empty: keep the mesh
};
std::vector<ShippingLine> shipping_lines(const ReportFigures& figures, const nlohmann::json& manifest);

/// recommendation.json: recommendation_json with, per use, the shipping line (`ship`) and
/// its `file`, and the flags (proxy_flags) under `flags`.
nlohmann::json report_recommendation_json(const ReportFigures& figures, const nlohmann::json& manifest);

struct ReportOptions {
  bool pictures = true;  ///< render the pictures (a few seconds for a folder of ten proxies)
  ProxyPictureOptions picture_options;
  /// Recommend only proxies of at most this many primitives (0: any), as recommend_proxies.
  std::size_t budget = 0;
};

/// The recommendation and the pictures of every proxy of FOLDER. `mesh` is the mesh the
/// folder was built from (read_manifest_mesh): a proxy's claim counts as proved only when
/// its verdict was made on these very files (verdict_proves), for the recommendation's
/// bounds and for the pictures' rounding pads. Throws InvalidInputError naming a proxy file
/// that cannot be read.
ReportFigures report_figures(const TriangleMesh& mesh, const std::filesystem::path& folder, const nlohmann::json& manifest,
                             const ReportOptions& options = {});

/// report.md: the recommendation, the mesh summary, the ray set, one table row per proxy
/// (kind, primitives, build time, verdict, f_hit, f_miss, V_avg, GSSA ratio, p1/p2/p3,
/// variance, cost ratio), the column definitions, the pictures and the plots by link.
std::string report_markdown(const nlohmann::json& manifest, const ReportFigures& figures = {});

/// report.html: the same, self-contained (no external file, script or font: pictures and
/// plots inline), with a table sortable by any column.
std::string report_html(const nlohmann::json& manifest, const ReportFigures& figures = {});

/// An SVG plot of each proxy's predicted efficiency for each use (with its 95 % interval)
/// against primitive count, log-log, each use's Pareto front joined and labelled, the mesh alone at 1.
std::string efficiency_plot_svg(const nlohmann::json& manifest, const Recommendation& recommendation);

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

/// Writes report.md, report.html, f_miss.svg, efficiency.svg, recommendation.json and the
/// pictures (pictures/mesh-shadow.png, pictures/NAME-overlay.png, -shadow.png and
/// -difference.png) into `folder`, each file atomically.
void write_report(const std::filesystem::path& folder, const nlohmann::json& manifest, const ReportFigures& figures);

/// report_figures, then write_report.
void write_report(const std::filesystem::path& folder, const nlohmann::json& manifest, const TriangleMesh& mesh,
                  const ReportOptions& options = {});

/// The file name pictures of a proxy start with: its name with every character but letters,
/// digits, '.', '-' and '_' replaced by '_'.
std::string picture_stem(const std::string& proxy_name);

}  // namespace visproxy
