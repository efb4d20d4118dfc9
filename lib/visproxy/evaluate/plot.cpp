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

// The plotting area and its axes: the frame, title, grid, ticks and axis labels every plot draws.
struct Frame {
  double left = 80, right = 170, top = 45, bottom = 60;
  double width = 0, height = 0, w = 0, h = 0;
  Axis ax, ay;
  double px(double v) const { return left + w * (ax.map(v) - ax.lo) / (ax.hi - ax.lo); }
  double py(double v) const { return top + h * (1 - (ay.map(v) - ay.lo) / (ay.hi - ay.lo)); }
  double legend_x() const { return left + w + 12; }
  double legend_y(std::size_t i) const { return top + 12 + 18.0 * static_cast<double>(i); }
};

Frame make_frame(int width, int height, const Axis& ax, const Axis& ay) {
  Frame f;
  f.width = width, f.height = height, f.ax = ax, f.ay = ay;
  f.w = width - f.left - f.right, f.h = height - f.top - f.bottom;
  return f;
}

std::string frame_svg(const Frame& f, const std::string& title, const std::string& x_label, const std::string& y_label) {
  std::string svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + number(f.width, "%.0f") + "\" height=\"" +
                    number(f.height, "%.0f") + "\" viewBox=\"0 0 " + number(f.width, "%.0f") + " " + number(f.height, "%.0f") +
                    "\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  svg += "<text x=\"" + number(f.left + f.w / 2) + "\" y=\"22\" text-anchor=\"middle\" font-size=\"14\">" + escape(title) + "</text>\n";
  for (double t : ticks(f.ax)) {
    const double x = f.left + f.w * (t - f.ax.lo) / (f.ax.hi - f.ax.lo);
    svg += "<line x1=\"" + number(x) + "\" x2=\"" + number(x) + "\" y1=\"" + number(f.top) + "\" y2=\"" + number(f.top + f.h) +
           "\" stroke=\"#ddd\"/><text x=\"" + number(x) + "\" y=\"" + number(f.top + f.h + 16) + "\" text-anchor=\"middle\">" +
           tick_label(f.ax, t) + "</text>\n";
  }
  for (double t : ticks(f.ay)) {
    const double y = f.top + f.h * (1 - (t - f.ay.lo) / (f.ay.hi - f.ay.lo));
    svg += "<line x1=\"" + number(f.left) + "\" x2=\"" + number(f.left + f.w) + "\" y1=\"" + number(y) + "\" y2=\"" + number(y) +
           "\" stroke=\"#ddd\"/><text x=\"" + number(f.left - 6) + "\" y=\"" + number(y + 4) + "\" text-anchor=\"end\">" +
           tick_label(f.ay, t) + "</text>\n";
  }
  svg += "<rect x=\"" + number(f.left) + "\" y=\"" + number(f.top) + "\" width=\"" + number(f.w) + "\" height=\"" + number(f.h) +
         "\" fill=\"none\" stroke=\"black\"/>\n";
  svg += "<text x=\"" + number(f.left + f.w / 2) + "\" y=\"" + number(f.height - 18.0) + "\" text-anchor=\"middle\">" + escape(x_label) + "</text>\n";
  svg += "<text transform=\"translate(20 " + number(f.top + f.h / 2) + ") rotate(-90)\" text-anchor=\"middle\">" + escape(y_label) + "</text>\n";
  return svg;
}

}  // namespace

std::string line_plot_svg(const std::vector<PlotSeries>& series, const PlotOptions& o) {
  std::vector<double> xs, ys;
  for (const PlotSeries& s : series) {
    xs.insert(xs.end(), s.x.begin(), s.x.end());
    ys.insert(ys.end(), s.y.begin(), s.y.end());
  }
  const Frame f = make_frame(o.width, o.height, fit_axis(xs, o.log_x), fit_axis(ys, o.log_y));
  const Axis &ax = f.ax, &ay = f.ay;
  auto px = [&](double v) { return f.px(v); };
  auto py = [&](double v) { return f.py(v); };
  std::string svg = frame_svg(f, o.title, o.x_label, o.y_label);
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
    const double ly = f.legend_y(i);
    svg += "<line x1=\"" + number(f.legend_x()) + "\" x2=\"" + number(f.legend_x() + 20) + "\" y1=\"" + number(ly) + "\" y2=\"" +
           number(ly) + "\" stroke=\"" + color + "\" stroke-width=\"2\"/><text x=\"" + number(f.legend_x() + 26) + "\" y=\"" +
           number(ly + 4) + "\">" + escape(s.name) + "</text>\n";
  }
  svg += "</svg>\n";
  return svg;
}

std::string scatter_plot_svg(const std::vector<ScatterGroup>& groups, const ScatterOptions& o) {
  std::vector<double> xs, ys;
  for (const ScatterGroup& g : groups)
    for (const ScatterPoint& p : g.points) {
      xs.push_back(p.x), ys.push_back(p.y);
      for (double v : {p.y_lower, p.y_upper})
        if (std::isfinite(v)) ys.push_back(v);
    }
  if (std::isfinite(o.reference_y)) ys.push_back(o.reference_y);
  Axis ay = fit_axis(ys, o.log_y);
  if (std::isfinite(o.y_min) && std::isfinite(o.y_max) && o.y_max > o.y_min && (!o.log_y || o.y_min > 0))
    ay.lo = ay.map(o.y_min), ay.hi = ay.map(o.y_max);
  const Frame f = make_frame(o.width, o.height, fit_axis(xs, o.log_x), ay);
  std::string svg = frame_svg(f, o.title, o.x_label, o.y_label);
  auto inside = [&](double x, double y) { return f.ax.drawable(x) && f.ay.drawable(y); };
  // The y of a value clamped to the plotting area (an interval may reach beyond it).
  auto clamped_py = [&](double v) { return std::clamp(f.py(v), f.top, f.top + f.h); };
  std::size_t drawn = 0;
  if (std::isfinite(o.reference_y) && f.ay.drawable(o.reference_y)) {
    const double y = f.py(o.reference_y);
    svg += "<line x1=\"" + number(f.left) + "\" x2=\"" + number(f.left + f.w) + "\" y1=\"" + number(y) + "\" y2=\"" + number(y) +
           "\" stroke=\"#555\" stroke-dasharray=\"6 4\"/><text x=\"" + number(f.left + 6) + "\" y=\"" + number(y - 5) +
           "\" font-size=\"11\" fill=\"#555\">" + escape(o.reference_label) + "</text>\n";
  }
  for (std::size_t i = 0; i < groups.size(); ++i) {
    const ScatterGroup& g = groups[i];
    // The front: by x, the points that raise the best y so far.
    std::vector<const ScatterPoint*> front;
    {
      std::vector<const ScatterPoint*> sorted;
      for (const ScatterPoint& p : g.points)
        if (inside(p.x, p.y)) sorted.push_back(&p);
      std::sort(sorted.begin(), sorted.end(), [](auto* a, auto* b) { return a->x < b->x || (a->x == b->x && a->y > b->y); });
      double best = -std::numeric_limits<double>::infinity();
      for (const ScatterPoint* p : sorted)
        if (p->y > best) front.push_back(p), best = p->y;
    }
    if (g.pareto_front && !front.empty()) {
      std::string points;
      for (std::size_t k = 0; k < front.size(); ++k) {
        if (k > 0) points += number(f.px(front[k]->x)) + "," + number(f.py(front[k - 1]->y)) + " ";
        points += number(f.px(front[k]->x)) + "," + number(f.py(front[k]->y)) + " ";
      }
      svg += "<polyline class=\"front\" points=\"" + points + "\" fill=\"none\" stroke=\"" + g.color +
             "\" stroke-opacity=\"0.6\" stroke-width=\"1.5\"/>\n";
    }
    for (const ScatterPoint& p : g.points) {
      if (!inside(p.x, p.y)) continue;
      ++drawn;
      const double x = f.px(p.x), y = f.py(p.y);
      svg += "<g class=\"point\"><title>" + escape(p.tooltip) + "</title>";
      if (f.ay.drawable(p.y_lower) && f.ay.drawable(p.y_upper))
        svg += "<line x1=\"" + number(x) + "\" x2=\"" + number(x) + "\" y1=\"" + number(clamped_py(p.y_lower)) + "\" y2=\"" +
               number(clamped_py(p.y_upper)) + "\" stroke=\"" + g.color + "\"/>";
      svg += "<circle cx=\"" + number(x) + "\" cy=\"" + number(y) + "\" r=\"4\" fill=\"" + g.color + "\"/>";
      if (!p.label.empty() && (!g.label_front_only || std::find(front.begin(), front.end(), &p) != front.end()))
        svg += "<text x=\"" + number(x + 7) + "\" y=\"" + number(y + 4) + "\" font-size=\"10\">" + escape(p.label) + "</text>";
      svg += "</g>\n";
    }
    const double ly = f.legend_y(i);
    svg += "<circle cx=\"" + number(f.legend_x() + 8) + "\" cy=\"" + number(ly) + "\" r=\"4\" fill=\"" + g.color +
           "\"/><text x=\"" + number(f.legend_x() + 18) + "\" y=\"" + number(ly + 4) + "\">" + escape(g.name) + "</text>\n";
  }
  if (drawn == 0)
    svg += "<text x=\"" + number(f.left + f.w / 2) + "\" y=\"" + number(f.top + f.h / 2) + "\" text-anchor=\"middle\">" +
           escape(o.empty_note) + "</text>\n";
  svg += "</svg>\n";
  return svg;
}

}  // namespace visproxy
