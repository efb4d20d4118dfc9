#pragma once
// Small self-contained SVG line plots for reports.

#include <cmath>
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

/// One point of a scatter plot: a value with its interval (NaN: none drawn), a label
/// written beside it and a tooltip.
struct ScatterPoint {
  double x = 0, y = 0;
  double y_lower = std::nan(""), y_upper = std::nan("");
  std::string label, tooltip;
};

struct ScatterGroup {
  std::string name;   ///< in the legend
  std::string color;  ///< CSS colour
  std::vector<ScatterPoint> points;
  /// Join the group's Pareto front (the points no other of the group beats with a smaller
  /// or equal x and a larger or equal y) with a step line.
  bool pareto_front = false;
  /// Label only the points on that front (the rest keep their tooltips).
  bool label_front_only = false;
};

struct ScatterOptions {
  std::string title, x_label, y_label;
  bool log_x = false, log_y = false;
  /// A fixed y range instead of one fitted to the points (both finite to apply).
  double y_min = std::nan(""), y_max = std::nan("");
  /// A dashed horizontal line at this y, with its label (NaN: none).
  double reference_y = std::nan("");
  std::string reference_label;
  /// What the plot says instead of points when no group has one.
  std::string empty_note = "nothing to plot";
  int width = 720, height = 420;
};

/// Points with their intervals, coloured by group, each a <g class="point"> with a <title>;
/// axes with ticks (decades on log axes) and a legend. Points that cannot be drawn are left out.
std::string scatter_plot_svg(const std::vector<ScatterGroup>& groups, const ScatterOptions& options);

}  // namespace visproxy
