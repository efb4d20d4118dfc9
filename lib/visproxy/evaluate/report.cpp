#include "visproxy/evaluate/report.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"
#include "visproxy/evaluate/measure_proxies.h"
#include "visproxy/evaluate/plot.h"
#include "visproxy/folder/proxy_folder.h"
#include "visproxy/folder/verdict.h"
#include "visproxy/image/image.h"

namespace visproxy {
namespace {

using nlohmann::json;

std::string format(const char* pattern, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, pattern, value);
  return buffer;
}

const json* find(const json& object, std::initializer_list<const char*> path) {
  const json* node = &object;
  for (const char* key : path) {
    if (!node->is_object() || !node->contains(key) || (*node)[key].is_null()) return nullptr;
    node = &(*node)[key];
  }
  return node;
}

double number(const json& object, std::initializer_list<const char*> path, double missing = std::nan("")) {
  const json* node = find(object, path);
  return node && node->is_number() ? node->get<double>() : missing;
}

// One table cell: the text a person reads and the number the table sorts by.
struct Cell {
  std::string text;
  double sort_value = std::nan("");
};

Cell fraction_cell(const json& entry, const char* key) {
  const double value = number(entry, {"measure", key, "value"});
  if (std::isnan(value)) return {"—"};
  const double lower = number(entry, {"measure", key, "lower"});
  const double upper = number(entry, {"measure", key, "upper"});
  std::string text = format("%.4f", value);
  if (!std::isnan(lower) && !std::isnan(upper)) text += " [" + format("%.4f", lower) + ", " + format("%.4f", upper) + "]";
  return {text, value};
}

std::vector<std::string> headers() {
  return {"proxy", "kind", "primitives", "build (s)", "verdict", "f_hit", "f_miss", "V_avg", "GSSA ratio",
          "p1 / p2 / p3", "variance", "cost ratio"};
}

std::vector<Cell> row(const json& entry) {
  std::vector<Cell> cells;
  cells.push_back({entry.value("name", "?")});
  cells.push_back({entry.value("kind", "?")});
  const double primitives = number(entry, {"primitives"});
  const std::string type = entry.value("primitive_type", "");
  cells.push_back({format("%.0f", primitives) + " " + (primitives == 1 ? type : type == "box" ? "boxes" : type + "s"), primitives});
  const double build = number(entry, {"build_seconds"});
  cells.push_back({std::isnan(build) ? "—" : format("%.3f", build), build});
  if (const json* verify = find(entry, {"verify"})) {
    const bool holds = verify->value("holds", false);
    const std::string claim = verify->value("claim", "");
    std::string text = claim == "none" ? "no claim" : (holds ? "holds" : "FAILS");
    if (claim == "none" && verify->contains("hausdorff_relative"))
      text += format(" (Hausdorff %.3f %% of diagonal)", 100 * (*verify)["hausdorff_relative"].get<double>());
    cells.push_back({text, holds ? 1.0 : 0.0});
  } else {
    cells.push_back({"not verified"});
  }
  cells.push_back(fraction_cell(entry, "f_hit"));
  cells.push_back(fraction_cell(entry, "f_miss"));
  cells.push_back(fraction_cell(entry, "v_avg"));
  cells.push_back(fraction_cell(entry, "gssa_ratio"));
  if (const json* p = find(entry, {"measure", "probabilities"})) {
    cells.push_back({format("%.3f", (*p)["p1"].get<double>()) + " / " + format("%.3f", (*p)["p2"].get<double>()) + " / " +
                         format("%.3f", (*p)["p3"].get<double>()),
                     (*p)["p1"].get<double>()});
  } else {
    cells.push_back({"—"});
  }
  const double variance = number(entry, {"measure", "variance", "optimal"});
  cells.push_back({std::isnan(variance) ? "—" : format("%.4f", variance), variance});
  const double cost = number(entry, {"measure", "cost_ns_per_ray", "proxy_over_mesh"});
  std::string cost_text = std::isnan(cost) ? "—" : format("%.3f", cost);
  if (const json* measure = find(entry, {"measure"}))
    if (const auto interval = cost_ratio_interval(*measure))
      cost_text += " (" + format("%.3f", (*interval)[0]) + "–" + format("%.3f", (*interval)[1]) + ")";
  cells.push_back({cost_text, cost});
  return cells;
}

const json* first_ray_set(const json& manifest) {
  for (const json& entry : manifest.at("proxies"))
    if (const json* rays = find(entry, {"measure", "rays"})) return rays;
  return nullptr;
}

std::string mesh_summary(const json& manifest) {
  const json& mesh = manifest.at("mesh");
  std::string text = mesh.value("path", "?") + ": " + std::to_string(mesh.value("vertices", 0)) + " vertices, " +
                     std::to_string(mesh.value("triangles", 0)) + " triangles, " +
                     std::to_string(mesh.value("components", 0)) + " component(s), bounding-box diagonal " +
                     format("%.6g", number(mesh, {"bbox", "diagonal"})) + " (mesh units)";
  return text;
}

std::string ray_summary(const json& manifest) {
  const json* rays = first_ray_set(manifest);
  if (!rays) return "Not measured yet: run `visproxy measure MESH DIR`.";
  return "Measured on " + std::to_string(rays->value("count", 0)) + " " + rays->value("kind", std::string("rays")) +
         " (" + rays->value("description", std::string()) + "), seed " + std::to_string(rays->value("seed", 0)) +
         "; cost timed on one core over the first " + std::to_string(rays->value("timed_rays", 0)) +
         " of them, in blocks that time the mesh and the proxy back to back.";
}

const char* kColumnNotes =
    "f_hit: fraction of rays blocked by the mesh that the proxy also blocks. "
    "f_miss: fraction of rays the mesh lets through that the proxy also lets through. "
    "V_avg: fraction of rays the mesh lets through. "
    "GSSA ratio: rays the proxy blocks over rays the mesh blocks (ratio of generalised shadowing surface areas). "
    "Intervals are 95 % (Wilson score; delta method for the GSSA ratio). "
    "p1 / p2 / p3: the estimator's variance-optimal probabilities (Billen et al. eq. 8): trace only the proxy / also "
    "the mesh when the proxy is hit / also the mesh when it is missed. "
    "variance: the estimator's variance per ray at those probabilities (eq. 16; 0 is exact). "
    "cost ratio: time per ray of the proxy over that of the mesh, on one core, same rays: the median over blocks that "
    "time both back to back, and in brackets the least and greatest block. "
    "verdict: whether the proxy keeps its kind's claim (outside: contains the mesh; inside: lies within it), checked "
    "exactly by `visproxy verify`.";

std::string svg_color(const std::string& kind) {
  if (kind == "outside") return "#1f77b4";
  if (kind == "inside") return "#2ca02c";
  return "#d62728";
}

const char* kUseColors[] = {"#9467bd", "#ff7f0e", "#17becf"};

std::string base64(const std::string& bytes) {
  static const char* digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::size_t n = std::min<std::size_t>(3, bytes.size() - i);
    std::uint32_t word = 0;
    for (std::size_t k = 0; k < 3; ++k) word = word << 8 | (k < n ? static_cast<unsigned char>(bytes[i + k]) : 0u);
    for (std::size_t k = 0; k < 4; ++k) out += k <= n ? digits[(word >> (18 - 6 * k)) & 63] : '=';
  }
  return out;
}

std::string percent(double fraction) { return std::isnan(fraction) ? "—" : format("%.1f %%", 100 * fraction); }

// The recommendation's sentences, and what they rest on.
std::string recommendation_intro(const Recommendation& r) {
  if (r.proxies.empty()) return "";
  return "Predicted on " + r.rays + " (seed " + std::to_string(r.seed) +
         "): efficiency is how many times cheaper than tracing the mesh alone a use is at equal error, 1 / (variance x "
         "cost) against the mesh's, with each use at its most efficient probabilities; intervals are 95 % over the "
         "sampling of the rays and the spread of the costs over their timing blocks.";
}

bool has_recommendation(const ReportFigures& figures) { return !figures.recommendation.choices[0].sentence.empty(); }

const char* kPictureNotes =
    "Each proxy drawn over the mesh (translucent, its silhouette and creases outlined; blue outside, green inside, red "
    "general; an inside proxy shows through the mesh), then the ground below the mesh seen from straight above under a "
    "square area light above and to one side: the mesh's shadow, the proxy's, and their difference (red: shadow of the "
    "mesh the proxy misses; blue: shadow the proxy adds). Missed and extra shadow are over the pictured ground, as "
    "fractions of the mesh's shadow. The up axis is +y; every ground point sees the same grid of points on the light.";

}  // namespace

std::string f_miss_plot_svg(const json& manifest) {
  std::vector<ScatterGroup> groups;
  for (const char* kind : {"outside", "inside", "general"})
    groups.push_back({std::string(kind) + " proxy", svg_color(kind), {}, false, false});
  for (const json& entry : manifest.at("proxies")) {
    const double value = number(entry, {"measure", "f_miss", "value"});
    const double primitives = number(entry, {"primitives"});
    if (std::isnan(value) || !(primitives > 0)) continue;
    const std::string kind = entry.value("kind", "general");
    ScatterPoint point{primitives, value, number(entry, {"measure", "f_miss", "lower"}, value),
                       number(entry, {"measure", "f_miss", "upper"}, value), entry.value("name", "?"), ""};
    point.tooltip = point.label + ": f_miss " + format("%.4f", value) + " [" + format("%.4f", point.y_lower) + ", " +
                    format("%.4f", point.y_upper) + "], " + format("%.0f", primitives) + " primitives";
    groups[kind == "outside" ? 0 : kind == "inside" ? 1 : 2].points.push_back(point);
  }
  return scatter_plot_svg(groups, {.title = "f_miss against primitive count: " + manifest.at("mesh").value("path", "?"),
                                   .x_label = "primitives (boxes, triangles or spheres; log scale)",
                                   .y_label = "f_miss (fraction of free rays the proxy lets through)",
                                   .log_x = true,
                                   .y_min = 0,
                                   .y_max = 1,
                                   .reference_y = std::nan(""),
                                   .reference_label = {},
                                   .empty_note = "No proxy measured yet (visproxy measure MESH DIR)"});
}

std::string efficiency_plot_svg(const json& manifest, const Recommendation& r) {
  std::vector<ScatterGroup> groups;
  for (std::size_t u = 0; u < kProxyUses.size(); ++u) {
    ScatterGroup group{std::string(use_name(kProxyUses[u])), kUseColors[u], {}, true, true};
    for (const ProxyEfficiency& p : r.proxies) {
      const UseFigures& f = p.uses[u];
      if (!f.prediction.usable) continue;
      ScatterPoint point{p.primitives, f.prediction.efficiency, f.interval.lower, f.interval.upper, p.name, ""};
      point.tooltip = p.name + ", " + std::string(use_name(kProxyUses[u])) + ": " + format("%.3g", point.y) + "x [" +
                      format("%.3g", point.y_lower) + ", " + format("%.3g", point.y_upper) + "], " +
                      format("%.0f", p.primitives) + " primitives";
      group.points.push_back(point);
    }
    groups.push_back(std::move(group));
  }
  return scatter_plot_svg(groups, {.title = "Predicted efficiency against primitive count: " + manifest.at("mesh").value("path", "?"),
                                   .x_label = "primitives (boxes, triangles or spheres; log scale)",
                                   .y_label = "efficiency against the mesh (log scale)",
                                   .log_x = true,
                                   .log_y = true,
                                   .reference_y = 1,
                                   .reference_label = "the mesh alone",
                                   .empty_note = "No proxy measured yet (visproxy measure MESH DIR)"});
}

std::string picture_stem(const std::string& proxy_name) {
  std::string stem = proxy_name.empty() ? std::string("proxy") : proxy_name;
  for (char& c : stem)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '-' && c != '_') c = '_';
  if (stem.front() == '.') stem.front() = '_';
  return stem;
}

ReportFigures report_figures(const TriangleMesh& mesh, const std::filesystem::path& folder, const json& manifest,
                             const ReportOptions& options) {
  ReportFigures figures;
  figures.picture_options = options.picture_options;
  figures.flags = proxy_flags(manifest);
  std::map<std::string, InstanceProxy> proxies;
  for (const json& entry : manifest.at("proxies")) {
    const ProxyGeometry geometry = read_proxy_geometry(folder, entry);
    const bool proved = entry.contains("verify") && verdict_proves(entry["verify"], entry, mesh, geometry);
    proxies[entry.at("name").get<std::string>()] =
        InstanceProxy{entry_kind(entry), entry.value("spec", std::string()), geometry.mesh, geometry.spheres, proved};
  }
  figures.recommendation = recommend_proxies(
      manifest,
      [&](const json& entry) {
        const InstanceProxy& proxy = proxies.at(entry.at("name").get<std::string>());
        return proxy.proved ? proxy.kind : ProxyKind::general;
      },
      options.budget);
  if (!options.pictures) return figures;
  const ProxyPictureStage stage(mesh, options.picture_options);
  figures.mesh_shadow_png = encode_png(stage.mesh_shadow());
  for (const auto& [name, proxy] : proxies) {
    const ProxyPictures pictures = stage.pictures(proxy);
    figures.pictures[name] = {encode_png(pictures.overlay), encode_png(pictures.shadow), encode_png(pictures.difference),
                              pictures.missed_shadow, pictures.extra_shadow};
  }
  figures.pictured = true;
  return figures;
}

std::string report_markdown(const json& manifest, const ReportFigures& figures) {
  std::string md = "# visproxy report: " + manifest.at("mesh").value("path", "?") + "\n\n";
  if (has_recommendation(figures)) {
    md += "## What to ship\n\n";
    for (const ShippingLine& line : shipping_lines(figures, manifest)) md += "- " + line.text + "\n";
    md += "\n## Recommendation\n\n";
    for (const UseChoice& choice : figures.recommendation.choices) md += "- " + choice.sentence + "\n";
    const std::string intro = recommendation_intro(figures.recommendation);
    md += (intro.empty() ? std::string() : "\n" + intro + " Every proxy's figures: recommendation.json.\n") + "\n";
  }
  if (!figures.flags.empty()) {
    md += "## Check before shipping\n\n";
    for (const ProxyFlag& flag : figures.flags) md += "- " + flag.text + "\n";
    md += "\n";
  }
  md += "Mesh: " + mesh_summary(manifest) + ".\n\n" + ray_summary(manifest) + "\n\n";
  const std::vector<std::string> head = headers();
  md += "|";
  for (const std::string& h : head) md += " " + h + " |";
  md += "\n|";
  for (std::size_t i = 0; i < head.size(); ++i) md += i < 2 || i == 4 || i == 9 ? " --- |" : " ---: |";
  md += "\n";
  for (const json& entry : manifest.at("proxies")) {
    md += "|";
    for (const Cell& cell : row(entry)) md += " " + cell.text + " |";
    md += "\n";
  }
  md += "\n" + std::string(kColumnNotes) + "\n\n";
  if (figures.pictured) {
    md += "## Proxies and their shadows\n\n" + std::string(kPictureNotes) + "\n\n";
    md += "| proxy | over the mesh | the mesh's shadow | the proxy's shadow | difference | missed shadow | extra shadow |\n";
    md += "| --- | --- | --- | --- | --- | ---: | ---: |\n";
    for (const auto& entry : manifest.at("proxies")) {
      const std::string name = entry.at("name").get<std::string>();
      const auto found = figures.pictures.find(name);
      if (found == figures.pictures.end()) continue;
      const std::string stem = "pictures/" + picture_stem(name);
      md += "| " + name + " | ![" + name + " over the mesh](" + stem + "-overlay.png) | ![the mesh's shadow](pictures/mesh-shadow.png) | ![" +
            name + "'s shadow](" + stem + "-shadow.png) | ![difference](" + stem + "-difference.png) | " +
            percent(found->second.missed_shadow) + " | " + percent(found->second.extra_shadow) + " |\n";
    }
    md += "\n";
  }
  md += "![f_miss against primitive count](f_miss.svg)\n\n";
  if (has_recommendation(figures)) md += "![predicted efficiency against primitive count](efficiency.svg)\n\n";
  md += "Written by " + manifest.value("generator", std::string("visproxy")) + " from manifest.json.\n";
  return md;
}

std::string escape_html(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string sortable_table_page(const std::string& title, const std::string& before_table,
                                const std::vector<std::string>& headers, const std::vector<std::vector<HtmlCell>>& rows,
                                const std::string& after_table) {
  std::string html = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" + escape_html(title) +
                     "</title>\n<style>\n"
                     "body { font-family: sans-serif; margin: 2em; color: #222; }\n"
                     "table { border-collapse: collapse; font-size: 13px; }\n"
                     "th, td { border: 1px solid #bbb; padding: 4px 8px; }\n"
                     "th { background: #eee; cursor: pointer; user-select: none; }\n"
                     "th.sorted-ascending::after { content: ' \\25B2'; } th.sorted-descending::after { content: ' \\25BC'; }\n"
                     "td.number { text-align: right; font-variant-numeric: tabular-nums; }\n"
                     "td.fails { color: #b00; font-weight: bold; }\n"
                     "p.notes { max-width: 60em; font-size: 13px; color: #444; }\n"
                     "#recommendation li { margin: 0.3em 0; max-width: 60em; }\n"
                     "figure.proxy { margin: 1em 0; }\n"
                     "figure.proxy .strip { display: flex; gap: 8px; flex-wrap: wrap; }\n"
                     "figure.proxy .strip div { display: flex; flex-direction: column; font-size: 12px; color: #444; }\n"
                     "figure.proxy img { border: 1px solid #bbb; image-rendering: auto; }\n"
                     "</style>\n</head>\n<body>\n";
  html += "<h1>" + escape_html(title) + "</h1>\n" + before_table;
  html += "<table id=\"sortable\">\n<thead><tr>";
  for (const std::string& h : headers) html += "<th>" + escape_html(h) + "</th>";
  html += "</tr></thead>\n<tbody>\n";
  for (const std::vector<HtmlCell>& cells : rows) {
    html += "<tr>";
    for (const HtmlCell& cell : cells) {
      const std::string cls = !cell.css_class.empty() ? cell.css_class : cell.number ? "number" : "";
      const std::string text = cell.link.empty() ? escape_html(cell.text)
                                                 : "<a href=\"" + escape_html(cell.link) + "\">" + escape_html(cell.text) + "</a>";
      html += "<td" + (cls.empty() ? std::string() : " class=\"" + cls + "\"") + " data-sort=\"" +
              (std::isnan(cell.sort_value) ? escape_html(cell.text) : format("%.17g", cell.sort_value)) + "\">" + text + "</td>";
    }
    html += "</tr>\n";
  }
  html += "</tbody>\n</table>\n" + after_table;
  html +=
      "<script>\n"
      "(function () {\n"
      "  const table = document.getElementById('sortable');\n"
      "  const headers = table.tHead.rows[0].cells;\n"
      "  const key = (row, column) => {\n"
      "    const text = row.cells[column].dataset.sort;\n"
      "    const value = parseFloat(text);\n"
      "    return isNaN(value) ? text : value;\n"
      "  };\n"
      "  for (let column = 0; column < headers.length; ++column) {\n"
      "    headers[column].addEventListener('click', () => {\n"
      "      const ascending = !headers[column].classList.contains('sorted-ascending');\n"
      "      const rows = Array.from(table.tBodies[0].rows);\n"
      "      rows.sort((a, b) => {\n"
      "        const x = key(a, column), y = key(b, column);\n"
      "        const order = typeof x === typeof y ? (x < y ? -1 : x > y ? 1 : 0) : (typeof x === 'number' ? -1 : 1);\n"
      "        return ascending ? order : -order;\n"
      "      });\n"
      "      for (const row of rows) table.tBodies[0].appendChild(row);\n"
      "      for (const h of headers) h.classList.remove('sorted-ascending', 'sorted-descending');\n"
      "      headers[column].classList.add(ascending ? 'sorted-ascending' : 'sorted-descending');\n"
      "    });\n"
      "  }\n"
      "  table.dataset.sortable = 'ready';\n"
      "})();\n"
      "</script>\n</body>\n</html>\n";
  return html;
}

std::string report_html(const json& manifest, const ReportFigures& figures) {
  const std::string title = "visproxy report: " + manifest.at("mesh").value("path", "?");
  std::vector<std::vector<HtmlCell>> rows;
  for (const json& entry : manifest.at("proxies")) {
    std::vector<HtmlCell> cells;
    std::size_t column = 0;
    for (const Cell& cell : row(entry)) {
      HtmlCell html_cell;
      html_cell.text = cell.text, html_cell.sort_value = cell.sort_value, html_cell.number = column >= 2 && column != 4 && column != 9;
      if (cell.text == "FAILS") html_cell.css_class = "fails";
      cells.push_back(std::move(html_cell));
      ++column;
    }
    rows.push_back(std::move(cells));
  }
  std::string before;
  if (has_recommendation(figures)) {
    before += "<section id=\"ship\">\n<h2>What to ship</h2>\n<ul>\n";
    for (const ShippingLine& line : shipping_lines(figures, manifest))
      before += "<li data-use=\"" + line.use_key + "\">" + escape_html(line.text) + "</li>\n";
    before += "</ul>\n</section>\n";
    before += "<section id=\"recommendation\">\n<h2>Recommendation</h2>\n<ul>\n";
    for (const UseChoice& choice : figures.recommendation.choices)
      before += "<li data-use=\"" + std::string(use_key(choice.use)) + "\">" + escape_html(choice.sentence) + "</li>\n";
    before += "</ul>\n<p class=\"notes\">" + escape_html(recommendation_intro(figures.recommendation)) +
              " Every proxy's figures are in recommendation.json and in the efficiency plot below.</p>\n</section>\n";
  }
  if (!figures.flags.empty()) {
    before += "<section id=\"flags\">\n<h2>Check before shipping</h2>\n<ul>\n";
    for (const ProxyFlag& flag : figures.flags)
      before += "<li data-proxy=\"" + escape_html(flag.proxy) + "\" data-flag=\"" + flag.flag + "\">" + escape_html(flag.text) + "</li>\n";
    before += "</ul>\n</section>\n";
  }
  before += "<p>Mesh: " + escape_html(mesh_summary(manifest)) + ".</p>\n<p>" + escape_html(ray_summary(manifest)) + "</p>\n";
  std::string after = "<p class=\"notes\">" + escape_html(kColumnNotes) + " Click a column header to sort.</p>\n";
  if (figures.pictured) {
    auto image = [](const std::string& png, const std::string& alt, int size) {
      return "<img alt=\"" + escape_html(alt) + "\" width=\"" + std::to_string(size) + "\" height=\"" + std::to_string(size) +
             "\" src=\"data:image/png;base64," + base64(png) + "\">";
    };
    const int size = figures.picture_options.size;
    after += "<section id=\"pictures\">\n<h2>Proxies and their shadows</h2>\n<p class=\"notes\">" + escape_html(kPictureNotes) + "</p>\n";
    for (const json& entry : manifest.at("proxies")) {
      const std::string name = entry.at("name").get<std::string>();
      const auto found = figures.pictures.find(name);
      if (found == figures.pictures.end()) continue;
      const ProxyPictureFiles& p = found->second;
      after += "<figure class=\"proxy\" data-proxy=\"" + escape_html(name) + "\">\n<figcaption><b>" + escape_html(name) + "</b>, " +
               escape_html(entry.value("kind", std::string("?"))) + ", " + escape_html(row(entry)[2].text) + ": missed shadow " +
               percent(p.missed_shadow) + ", extra shadow " + percent(p.extra_shadow) + "</figcaption>\n<div class=\"strip\">";
      for (const auto& [png, label] : {std::pair{&p.overlay_png, name + " over the mesh"}, std::pair{&figures.mesh_shadow_png, std::string("the mesh's shadow")},
                                       std::pair{&p.shadow_png, name + "'s shadow"}, std::pair{&p.difference_png, std::string("difference")}})
        after += "<div>" + image(*png, label, size) + "<span>" + escape_html(label) + "</span></div>";
      after += "</div>\n</figure>\n";
    }
    after += "</section>\n";
  }
  after += "<figure>\n" + f_miss_plot_svg(manifest) + "</figure>\n";
  if (has_recommendation(figures)) after += "<figure>\n" + efficiency_plot_svg(manifest, figures.recommendation) + "</figure>\n";
  after += "<p class=\"notes\">Written by " + escape_html(manifest.value("generator", std::string("visproxy"))) + " from manifest.json.</p>\n";
  return sortable_table_page(title, before, headers(), rows, after);
}

std::vector<ShippingLine> shipping_lines(const ReportFigures& figures, const json& manifest) {
  std::vector<ShippingLine> lines;
  const Recommendation& r = figures.recommendation;
  for (std::size_t u = 0; u < r.choices.size(); ++u) {
    const UseChoice& choice = r.choices[u];
    const std::string use = use_phrase(choice.use);
    ShippingLine line{std::string(use_key(choice.use)), "", ""};
    const ProxyEfficiency* p = choice.best >= 0 ? &r.proxies[static_cast<std::size_t>(choice.best)] : nullptr;
    const UseFigures* f = p ? &p->uses[u] : nullptr;
    const json* entry = nullptr;
    if (p)
      for (const json& e : manifest.at("proxies"))
        if (e.value("name", std::string()) == p->name) entry = &e;
    if (!p || !entry || !f->shown_cheaper()) {
      std::string best;
      if (p) {
        best = " (the best, " + p->name + ", is predicted " + format("%#.3g", f->prediction.efficiency) + "x";
        if (f->at_render())
          best += " per shadow ray and " + format("%#.3g", f->render_efficiency) + "x [" + format("%#.3g", f->render_interval.lower) +
                  ", " + format("%#.3g", f->render_interval.upper) + "] over the render";
        best += ")";
      }
      line.text = use + ", keep the mesh: no proxy is shown cheaper than it" + (f && f->at_render() ? " over the render" : "") + best + ".";
      lines.push_back(std::move(line));
      continue;
    }
    line.file = entry->value("file", std::string());
    const std::string type = entry->value("primitive_type", std::string("triangle"));
    const double count = entry->value("primitives", 0.0);
    line.text = use + ", ship " + line.file + " (" + format("%.0f", count) + " " +
                (count == 1 ? type : type == "box" ? "boxes" : type + "s") + ") beside the mesh: shadow rays are predicted " +
                format("%#.3g", f->prediction.efficiency) + "x [" + format("%#.3g", f->interval.lower) + ", " +
                format("%#.3g", f->interval.upper) + "] cheaper, the shadows " +
                (choice.use == ProxyUse::bounds ? "unchanged" : "unbiased at equal noise");
    if (const auto pictured = figures.pictures.find(p->name); pictured != figures.pictures.end())
      line.text += " (cast on its own, it would miss " + percent(pictured->second.missed_shadow) +
                   " of the mesh's shadow and add " + percent(pictured->second.extra_shadow) + ")";
    line.text += render_phrase(r, *f) + ".";
    lines.push_back(std::move(line));
  }
  return lines;
}

json report_recommendation_json(const ReportFigures& figures, const json& manifest) {
  json recommendation = recommendation_json(figures.recommendation, manifest);
  for (const ShippingLine& line : shipping_lines(figures, manifest)) {
    json& use = recommendation["uses"][line.use_key];
    use["ship"] = line.text;
    use["file"] = line.file.empty() ? json(nullptr) : json(line.file);
  }
  recommendation["flags"] = flags_json(figures.flags);
  return recommendation;
}

void write_report(const std::filesystem::path& folder, const json& manifest, const ReportFigures& figures) {
  if (figures.pictured) {
    const std::filesystem::path pictures = folder / "pictures";
    std::error_code error;
    std::filesystem::create_directories(pictures, error);
    if (error) throw IOError(pictures, "cannot create the pictures folder: " + error.message());
    write_file_atomically(pictures / "mesh-shadow.png", figures.mesh_shadow_png);
    for (const auto& [name, p] : figures.pictures) {
      const std::string stem = picture_stem(name);
      write_file_atomically(pictures / (stem + "-overlay.png"), p.overlay_png);
      write_file_atomically(pictures / (stem + "-shadow.png"), p.shadow_png);
      write_file_atomically(pictures / (stem + "-difference.png"), p.difference_png);
    }
  }
  write_file_atomically(folder / "f_miss.svg", f_miss_plot_svg(manifest));
  if (has_recommendation(figures)) {
    write_file_atomically(folder / "efficiency.svg", efficiency_plot_svg(manifest, figures.recommendation));
    write_file_atomically(folder / "recommendation.json", report_recommendation_json(figures, manifest).dump(2) + "\n");
  }
  write_file_atomically(folder / "report.md", report_markdown(manifest, figures));
  write_file_atomically(folder / "report.html", report_html(manifest, figures));
}

void write_report(const std::filesystem::path& folder, const json& manifest, const TriangleMesh& mesh, const ReportOptions& options) {
  write_report(folder, manifest, report_figures(mesh, folder, manifest, options));
}

}  // namespace visproxy
