#include "visproxy/evaluate/plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace visproxy {
namespace {

std::string number(double value, const char* format = "%.1f") {
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, format, value);
  return buffer;
}

std::string escape(const std::string& text) {
  std::string out;
  for (char c : text) out += c == '<' ? "&lt;" : c == '>' ? "&gt;" : c == '&' ? "&amp;" : std::string(1, c);
  return out;
}

const char* kColors[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"};

struct Axis {
  bool log = false;
  double lo = 0, hi = 1;
  double map(double v) const { return log ? std::log10(v) : v; }
  bool drawable(double v) const { return std::isfinite(v) && (!log || v > 0); }
};

Axis fit_axis(const std::vector<double>& values, bool log) {
  Axis axis{log, std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  for (double v : values)
    if (axis.drawable(v)) axis.lo = std::min(axis.lo, axis.map(v)), axis.hi = std::max(axis.hi, axis.map(v));
  if (!std::isfinite(axis.lo)) axis.lo = 0, axis.hi = 1;
  if (log) axis.lo = std::floor(axis.lo), axis.hi = std::ceil(axis.hi);
  if (axis.hi <= axis.lo) axis.hi = axis.lo + 1;
  if (!log) {
    const double pad = 0.05 * (axis.hi - axis.lo);
    axis.lo = axis.lo >= 0 && axis.lo - pad < 0 ? 0.0 : axis.lo - pad;
    axis.hi += pad;
  }
  return axis;
}

std::vector<double> ticks(const Axis& axis) {
  std::vector<double> out;
  if (axis.log) {
    for (double e = axis.lo; e <= axis.hi + 1e-9; ++e) out.push_back(e);
    return out;
  }
  const double span = axis.hi - axis.lo;
  const double step = std::pow(10, std::floor(std::log10(span / 5)));
  const double nice = span / step > 20 ? 5 * step : span / step > 10 ? 2 * step : step;
  for (double t = std::ceil(axis.lo / nice) * nice; t <= axis.hi + 1e-12; t += nice) out.push_back(t);
  return out;
}

std::string tick_label(const Axis& axis, double t) {
  if (axis.log) return "1e" + number(t, "%.0f");
  return number(t, "%g");
}

}  // namespace

std::string line_plot_svg(const std::vector<PlotSeries>& series, const PlotOptions& o) {
  const double left = 80, right = 170, top = 45, bottom = 60;
  const double w = o.width - left - right, h = o.height - top - bottom;
  std::vector<double> xs, ys;
  for (const PlotSeries& s : series) {
    xs.insert(xs.end(), s.x.begin(), s.x.end());
    ys.insert(ys.end(), s.y.begin(), s.y.end());
  }
  const Axis ax = fit_axis(xs, o.log_x), ay = fit_axis(ys, o.log_y);
  auto px = [&](double v) { return left + w * (ax.map(v) - ax.lo) / (ax.hi - ax.lo); };
  auto py = [&](double v) { return top + h * (1 - (ay.map(v) - ay.lo) / (ay.hi - ay.lo)); };
  std::string svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + number(o.width, "%.0f") + "\" height=\"" +
                    number(o.height, "%.0f") + "\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  svg += "<text x=\"" + number(left + w / 2) + "\" y=\"22\" text-anchor=\"middle\" font-size=\"14\">" + escape(o.title) + "</text>\n";
  for (double t : ticks(ax)) {
    const double x = left + w * (t - ax.lo) / (ax.hi - ax.lo);
    svg += "<line x1=\"" + number(x) + "\" x2=\"" + number(x) + "\" y1=\"" + number(top) + "\" y2=\"" + number(top + h) +
           "\" stroke=\"#ddd\"/><text x=\"" + number(x) + "\" y=\"" + number(top + h + 16) + "\" text-anchor=\"middle\">" +
           tick_label(ax, t) + "</text>\n";
  }
  for (double t : ticks(ay)) {
    const double y = top + h * (1 - (t - ay.lo) / (ay.hi - ay.lo));
    svg += "<line x1=\"" + number(left) + "\" x2=\"" + number(left + w) + "\" y1=\"" + number(y) + "\" y2=\"" + number(y) +
           "\" stroke=\"#ddd\"/><text x=\"" + number(left - 6) + "\" y=\"" + number(y + 4) + "\" text-anchor=\"end\">" +
           tick_label(ay, t) + "</text>\n";
  }
  svg += "<rect x=\"" + number(left) + "\" y=\"" + number(top) + "\" width=\"" + number(w) + "\" height=\"" + number(h) +
         "\" fill=\"none\" stroke=\"black\"/>\n";
  svg += "<text x=\"" + number(left + w / 2) + "\" y=\"" + number(o.height - 18.0) + "\" text-anchor=\"middle\">" + escape(o.x_label) + "</text>\n";
  svg += "<text transform=\"translate(20 " + number(top + h / 2) + ") rotate(-90)\" text-anchor=\"middle\">" + escape(o.y_label) + "</text>\n";
  for (std::size_t i = 0; i < series.size(); ++i) {
    const PlotSeries& s = series[i];
    const std::string color = kColors[i % std::size(kColors)];
    std::string points;
    for (std::size_t k = 0; k < std::min(s.x.size(), s.y.size()); ++k) {
      if (!ax.drawable(s.x[k]) || !ay.drawable(s.y[k])) continue;
      points += number(px(s.x[k])) + "," + number(py(s.y[k])) + " ";
      svg += "<circle cx=\"" + number(px(s.x[k])) + "\" cy=\"" + number(py(s.y[k])) + "\" r=\"3\" fill=\"" + color + "\"/>";
    }
    svg += "<polyline points=\"" + points + "\" fill=\"none\" stroke=\"" + color + "\"/>\n";
    const double ly = top + 12 + 18.0 * static_cast<double>(i);
    svg += "<line x1=\"" + number(left + w + 12) + "\" x2=\"" + number(left + w + 32) + "\" y1=\"" + number(ly) + "\" y2=\"" +
           number(ly) + "\" stroke=\"" + color + "\" stroke-width=\"2\"/><text x=\"" + number(left + w + 38) + "\" y=\"" +
           number(ly + 4) + "\">" + escape(s.name) + "</text>\n";
  }
  svg += "</svg>\n";
  return svg;
}

}  // namespace visproxy
