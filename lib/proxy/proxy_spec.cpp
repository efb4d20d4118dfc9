#include "visproxy/proxy/proxy_spec.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <set>

#include "visproxy/core/errors.h"

namespace visproxy {
namespace {

[[noreturn]] void fail(std::string_view spec, std::string_view problem) {
  throw Error("--proxy '" + std::string(spec) + "': " + std::string(problem));
}

std::size_t parse_count(std::string_view spec, std::string_view text) {
  std::size_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || text.empty())
    fail(spec, "N must be a whole number, got '" + std::string(text) + "'");
  if (value == 0) fail(spec, "N must be at least 1");
  if (value > 100'000'000) fail(spec, "N must be at most 100000000");
  return value;
}

double parse_fraction(std::string_view spec, std::string_view what, std::string_view text) {
  double value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || text.empty() || !std::isfinite(value))
    fail(spec, std::string(what) + " must be a number, got '" + std::string(text) + "'");
  if (value <= 0 || value > 1) fail(spec, std::string(what) + " must be in (0, 1], got " + std::string(text));
  return value;
}

}  // namespace

std::string ProxySpec::name() const { return output_names().front(); }

std::vector<std::string> ProxySpec::output_names() const {
  if (method == ProxyMethod::sphere_set) {
    std::vector<std::string> names;
    for (const std::size_t level : levels) names.push_back("spheres-" + std::to_string(level));
    return names;
  }
  std::string name = text;
  for (char& c : name)
    if (c == ':' || c == ',') c = '-';
  return {name};
}

ProxyKind ProxySpec::kind() const {
  switch (method) {
    case ProxyMethod::quadric:
    case ProxyMethod::clustering:
    case ProxyMethod::sphere_set: return ProxyKind::general;
    case ProxyMethod::inscribed_spheres:
    case ProxyMethod::inner_hull: return ProxyKind::inside;
    default: return ProxyKind::outside;
  }
}

ProxySpec parse_proxy_spec(std::string_view text) {
  ProxySpec spec;
  spec.text = std::string(text);
  const std::size_t colon = text.find(':');
  const std::string_view method = text.substr(0, colon);
  const bool has_argument = colon != std::string_view::npos;
  const std::string_view argument = has_argument ? text.substr(colon + 1) : std::string_view();
  auto require_argument = [&](std::string_view form) {
    if (!has_argument || argument.empty()) fail(text, "expected " + std::string(form));
  };
  auto forbid_argument = [&]() {
    if (has_argument) fail(text, std::string(method) + " takes no parameters");
  };

  if (method == "aabb") {
    forbid_argument();
    spec.method = ProxyMethod::aabb;
  } else if (method == "obb") {
    forbid_argument();
    spec.method = ProxyMethod::obb;
  } else if (method == "hull") {
    if (has_argument) {
      spec.method = ProxyMethod::bounded_hull;
      spec.count = parse_count(text, argument);
      if (spec.count < 4) fail(text, "a closed convex polytope has at least 4 faces");
    } else {
      spec.method = ProxyMethod::convex_hull;
    }
  } else if (method == "wrap") {
    spec.method = ProxyMethod::alpha_wrap;
    if (has_argument) {
      std::set<std::string_view> seen;
      std::string_view rest = argument;
      while (true) {
        const std::size_t comma = rest.find(',');
        const std::string_view item = rest.substr(0, comma);
        const std::size_t equals = item.find('=');
        if (equals == std::string_view::npos) fail(text, "expected alpha=A and/or offset=O, got '" + std::string(item) + "'");
        const std::string_view key = item.substr(0, equals);
        const std::string_view value = item.substr(equals + 1);
        if (!seen.insert(key).second) fail(text, "'" + std::string(key) + "' given twice");
        if (key == "alpha") spec.alpha_relative = parse_fraction(text, "alpha", value);
        else if (key == "offset") spec.offset_relative = parse_fraction(text, "offset", value);
        else fail(text, "unknown wrap parameter '" + std::string(key) + "' (expected alpha or offset)");
        if (comma == std::string_view::npos) break;
        rest = rest.substr(comma + 1);
      }
    }
  } else if (method == "outer") {
    require_argument("outer:N");
    spec.method = ProxyMethod::outer_hull;
    spec.count = parse_count(text, argument);
    if (spec.count < 4) fail(text, "a closed mesh has at least 4 triangles");
  } else if (method == "inner") {
    require_argument("inner:N[,grid=G]");
    spec.method = ProxyMethod::inner_hull;
    const std::size_t comma = argument.find(',');
    spec.count = parse_count(text, argument.substr(0, comma));
    if (spec.count < 4) fail(text, "a closed mesh has at least 4 triangles");
    if (comma != std::string_view::npos) {
      const std::string_view item = argument.substr(comma + 1);
      if (!item.starts_with("grid=")) fail(text, "unknown inner parameter '" + std::string(item) + "' (expected grid=G)");
      spec.grid_cells = parse_count(text, item.substr(5));
      if (spec.grid_cells < 4 || spec.grid_cells > 1024) fail(text, "grid must be between 4 and 1024 cells");
    }
  } else if (method == "quadric") {
    require_argument("quadric:N");
    spec.method = ProxyMethod::quadric;
    spec.count = parse_count(text, argument);
  } else if (method == "cluster") {
    require_argument("cluster:F");
    spec.method = ProxyMethod::clustering;
    spec.cell_size_relative = parse_fraction(text, "F", argument);
  } else if (method == "inside") {
    require_argument("inside:N");
    spec.method = ProxyMethod::inscribed_spheres;
    spec.count = parse_count(text, argument);
  } else if (method == "spheres") {
    require_argument("spheres:N[,N2,...]");
    spec.method = ProxyMethod::sphere_set;
    std::set<std::string_view> seen;
    std::string_view rest = argument;
    while (true) {
      const std::size_t comma = rest.find(',');
      const std::string_view item = rest.substr(0, comma);
      const std::size_t equals = item.find('=');
      if (equals == std::string_view::npos) {
        spec.levels.push_back(parse_count(text, item));
      } else {
        const std::string_view key = item.substr(0, equals);
        const std::string_view value = item.substr(equals + 1);
        if (!seen.insert(key).second) fail(text, "'" + std::string(key) + "' given twice");
        if (key == "pair" && (value == "d1" || value == "d2")) {
          spec.pair_distance = value == "d1" ? PairDistance::d1 : PairDistance::d2;
        } else if (key == "merge" && (value == "exact" || value == "analytic")) {
          spec.merge_radius = value == "exact" ? MergeRadius::exact : MergeRadius::analytic;
        } else if (key == "samples") {
          spec.samples = parse_count(text, value);
          if (spec.samples < 4) fail(text, "samples must be at least 4 (one tetrahedron)");
        } else {
          fail(text, "unknown spheres parameter '" + std::string(item) +
                         "' (expected pair=d1|d2, merge=exact|analytic, samples=S)");
        }
      }
      if (comma == std::string_view::npos) break;
      rest = rest.substr(comma + 1);
    }
    if (spec.levels.empty()) fail(text, "expected spheres:N[,N2,...]: at least one sphere count");
    std::sort(spec.levels.begin(), spec.levels.end(), std::greater<>());
    if (std::adjacent_find(spec.levels.begin(), spec.levels.end()) != spec.levels.end())
      fail(text, "a sphere count is given twice");
  } else {
    fail(text, "unknown proxy '" + std::string(method) +
                   "' (expected aabb, obb, hull, hull:N, wrap, wrap:alpha=A,offset=O, outer:N, inner:N, quadric:N, "
                   "cluster:F, inside:N, spheres:N[,N2,...])");
  }
  return spec;
}

std::vector<ProxySpec> default_proxy_specs() {
  return parse_proxy_specs(
      {"aabb", "obb", "hull", "hull:32", "wrap", "outer:512", "quadric:512", "cluster:0.03", "inside:40", "spheres:100"});
}

std::vector<ProxySpec> parse_proxy_specs(const std::vector<std::string>& texts) {
  std::vector<ProxySpec> specs;
  std::set<std::string> names;
  for (const std::string& text : texts) {
    ProxySpec spec = parse_proxy_spec(text);
    for (const std::string& name : spec.output_names())
      if (!names.insert(name).second) fail(text, "the proxy '" + name + "' is asked for twice");
    specs.push_back(std::move(spec));
  }
  return specs;
}

}  // namespace visproxy
