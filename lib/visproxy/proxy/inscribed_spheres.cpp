// Maximal inscribed spheres for inside proxies (Billen, Lagae, Dutre, "Probabilistic
// visibility evaluation using geometry proxies", EGSR 2014, section 3.4 and the dragon's 40
// spheres). Candidate centres are inner Voronoi poles of surface samples, which converge to
// the medial axis as the samples get denser (N. Amenta, S. Choi, R. Kolluri, "The power
// crust", SMA 2001); the choice among them is greedy maximum coverage of the volume
// (G. Nemhauser, L. Wolsey, M. Fisher, 1978: within 1 - 1/e of the optimum; lazy
// evaluation after M. Minoux, 1978).

#include "visproxy/proxy/inscribed_spheres.h"

#include <CGAL/box_intersection_d.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <queue>
#include <string>
#include <tuple>

#include "visproxy/core/errors.h"
#include "visproxy/core/random.h"
#include "visproxy/proxy/detail/delaunay_cells.h"
#include "visproxy/proxy/surface_distance.h"
#include "visproxy/proxy/detail/surface_samples.h"
#include "visproxy/proxy/detail/watertight_input.h"
#include "visproxy/verify/containment.h"
#include "visproxy/verify/sphere_containment.h"

namespace visproxy {
namespace {

using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::uint32_t>;

constexpr double kZ95 = 1.959964;

// Distinct random streams from one seed.
constexpr std::uint64_t kVolumeStream = 0x766F6C756D65ull;
constexpr std::uint64_t kCoverageStream = 0x636F76657261ull;

Vertex uniform_in_ball(Random& random, const Sphere& ball) {
  const double radius = ball.radius * std::cbrt(random.uniform());
  return ball.center + radius * random.unit_vector();
}

Box point_box(const Vertex& p, std::uint32_t id) {
  double low[3] = {p.x(), p.y(), p.z()};
  return Box(low, low, id);
}

Box ball_box(const Sphere& s, std::uint32_t id) {
  double low[3] = {s.center.x() - s.radius, s.center.y() - s.radius, s.center.z() - s.radius};
  double high[3] = {s.center.x() + s.radius, s.center.y() + s.radius, s.center.z() + s.radius};
  return Box(low, high, id);
}

// For every point, the balls that hold it (closed balls), each list sorted.
std::vector<std::vector<std::uint32_t>> balls_holding(const std::vector<Vertex>& points, const std::vector<Sphere>& balls) {
  std::vector<Box> point_boxes, ball_boxes;
  point_boxes.reserve(points.size());
  ball_boxes.reserve(balls.size());
  for (std::uint32_t i = 0; i < points.size(); ++i) point_boxes.push_back(point_box(points[i], i));
  for (std::uint32_t i = 0; i < balls.size(); ++i) ball_boxes.push_back(ball_box(balls[i], i));
  std::vector<std::vector<std::uint32_t>> holding(points.size());
  CGAL::box_intersection_d(point_boxes.begin(), point_boxes.end(), ball_boxes.begin(), ball_boxes.end(),
                           [&](const Box& point, const Box& ball) {
                             const Sphere& s = balls[ball.info()];
                             if ((points[point.info()] - s.center).squaredNorm() <= s.radius * s.radius)
                               holding[point.info()].push_back(ball.info());
                           },
                           std::ptrdiff_t(10), CGAL::Box_intersection_d::CLOSED);
  for (auto& list : holding) std::sort(list.begin(), list.end());
  return holding;
}

// Greedy weighted maximum coverage: `count` balls, each covering the most weight not yet
// covered. Lazy: a ball's gain only falls as others are chosen (and as its radius is
// corrected), so a stale gain that still tops the queue after recomputation is the true
// maximum. `measure(ball)` returns the ball's true radius (<= its estimate), called once per
// ball when it first reaches the top; balls of radius <= 0 drop out.
template <typename Measure>
std::vector<std::uint32_t> choose_greedily(std::vector<Sphere>& balls, const std::vector<Vertex>& points,
                                           const std::vector<std::vector<std::uint32_t>>& holding, std::size_t count,
                                           Measure&& measure) {
  std::vector<std::vector<std::uint32_t>> held(balls.size());  // points in each ball
  std::vector<double> weight(points.size(), 0);
  for (std::uint32_t p = 0; p < points.size(); ++p) {
    weight[p] = holding[p].empty() ? 0.0 : 1.0 / static_cast<double>(holding[p].size());
    for (const std::uint32_t ball : holding[p]) held[ball].push_back(p);
  }
  std::vector<std::uint8_t> covered(points.size(), 0);
  auto gain_of = [&](std::uint32_t ball) {
    double gain = 0;
    for (const std::uint32_t p : held[ball])
      if (!covered[p]) gain += weight[p];
    return gain;
  };
  // (gain, radius, -index): with nothing left to gain, larger balls first.
  using Entry = std::tuple<double, double, std::int64_t>;
  std::priority_queue<Entry> queue;
  for (std::uint32_t ball = 0; ball < balls.size(); ++ball)
    queue.emplace(gain_of(ball), balls[ball].radius, -static_cast<std::int64_t>(ball));
  std::vector<std::uint8_t> measured(balls.size(), 0);
  std::vector<std::uint32_t> order;
  while (order.size() < count && !queue.empty()) {
    const auto [gain, radius, negative_index] = queue.top();
    queue.pop();
    const auto ball = static_cast<std::uint32_t>(-negative_index);
    if (!measured[ball]) {
      measured[ball] = 1;
      balls[ball].radius = std::min(balls[ball].radius, measure(ball));
      if (!(balls[ball].radius > 0)) continue;
      const Sphere& b = balls[ball];
      std::erase_if(held[ball], [&](std::uint32_t p) { return (points[p] - b.center).squaredNorm() > b.radius * b.radius; });
    }
    const double current = gain_of(ball);
    const Entry updated(current, balls[ball].radius, negative_index);
    if (!queue.empty() && updated < queue.top()) {
      queue.push(updated);
      continue;
    }
    order.push_back(ball);
    for (const std::uint32_t p : held[ball]) covered[p] = 1;
  }
  return order;
}

// A uniform grid over a box listing the balls that meet each cell (by their bounding
// boxes): "which balls may hold this point" in O(1) cells. Balls are added one by one.
class BallGrid {
 public:
  BallGrid(const BoundingBox& box, std::size_t expected_balls) : box_(box) {
    const Vertex extent = (box.max - box.min).cwiseMax(Vertex::Constant(1e-300));
    const double cell = std::cbrt(extent.prod() / (8.0 * static_cast<double>(expected_balls) + 1.0));
    for (int axis = 0; axis < 3; ++axis)
      cells_[static_cast<std::size_t>(axis)] = std::clamp(static_cast<int>(std::ceil(extent[axis] / cell)), 1, 128);
    lists_.resize(static_cast<std::size_t>(cells_[0] * cells_[1] * cells_[2]));
  }
  void add(const Sphere& ball) {
    const auto id = static_cast<std::uint32_t>(balls_.size());
    balls_.push_back(ball);
    const auto low = cell_of(ball.center - Vertex::Constant(ball.radius));
    const auto high = cell_of(ball.center + Vertex::Constant(ball.radius));
    for (int z = low[2]; z <= high[2]; ++z)
      for (int y = low[1]; y <= high[1]; ++y)
        for (int x = low[0]; x <= high[0]; ++x) lists_[index(x, y, z)].push_back(id);
  }
  /// Balls whose bounding box may hold p (a superset of the balls holding p).
  const std::vector<std::uint32_t>& near(const Vertex& p) const {
    const auto c = cell_of(p);
    return lists_[index(c[0], c[1], c[2])];
  }
  const Sphere& ball(std::uint32_t id) const { return balls_[id]; }
  bool holds(const Vertex& p) const {
    for (const std::uint32_t i : near(p))
      if ((p - balls_[i].center).squaredNorm() <= balls_[i].radius * balls_[i].radius) return true;
    return false;
  }

 private:
  std::array<int, 3> cell_of(const Vertex& p) const {
    std::array<int, 3> c{};
    for (std::size_t axis = 0; axis < 3; ++axis) {
      const double t = (p[static_cast<int>(axis)] - box_.min[static_cast<int>(axis)]) /
                       (box_.max[static_cast<int>(axis)] - box_.min[static_cast<int>(axis)]);
      c[axis] = std::clamp(static_cast<int>(std::isfinite(t) ? t * cells_[axis] : 0.0), 0, cells_[axis] - 1);
    }
    return c;
  }
  std::size_t index(int x, int y, int z) const { return static_cast<std::size_t>((z * cells_[1] + y) * cells_[0] + x); }
  BoundingBox box_;
  std::array<int, 3> cells_{1, 1, 1};
  std::vector<Sphere> balls_;
  std::vector<std::vector<std::uint32_t>> lists_;
};

// Drops balls that poke out of a larger kept ball by at most `slack` of their own radius:
// nearly held balls add little volume but much overlap to the cover. Largest first.
std::vector<Sphere> drop_nearly_held(std::vector<Sphere> balls, const BoundingBox& box, double slack) {
  std::stable_sort(balls.begin(), balls.end(), [](const Sphere& a, const Sphere& b) { return a.radius > b.radius; });
  BallGrid grid(box, balls.size());
  std::vector<Sphere> kept;
  for (const Sphere& ball : balls) {
    bool held = false;
    for (const std::uint32_t id : grid.near(ball.center)) {
      const Sphere& larger = grid.ball(id);
      if ((ball.center - larger.center).norm() + ball.radius * (1 - slack) <= larger.radius) {
        held = true;
        break;
      }
    }
    if (held) continue;
    kept.push_back(ball);
    grid.add(ball);
  }
  return kept;
}

}  // namespace

double inscribed_sphere_margin(const BoundingBox& bounds, double margin_relative) {
  if (margin_relative == 0 || bounds.empty()) return 0;
  const double magnitude = std::max(bounds.min.cwiseAbs().maxCoeff(), bounds.max.cwiseAbs().maxCoeff());
  return margin_relative * bounds.diagonal() + 0x1.0p-22 * magnitude;
}

InscribedSpheres build_inscribed_spheres(const TriangleMesh& mesh, const InscribedSpheresOptions& options) {
  if (options.count == 0) throw InvalidInputError("", "an inside proxy needs at least one sphere");
  require_closed(mesh,
                 "an inside proxy must lie within the solid the surface bounds, {winding number != 0}, and only a "
                 "closed surface (every edge used as often in each direction) bounds one");
  InscribedSpheres result;
  const double volume = signed_volume(mesh);
  result.mesh_volume = std::abs(volume);
  if (!(result.mesh_volume > 0)) throw InvalidInputError("", "the mesh encloses no volume: nothing fits inside it");
  const BoundingBox bounds = bounding_box(mesh);
  const double diagonal = bounds.diagonal();
  const double outward = volume > 0 ? 1.0 : -1.0;

  // Candidate centres: the inner pole of each surface sample.
  result.surface_samples = options.surface_samples > 0
                               ? options.surface_samples
                               : std::min<std::size_t>(2'000'000, std::max<std::size_t>(20000, 8 * options.count));
  const std::vector<SurfaceSample> samples = sample_surface_evenly(mesh, result.surface_samples, options.seed);
  std::vector<Vertex> points;
  points.reserve(samples.size());
  for (const SurfaceSample& sample : samples) points.push_back(sample.position);
  const std::vector<DelaunayCell> cells = delaunay_cells(points);
  constexpr std::uint32_t kNoPole = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> pole(points.size(), kNoPole);
  for (std::uint32_t c = 0; c < cells.size(); ++c) {
    const Sphere& sphere = cells[c].circumsphere;
    for (const std::uint32_t corner : cells[c].corners) {
      if (outward * (sphere.center - points[corner]).dot(samples[corner].normal) >= 0) continue;  // outer side
      if (pole[corner] == kNoPole || sphere.radius > cells[pole[corner]].circumsphere.radius) pole[corner] = c;
    }
  }
  // One pole per cell of a grid (the largest circumsphere in it): candidates spread along
  // the whole medial axis instead of thousands of near copies of the biggest balls.
  const double cell = diagonal / std::max(64.0, 8.0 * std::sqrt(static_cast<double>(options.count)));
  std::vector<std::pair<std::array<std::int64_t, 3>, std::uint32_t>> keyed;
  for (const std::uint32_t c : pole) {
    if (c == kNoPole) continue;
    const Vertex& center = cells[c].circumsphere.center;
    if ((center.array() <= bounds.min.array()).any() || (center.array() >= bounds.max.array()).any())
      continue;  // outside the box, so outside the mesh
    const Vertex grid = (center - bounds.min) / cell;
    keyed.push_back({{static_cast<std::int64_t>(grid.x()), static_cast<std::int64_t>(grid.y()),
                      static_cast<std::int64_t>(grid.z())},
                     c});
  }
  std::sort(keyed.begin(), keyed.end(), [&](const auto& a, const auto& b) {
    if (a.first != b.first) return a.first < b.first;
    const double ra = cells[a.second].circumsphere.radius, rb = cells[b.second].circumsphere.radius;
    return ra > rb || (ra == rb && a.second < b.second);
  });
  std::vector<std::uint32_t> thinned;
  for (std::size_t k = 0; k < keyed.size(); ++k)
    if (k == 0 || keyed[k].first != keyed[k - 1].first) thinned.push_back(keyed[k].second);

  std::vector<Vertex> centers;
  for (const std::uint32_t c : thinned) centers.push_back(cells[c].circumsphere.center);
  const std::vector<PointLocation> locations = locate_points(mesh, centers);
  const double margin = inscribed_sphere_margin(bounds, options.margin_relative);
  // Until measured, a candidate's radius is its circumradius (the sphere through four
  // samples), an estimate of its distance to the surface.
  std::vector<Sphere> candidates;
  for (std::size_t i = 0; i < thinned.size(); ++i)
    if (locations[i] == PointLocation::inside) candidates.push_back(cells[thinned[i]].circumsphere);
  result.candidates = candidates.size();
  if (candidates.size() > options.count) {
    std::vector<Sphere> spread = drop_nearly_held(candidates, bounds, 0.25);
    if (spread.size() >= options.count) candidates = std::move(spread);
  }
  if (candidates.size() < options.count)
    throw InvalidInputError("", "only " + std::to_string(candidates.size()) +
                                    " candidate spheres were found (inner Voronoi poles of " +
                                    std::to_string(samples.size()) +
                                    " surface samples, one per grid cell, with their centre inside): ask for at most " +
                                    std::to_string(candidates.size()) + " spheres");

  // The volume: points uniform over the union of the candidate balls (a ball drawn by
  // volume, a point in it, weighted by 1 / the number of balls holding it).
  Random random(options.seed ^ kVolumeStream);
  std::vector<double> cumulative(candidates.size());
  double total = 0;
  for (std::size_t i = 0; i < candidates.size(); ++i) cumulative[i] = total += std::pow(candidates[i].radius, 3);
  std::vector<Vertex> volume_points;
  volume_points.reserve(options.volume_samples);
  for (std::size_t k = 0; k < options.volume_samples; ++k) {
    const double pick = random.uniform() * total;
    const auto ball = std::min<std::size_t>(
        candidates.size() - 1,
        static_cast<std::size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin()));
    volume_points.push_back(uniform_in_ball(random, candidates[ball]));
  }
  const auto holding = balls_holding(volume_points, candidates);

  // Choose; each candidate reaching the top is measured: radius = distance to the surface
  // (closest point on the triangles through surface_distance.h's BVH over triangle indices,
  // built in parallel, with no copy of the triangles) minus the margin.
  const MeasuredSurface surface(mesh, "mesh");
  const std::vector<std::uint32_t> order =
      choose_greedily(candidates, volume_points, holding, options.count,
                      [&](std::uint32_t ball) { return surface.distance_to(candidates[ball].center) - margin; });
  if (order.size() < options.count)
    throw InvalidInputError("", "only " + std::to_string(order.size()) +
                                    " candidate spheres keep a positive radius inside the surface: ask for at most " +
                                    std::to_string(order.size()) + " spheres");

  std::vector<Sphere> chosen;
  for (const std::uint32_t c : order) chosen.push_back(candidates[c]);
  std::vector<int> shrink_steps(chosen.size(), 0);
  for (int round = 0;; ++round) {
    const SphereContainment check = check_spheres_inside(mesh, chosen);
    result.min_margin_world = check.min_margin_world;
    if (check.contained()) break;
    if (round == 60) throw Error("inside spheres: a sphere still fails the exact containment check after shrinking");
    // Only failing spheres shrink.
    for (const std::size_t i : check.outside) {
      chosen[i].radius *= 1.0 - std::ldexp(1.0, -52 + shrink_steps[i]);
      ++shrink_steps[i];
    }
  }
  result.spheres_shrunk = static_cast<std::size_t>(std::count_if(shrink_steps.begin(), shrink_steps.end(), [](int s) { return s > 0; }));
  result.spheres = std::move(chosen);

  // Covered volume: uniform points in the spheres' box.
  BoundingBox box;
  for (const Sphere& s : result.spheres) {
    box.extend(s.center - Vertex::Constant(s.radius));
    box.extend(s.center + Vertex::Constant(s.radius));
  }
  result.box_volume = (box.max - box.min).prod();
  result.coverage_seed = options.seed ^ kCoverageStream;
  Random coverage(result.coverage_seed);
  BallGrid grid(box, result.spheres.size());
  for (const Sphere& sphere : result.spheres) grid.add(sphere);
  result.coverage_hits.trials = options.coverage_samples;
  for (std::size_t k = 0; k < options.coverage_samples; ++k) {
    const Vertex p(box.min.x() + coverage.uniform() * (box.max.x() - box.min.x()),
                   box.min.y() + coverage.uniform() * (box.max.y() - box.min.y()),
                   box.min.z() + coverage.uniform() * (box.max.z() - box.min.z()));
    if (grid.holds(p)) ++result.coverage_hits.successes;
  }
  const double scale = result.box_volume / result.mesh_volume;
  result.covered_volume_fraction = result.coverage_hits.fraction() * scale;
  result.covered_volume_lower = result.coverage_hits.lower(kZ95) * scale;
  result.covered_volume_upper = result.coverage_hits.upper(kZ95) * scale;
  return result;
}

}  // namespace visproxy
