// The table of proxy methods (proxy_methods.h): each row and the few lines that read its
// spec's parameters, state them in mesh units and call its builder.

#include "visproxy/proxy/proxy_methods.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <set>
#include <stdexcept>

#include "visproxy/core/errors.h"
#include "visproxy/proxy/alpha_wrap.h"
#include "visproxy/proxy/bounded_hull.h"
#include "visproxy/proxy/build_proxies.h"
#include "visproxy/proxy/circumsphere_set.h"
#include "visproxy/proxy/convex_hull.h"
#include "visproxy/proxy/inner_hull.h"
#include "visproxy/proxy/inscribed_spheres.h"
#include "visproxy/proxy/merge_spheres.h"
#include "visproxy/proxy/meshopt_simplify.h"
#include "visproxy/proxy/outer_hull.h"
#include "visproxy/proxy/proxy_spec.h"
#include "visproxy/proxy/quadric_simplify.h"
#include "visproxy/proxy/result_json.h"
#include "visproxy/proxy/vertex_clustering.h"

namespace visproxy {

void fail_spec(std::string_view spec, std::string_view problem) {
  throw Error("--proxy '" + std::string(spec) + "': " + std::string(problem));
}

namespace {

using nlohmann::json;
using Argument = ProxyMethodRow::Argument;

// ---------------------------------------------------------------------------------------
// Reading parameters.

std::size_t parse_count(const ProxySpec& spec, std::string_view text) {
  std::size_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || text.empty())
    fail_spec(spec.text, "N must be a whole number, got '" + std::string(text) + "'");
  if (value == 0) fail_spec(spec.text, "N must be at least 1");
  if (value > 100'000'000) fail_spec(spec.text, "N must be at most 100000000");
  return value;
}

double parse_fraction(const ProxySpec& spec, std::string_view what, std::string_view text) {
  double value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || text.empty() || !std::isfinite(value))
    fail_spec(spec.text, std::string(what) + " must be a number, got '" + std::string(text) + "'");
  if (value <= 0 || value > 1) fail_spec(spec.text, std::string(what) + " must be in (0, 1], got " + std::string(text));
  return value;
}

// Calls item(key, value) for each comma-separated item; value empty and key the item for
// items without '='. A key given twice is an error.
template <class Item>
void for_items(const ProxySpec& spec, std::string_view argument, Item&& item) {
  std::set<std::string_view> seen;
  std::string_view rest = argument;
  while (true) {
    const std::size_t comma = rest.find(',');
    const std::string_view text = rest.substr(0, comma);
    const std::size_t equals = text.find('=');
    if (equals != std::string_view::npos && !seen.insert(text.substr(0, equals)).second)
      fail_spec(spec.text, "'" + std::string(text.substr(0, equals)) + "' given twice");
    if (equals == std::string_view::npos)
      item(text, std::string_view());
    else
      item(text.substr(0, equals), text.substr(equals + 1));
    if (comma == std::string_view::npos) break;
    rest = rest.substr(comma + 1);
  }
}

void parse_nothing(ProxySpec&, std::string_view) {}

void parse_count_only(ProxySpec& spec, std::string_view argument) { spec.count = parse_count(spec, argument); }

// N, or P% of the input's triangles (as Blender's Decimate ratio), P in (0, 100].
void parse_count_or_share(ProxySpec& spec, std::string_view argument) {
  if (argument.empty() || argument.back() != '%') return parse_count_only(spec, argument);
  const std::string_view number = argument.substr(0, argument.size() - 1);
  double percent = 0;
  const auto [end, error] = std::from_chars(number.data(), number.data() + number.size(), percent);
  if (error != std::errc() || end != number.data() + number.size() || number.empty() || !std::isfinite(percent))
    fail_spec(spec.text, "P of P% must be a number, got '" + std::string(number) + "'");
  if (percent <= 0 || percent > 100) fail_spec(spec.text, "P of P% must be in (0, 100], got " + std::string(number));
  spec.count_share = percent / 100;
}

void parse_closed_count(ProxySpec& spec, std::string_view argument) {
  spec.count = parse_count(spec, argument);
  if (spec.count < 4) fail_spec(spec.text, "a closed mesh has at least 4 triangles");
}

// ---------------------------------------------------------------------------------------
// Parameters in mesh units.

json no_params(const ProxySpec&, const MethodContext&, std::size_t) { return json::object(); }
json max_triangles(const ProxySpec& spec, const MethodContext&, std::size_t) { return {{"max_triangles", spec.count}}; }

using detail::box_json;
using detail::interval_json;
using detail::to_json;

// ---------------------------------------------------------------------------------------
// The methods.

MethodPiece build_aabb(const ProxySpec&, const TriangleMesh& mesh, const BuildOptions&) {
  MethodPiece piece;
  piece.mesh = axis_aligned_box_mesh(mesh);
  const BoundingBox bounds = bounding_box(mesh);
  piece.boxes.push_back(
      {0.5 * (bounds.min + bounds.max), Eigen::Matrix3d::Identity(), 0.5 * (bounds.max - bounds.min)});
  piece.result = {{"min", to_json(bounds.min)}, {"max", to_json(bounds.max)}};
  return piece;
}

MethodPiece build_obb(const ProxySpec&, const TriangleMesh& mesh, const BuildOptions& options) {
  MethodPiece piece;
  OrientedBoxResult box = build_oriented_box(mesh, {.seed = static_cast<std::uint32_t>(options.seed)});
  piece.mesh = std::move(box.mesh);
  piece.boxes.push_back(box.box);
  piece.result = box_json(box.box);
  piece.result["volume"] = box.box.volume();
  piece.result["axes_from"] = box.axes_from;
  piece.result["inflation_world"] = box.inflation_world;
  return piece;
}

MethodPiece build_hull(const ProxySpec&, const TriangleMesh& mesh, const BuildOptions&) {
  MethodPiece piece;
  ConvexHullResult hull = build_convex_hull(mesh);
  piece.mesh = std::move(hull.mesh);
  piece.result = {{"faces", hull.faces}, {"volume", hull.volume}};
  return piece;
}

void parse_bounded_hull(ProxySpec& spec, std::string_view argument) {
  spec.count = parse_count(spec, argument);
  if (spec.count < 4) fail_spec(spec.text, "a closed convex polytope has at least 4 faces");
}
json bounded_hull_params(const ProxySpec& spec, const MethodContext&, std::size_t) {
  return {{"max_faces", spec.count}};
}
MethodPiece build_bounded(const ProxySpec& spec, const TriangleMesh& mesh, const BuildOptions&) {
  MethodPiece piece;
  BoundedHullResult hull = build_bounded_hull(mesh, {.max_faces = spec.count});
  piece.mesh = std::move(hull.mesh);
  piece.result = {{"faces", hull.faces},
                  {"volume", hull.volume},
                  {"hull_volume", hull.exact_hull_volume},
                  {"volume_over_hull", hull.added_volume_fraction()}};
  return piece;
}

void parse_wrap(ProxySpec& spec, std::string_view argument) {
  if (argument.empty()) return;
  for_items(spec, argument, [&](std::string_view key, std::string_view value) {
    if (value.empty()) fail_spec(spec.text, "expected alpha=A and/or offset=O, got '" + std::string(key) + "'");
    if (key == "alpha")
      spec.alpha_relative = parse_fraction(spec, "alpha", value);
    else if (key == "offset")
      spec.offset_relative = parse_fraction(spec, "offset", value);
    else
      fail_spec(spec.text, "unknown wrap parameter '" + std::string(key) + "' (expected alpha or offset)");
  });
}
json wrap_params(const ProxySpec& spec, const MethodContext& context, std::size_t) {
  return {{"alpha_relative", spec.alpha_relative},
          {"offset_relative", spec.offset_relative},
          {"alpha_world", spec.alpha_relative * context.diagonal},
          {"offset_world", spec.offset_relative * context.diagonal}};
}
MethodPiece build_wrap(const ProxySpec& spec, const TriangleMesh& mesh, const BuildOptions&) {
  MethodPiece piece;
  AlphaWrapResult wrap =
      build_alpha_wrap(mesh, {.alpha_relative = spec.alpha_relative, .offset_relative = spec.offset_relative});
  piece.mesh = std::move(wrap.mesh);
  piece.result = {{"alpha_world", wrap.alpha_world}, {"offset_world", wrap.offset_world}};
  return piece;
}

MethodPiece build_outer(const ProxySpec& spec, const TriangleMesh& mesh, const BuildOptions&) {
  MethodPiece piece;
  OuterHullResult outer = build_outer_hull(mesh, {.max_triangles = spec.count});
  piece.mesh = std::move(outer.mesh);
  piece.result = {{"reached_target", outer.reached_target},
                  {"wrap_triangles", outer.wrap_triangles},
                  {"wrap_alpha_world", outer.wrap_alpha_world},
                  {"wrap_offset_world", outer.wrap_offset_world},
                  {"max_distance_to_input_world", outer.max_distance_to_input_world},
                  {"clearance_world", outer.clearance_world},
                  {"clearance_kept", outer.clearance_kept}};
  return piece;
}

void parse_inner(ProxySpec& spec, std::string_view argument) {
  const std::size_t comma = argument.find(',');
  parse_closed_count(spec, argument.substr(0, comma));
  if (comma == std::string_view::npos) return;
  const std::string_view item = argument.substr(comma + 1);
  if (!item.starts_with("grid="))
    fail_spec(spec.text, "unknown inner parameter '" + std::string(item) + "' (expected grid=G)");
  spec.grid_cells = parse_count(spec, item.substr(5));
  if (spec.grid_cells < 4 || spec.grid_cells > 1024) fail_spec(spec.text, "grid must be between 4 and 1024 cells");
}
json inner_params(const ProxySpec& spec, const MethodContext&, std::size_t) {
  return {{"max_triangles", spec.count},
          {"grid_cells", spec.grid_cells != 0 ? spec.grid_cells : inner_hull_grid_cells(spec.count)}};
}
MethodPiece build_inner(const ProxySpec& spec, const TriangleMesh& mesh, const BuildOptions&) {
  MethodPiece piece;
  InnerHullResult inner = build_inner_hull(mesh, {.max_triangles = spec.count, .grid_cells = spec.grid_cells});
  if (inner.mesh.triangles.empty())
    throw InvalidInputError("", "the solid is thinner everywhere than about one grid cell (" +
                                    std::to_string(inner.grid_cell_world) +
                                    " mesh units): no inner hull on this grid; a larger grid=G resolves thinner parts");
  piece.mesh = std::move(inner.mesh);
  piece.result = {{"reached_target", inner.reached_target},
                  {"start_triangles", inner.start_triangles},
                  {"grid_cell_world", inner.grid_cell_world},
                  {"components_dropped", inner.components_dropped},
                  {"volume", inner.volume},
                  {"clearance_world", inner.clearance_world},
                  {"clearance_kept", inner.clearance_kept},
                  {"relax_passes_kept", inner.relax_passes_kept},
                  {"max_distance_to_input_world", inner.max_distance_to_input_world}};
  return piece;
}

MethodPiece build_quadric(const ProxySpec& spec, const TriangleMesh& mesh, const BuildOptions&) {
  MethodPiece piece;
  QuadricSimplifyResult simplified = simplify_quadric(mesh, {.max_triangles = spec.count});
  piece.mesh = std::move(simplified.mesh);
  piece.result = {{"collapses", simplified.collapses},
                  {"max_quadric_error_world", simplified.max_quadric_error_relative * bounding_box(mesh).diagonal()}};
  return piece;
}

MethodPiece build_meshopt(const ProxySpec& spec, const TriangleMesh& mesh, const BuildOptions&) {
  MethodPiece piece;
  MeshoptSimplifyResult simplified = simplify_meshopt(mesh, {.max_triangles = spec.count});
  piece.mesh = std::move(simplified.mesh);
  piece.result = {{"reached_target", simplified.reached_target},
                  {"sloppy_pass", simplified.sloppy_pass},
                  {"meshopt_error_world", simplified.error_world}};
  return piece;
}

void parse_cluster(ProxySpec& spec, std::string_view argument) {
  spec.cell_size_relative = parse_fraction(spec, "F", argument);
}
json cluster_params(const ProxySpec& spec, const MethodContext& context, std::size_t) {
  return {{"cell_size_relative", spec.cell_size_relative},
          {"cell_size_world", spec.cell_size_relative * (context.bounds.max - context.bounds.min).maxCoeff()}};
}
MethodPiece build_cluster(const ProxySpec& spec, const TriangleMesh& mesh, const BuildOptions&) {
  MethodPiece piece;
  VertexClusteringResult clustered = cluster_vertices(mesh, {.cell_size_relative = spec.cell_size_relative});
  piece.mesh = std::move(clustered.mesh);
  piece.result = {{"cell_size_world", clustered.cell_size_world},
                  {"max_vertex_displacement_world", clustered.max_vertex_displacement_world}};
  return piece;
}

void parse_inside(ProxySpec& spec, std::string_view argument) {
  spec.count = parse_count(spec, argument);
  spec.levels = {spec.count};
}
json inside_params(const ProxySpec& spec, const MethodContext& context, std::size_t) {
  const InscribedSpheresOptions defaults;
  return {{"spheres", spec.count},
          {"margin_relative", defaults.margin_relative},
          {"margin_world", inscribed_sphere_margin(context.bounds, defaults.margin_relative)},
          {"volume_samples", defaults.volume_samples},
          {"coverage_samples", defaults.coverage_samples}};
}
MethodPiece build_inside(const ProxySpec& spec, const TriangleMesh& mesh, const BuildOptions& options) {
  MethodPiece piece;
  InscribedSpheres built = build_inscribed_spheres(mesh, {.count = spec.count, .seed = options.seed});
  piece.result = {{"candidates", built.candidates},
                  {"surface_samples", built.surface_samples},
                  {"mesh_volume", built.mesh_volume},
                  {"covered_volume_fraction", interval_json(built.covered_volume_fraction, built.covered_volume_lower,
                                                            built.covered_volume_upper)},
                  {"coverage_samples", built.coverage_hits.trials},
                  {"coverage_seed", built.coverage_seed},
                  {"min_margin_world", built.min_margin_world},
                  {"spheres_shrunk", built.spheres_shrunk}};
  piece.levels.push_back(std::move(built.spheres));
  return piece;
}

void parse_spheres(ProxySpec& spec, std::string_view argument) {
  for_items(spec, argument, [&](std::string_view key, std::string_view value) {
    if (value.empty()) {
      spec.levels.push_back(parse_count(spec, key));
    } else if (key == "pair" && (value == "d1" || value == "d2")) {
      spec.pair_distance = value == "d1" ? PairDistance::d1 : PairDistance::d2;
    } else if (key == "merge" && (value == "exact" || value == "analytic")) {
      spec.merge_radius = value == "exact" ? MergeRadius::exact : MergeRadius::analytic;
    } else if (key == "samples") {
      spec.samples = parse_count(spec, value);
      if (spec.samples < 4) fail_spec(spec.text, "samples must be at least 4 (one tetrahedron)");
    } else {
      fail_spec(spec.text, "unknown spheres parameter '" + std::string(key) + "=" + std::string(value) +
                               "' (expected pair=d1|d2, merge=exact|analytic, samples=S)");
    }
  });
  if (spec.levels.empty()) fail_spec(spec.text, "expected spheres:N[,N2,...]: at least one sphere count");
  std::sort(spec.levels.begin(), spec.levels.end(), std::greater<>());
  if (std::adjacent_find(spec.levels.begin(), spec.levels.end()) != spec.levels.end())
    fail_spec(spec.text, "a sphere count is given twice");
}
std::size_t circumsphere_samples(const ProxySpec& spec) {
  return spec.samples > 0 ? spec.samples : default_circumsphere_samples(spec.levels.front());
}
json spheres_params(const ProxySpec& spec, const MethodContext& context, std::size_t level) {
  return {{"spheres", spec.levels[level]},
          {"levels", spec.levels},
          {"pair_distance", pair_distance_name(spec.pair_distance)},
          {"merge_radius", spec.merge_radius == MergeRadius::exact ? "exact" : "analytic"},
          {"samples", circumsphere_samples(spec)},
          {"tets", name_of(context.options->tets)}};
}
MethodPiece build_spheres(const ProxySpec& spec, const TriangleMesh& mesh, const BuildOptions& options) {
  MethodPiece piece;
  const CircumsphereSet set = build_circumsphere_set(
      mesh, {.tetrahedra = options.tets, .samples = circumsphere_samples(spec), .seed = options.seed});
  piece.levels =
      merge_spheres(set.spheres, spec.levels, {.pair_distance = spec.pair_distance, .radius = spec.merge_radius});
  piece.result = {{"points", set.points}, {"tetrahedra", set.tetrahedra}, {"initial_spheres", set.spheres.size()}};
  piece.summary = {{"levels_built_together", spec.levels}};
  return piece;
}

}  // namespace

const std::vector<ProxyMethodRow>& proxy_methods() {
  using K = ProxyKind;
  using P = PrimitiveType;
  static const std::vector<ProxyMethodRow> rows{
      {"aabb", "aabb", "aabb", Argument::none, K::outside, P::box, "axis-aligned bounding box",
       "axis-aligned bounding box", 4, parse_nothing, no_params, build_aabb, "", false},
      {"obb", "obb", "obb", Argument::none, K::outside, P::box, "oriented bounding box",
       "oriented bounding box (CGAL optimal box, principal axes or axis-aligned: smallest)", 2, parse_nothing,
       no_params, build_obb, "", false},
      {"convex_hull", "hull", "hull", Argument::none, K::outside, P::triangle, "convex hull", "convex hull (CGAL)", 3,
       parse_nothing, no_params, build_hull, "", false},
      {"bounded_hull", "hull", "hull:N", Argument::required, K::outside, P::triangle,
       "convex polytope with at most N faces", "convex hull simplified by greedy half-space removal", 2,
       parse_bounded_hull, bounded_hull_params, build_bounded, "", false},
      {"alpha_wrap", "wrap", "wrap[:alpha=A,offset=O]", Argument::optional, K::outside, P::triangle,
       "alpha wrap; A, O relative to the bbox diagonal (either may be left out; 1/20 and 1/600)",
       "3D alpha wrap (CGAL)", 1, parse_wrap, wrap_params, build_wrap, "", false},
      {"outer_hull", "outer", "outer:N", Argument::required, K::outside, P::triangle,
       "non-convex outside mesh, at most N triangles", "alpha wrap decimated by conservative edge collapses", 0,
       parse_closed_count, max_triangles, build_outer, "", false},
      {"inner_hull", "inner", "inner:N[,grid=G]", Argument::required, K::inside, P::triangle,
       "non-convex inside mesh, at most N triangles, started from a grid of G cells along the longest side (default "
       "sqrt(2N), 16-256)",
       "marching-tetrahedra surface inside the solid, decimated by conservative edge collapses", 0, parse_inner,
       inner_params, build_inner, "", false},
      {"quadric", "quadric", "quadric:N|P%", Argument::required, K::general, P::triangle,
       "quadric edge collapse to at most N triangles, or P % of the mesh's", "quadric edge collapse", 3,
       parse_count_or_share, max_triangles, build_quadric, "", false},
      {"meshopt", "meshopt", "meshopt:N|P%", Argument::required, K::general, P::triangle,
       "meshoptimizer's simplifier to at most N triangles, or P % of the mesh's (its sloppy pass where topology stops it)",
       "meshoptimizer 0.18 edge collapse (meshopt_simplify, then meshopt_simplifySloppy if above the budget)", 4,
       parse_count_or_share, max_triangles, build_meshopt, " (use a larger N)", false},
      {"clustering", "cluster", "cluster:F", Argument::required, K::general, P::triangle,
       "vertex clustering, cell F x largest bbox extent", "vertex clustering", 4, parse_cluster, cluster_params,
       build_cluster, " (use a smaller cell)", false},
      {"inscribed_spheres", "inside", "inside:N", Argument::required, K::inside, P::sphere,
       "N maximal spheres inscribed in a closed mesh",
       "maximal inscribed spheres: inner Voronoi poles, greedy volume cover, exact containment check", 1, parse_inside,
       inside_params, build_inside, "", true},
      {"sphere_set", "spheres", "spheres:N[,N2,...][,pair=d1|d2][,merge=exact|analytic][,samples=S]",
       Argument::required, K::general, P::sphere,
       "Delaunay circumsphere set merged to N (and N2, ...) spheres, all levels in one pass, one proxy each named "
       "spheres-N; pair: "
       "D1 = d or D2 = d + r - R (default d2); merge: the GSSA each merge keeps, exact (default) or the paper's "
       "analytic "
       "overestimates; samples: surface samples triangulated (default max(4000, 4 x largest N))",
       "Delaunay circumsphere set merged pairwise keeping the GSSA (occluding spheres)", 1, parse_spheres,
       spheres_params, build_spheres, "", false},
  };
  return rows;
}

const ProxyMethodRow& proxy_method(std::string_view id) {
  for (const ProxyMethodRow& row : proxy_methods())
    if (row.id == id) return row;
  throw std::logic_error("no proxy method " + std::string(id));
}

std::string proxy_spec_help() {
  std::size_t width = 0;
  for (const ProxyMethodRow& row : proxy_methods()) width = std::max(width, row.grammar.size());
  width = std::min<std::size_t>(width, 20);
  std::string text;
  for (const ProxyMethodRow& row : proxy_methods()) {
    std::string line = "  " + std::string(row.grammar);
    line += row.grammar.size() < width ? std::string(width - row.grammar.size() + 2, ' ')
                                       : std::string("\n") + std::string(width + 4, ' ');
    text += line + std::string(row.summary) + " (" + std::string(kind_name(row.kind)) + ")\n";
  }
  return text;
}

std::string_view primitive_type_name(PrimitiveType type) {
  switch (type) {
    case PrimitiveType::triangle:
      return "triangle";
    case PrimitiveType::box:
      return "box";
    case PrimitiveType::sphere:
      return "sphere";
  }
  return "triangle";
}

}  // namespace visproxy
