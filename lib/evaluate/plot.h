#pragma once
// Small self-contained SVG line plots for reports.

#include <string>
#include <vector>

namespace visproxy {

struct PlotSeries {
  std::string name;
  std::vector<double> x, y;
};

struct PlotOptions {
  std::string title, x_label, y_label;
  bool log_x = false, log_y = false;
  int width = 720, height = 440;
};

/// One polyline with markers per series, axes with ticks (decades on log axes), a legend.
/// Points that cannot be drawn (non-positive on a log axis, NaN) are left out.
std::string line_plot_svg(const std::vector<PlotSeries>& series, const PlotOptions& options);

}  // namespace visproxy
