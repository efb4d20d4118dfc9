#include "visproxy/evaluate/report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "visproxy/core/files.h"

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
  cells.push_back({std::isnan(cost) ? "—" : format("%.3f", cost), cost});
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
         "; cost timed on one core over the first " + std::to_string(rays->value("timed_rays", 0)) + " of them.";
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
    "cost ratio: time per ray of the proxy over that of the mesh, on one core, same rays. "
    "verdict: whether the proxy keeps its kind's claim (outside: contains the mesh; inside: lies within it), checked "
    "exactly by `visproxy verify`.";

std::string svg_color(const std::string& kind) {
  if (kind == "outside") return "#1f77b4";
  if (kind == "inside") return "#2ca02c";
  return "#d62728";
}

}  // namespace

std::string f_miss_plot_svg(const json& manifest) {
  const double width = 720, height = 420, left = 70, right = 170, top = 50, bottom = 60;
  const double plot_w = width - left - right, plot_h = height - top - bottom;
  struct Point {
    std::string name, kind;
    double primitives, value, lower, upper;
  };
  std::vector<Point> points;
  for (const json& entry : manifest.at("proxies")) {
    const double value = number(entry, {"measure", "f_miss", "value"});
    const double primitives = number(entry, {"primitives"});
    if (std::isnan(value) || !(primitives > 0)) continue;
    points.push_back({entry.value("name", "?"), entry.value("kind", "general"), primitives, value,
                      number(entry, {"measure", "f_miss", "lower"}, value), number(entry, {"measure", "f_miss", "upper"}, value)});
  }
  std::string svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + format("%.0f", width) + "\" height=\"" +
                    format("%.0f", height) + "\" viewBox=\"0 0 " + format("%.0f", width) + " " + format("%.0f", height) +
                    "\" font-family=\"sans-serif\" font-size=\"12\">\n";
  svg += "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  svg += "<text x=\"" + format("%.0f", width / 2) + "\" y=\"22\" text-anchor=\"middle\" font-size=\"14\">f_miss against primitive count: " +
         escape_html(manifest.at("mesh").value("path", "?")) + "</text>\n";
  if (points.empty()) {
    svg += "<text x=\"" + format("%.0f", width / 2) + "\" y=\"" + format("%.0f", height / 2) +
           "\" text-anchor=\"middle\">No proxy measured yet (visproxy measure MESH DIR)</text>\n</svg>\n";
    return svg;
  }
  double log_min = std::floor(std::log10(std::min_element(points.begin(), points.end(), [](auto& a, auto& b) { return a.primitives < b.primitives; })->primitives));
  double log_max = std::ceil(std::log10(std::max_element(points.begin(), points.end(), [](auto& a, auto& b) { return a.primitives < b.primitives; })->primitives));
  if (log_max <= log_min) log_max = log_min + 1;
  auto x_of = [&](double primitives) { return left + plot_w * (std::log10(primitives) - log_min) / (log_max - log_min); };
  auto y_of = [&](double value) { return top + plot_h * (1 - value); };
  // Axes, grid and ticks.
  svg += "<g stroke=\"#ccc\">\n";
  for (int i = 0; i <= 10; i += 2)
    svg += "<line x1=\"" + format("%.1f", left) + "\" x2=\"" + format("%.1f", left + plot_w) + "\" y1=\"" +
           format("%.1f", y_of(i / 10.0)) + "\" y2=\"" + format("%.1f", y_of(i / 10.0)) + "\"/>\n";
  for (double e = log_min; e <= log_max; ++e)
    svg += "<line x1=\"" + format("%.1f", x_of(std::pow(10, e))) + "\" x2=\"" + format("%.1f", x_of(std::pow(10, e))) +
           "\" y1=\"" + format("%.1f", top) + "\" y2=\"" + format("%.1f", top + plot_h) + "\"/>\n";
  svg += "</g>\n<g>\n";
  for (int i = 0; i <= 10; i += 2)
    svg += "<text x=\"" + format("%.1f", left - 8) + "\" y=\"" + format("%.1f", y_of(i / 10.0) + 4) +
           "\" text-anchor=\"end\">" + format("%.1f", i / 10.0) + "</text>\n";
  for (double e = log_min; e <= log_max; ++e)
    svg += "<text x=\"" + format("%.1f", x_of(std::pow(10, e))) + "\" y=\"" + format("%.1f", top + plot_h + 18) +
           "\" text-anchor=\"middle\">" + format("%.0f", std::pow(10, e)) + "</text>\n";
  svg += "<text x=\"" + format("%.1f", left + plot_w / 2) + "\" y=\"" + format("%.1f", height - 15) +
         "\" text-anchor=\"middle\">primitives (boxes, triangles or spheres; log scale)</text>\n";
  svg += "<text transform=\"translate(18 " + format("%.1f", top + plot_h / 2) +
         ") rotate(-90)\" text-anchor=\"middle\">f_miss (fraction of free rays the proxy lets through)</text>\n";
  svg += "<rect x=\"" + format("%.1f", left) + "\" y=\"" + format("%.1f", top) + "\" width=\"" + format("%.1f", plot_w) +
         "\" height=\"" + format("%.1f", plot_h) + "\" fill=\"none\" stroke=\"black\"/>\n</g>\n";
  // Points with their intervals and labels.
  for (const Point& p : points) {
    const std::string color = svg_color(p.kind);
    const double x = x_of(p.primitives);
    svg += "<g class=\"proxy\"><title>" + escape_html(p.name) + ": f_miss " + format("%.4f", p.value) + " [" +
           format("%.4f", p.lower) + ", " + format("%.4f", p.upper) + "], " + format("%.0f", p.primitives) +
           " primitives</title>";
    svg += "<line x1=\"" + format("%.1f", x) + "\" x2=\"" + format("%.1f", x) + "\" y1=\"" + format("%.1f", y_of(p.lower)) +
           "\" y2=\"" + format("%.1f", y_of(p.upper)) + "\" stroke=\"" + color + "\"/>";
    svg += "<circle cx=\"" + format("%.1f", x) + "\" cy=\"" + format("%.1f", y_of(p.value)) + "\" r=\"4\" fill=\"" + color + "\"/>";
    svg += "<text x=\"" + format("%.1f", x + 7) + "\" y=\"" + format("%.1f", y_of(p.value) + 4) + "\" font-size=\"10\">" +
           escape_html(p.name) + "</text></g>\n";
  }
  // Legend.
  double legend_y = top + 10;
  for (const char* kind : {"outside", "inside", "general"}) {
    svg += "<circle cx=\"" + format("%.1f", width - right + 20) + "\" cy=\"" + format("%.1f", legend_y) + "\" r=\"4\" fill=\"" +
           svg_color(kind) + "\"/><text x=\"" + format("%.1f", width - right + 30) + "\" y=\"" + format("%.1f", legend_y + 4) +
           "\">" + kind + " proxy</text>\n";
    legend_y += 18;
  }
  svg += "</svg>\n";
  return svg;
}

std::string report_markdown(const json& manifest) {
  std::string md = "# visproxy report: " + manifest.at("mesh").value("path", "?") + "\n\n";
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
  md += "\n" + std::string(kColumnNotes) + "\n\n![f_miss against primitive count](f_miss.svg)\n\n";
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

std::string report_html(const json& manifest) {
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
  const std::string before = "<p>Mesh: " + escape_html(mesh_summary(manifest)) + ".</p>\n<p>" + escape_html(ray_summary(manifest)) + "</p>\n";
  const std::string after = "<p class=\"notes\">" + escape_html(kColumnNotes) + " Click a column header to sort.</p>\n" +
                            "<figure>\n" + f_miss_plot_svg(manifest) + "</figure>\n" +
                            "<p class=\"notes\">Written by " + escape_html(manifest.value("generator", std::string("visproxy"))) +
                            " from manifest.json.</p>\n";
  return sortable_table_page(title, before, headers(), rows, after);
}

void write_report(const std::filesystem::path& folder, const json& manifest) {
  write_file_atomically(folder / "f_miss.svg", f_miss_plot_svg(manifest));
  write_file_atomically(folder / "report.md", report_markdown(manifest));
  write_file_atomically(folder / "report.html", report_html(manifest));
}

}  // namespace visproxy
