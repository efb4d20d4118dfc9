#include "visproxy/measure/proxy_measurement.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "visproxy/mesh/read_mesh.h"
#include "visproxy/mesh/sphere_set.h"
#include "visproxy/measure/random_lines.h"
#include "test_meshes.h"

namespace visproxy {
namespace {

constexpr double kZ999 = 3.290527;  // 99.9 % two-sided

double surface_area(const TriangleMesh& mesh) {
  double area = 0;
  for (const Triangle& t : mesh.triangles)
    area += 0.5 * (mesh.positions[t[1]] - mesh.positions[t[0]]).cross(mesh.positions[t[2]] - mesh.positions[t[0]]).norm();
  return area;
}

TriangleMesh box(const Vertex& min, const Vertex& max) {
  TriangleMesh mesh = testing::unit_cube();
  for (Vertex& p : mesh.positions) p = min + p.cwiseProduct(max - min);
  return mesh;
}

void expect_within(const Proportion& measured, double expected, const char* what) {
  EXPECT_LE(measured.lower(kZ999), expected) << what << " measured " << measured.fraction();
  EXPECT_GE(measured.upper(kZ999), expected) << what << " measured " << measured.fraction();
}

// A convex polyhedral sphere and its bounding box, under isotropic lines through a sphere
// of radius R_s around both: Cauchy's formula gives P(line hits K) = area(K) / (4 pi R_s^2)
// for each, and since every line that hits the sphere hits the box, f_hit = 1 and
// f_miss = P(miss box) / P(miss sphere).
TEST(MeasureProxy, SphereAndItsBoxMatchCauchysFormula) {
  const TriangleMesh ball = sphere_set_mesh({{{0.2, -0.1, 0.3}, 1.0}}, 4);
  const BoundingBox bounds = bounding_box(ball);
  const TriangleMesh aabb = box(bounds.min, bounds.max);
  const Sphere sampling{bounds.min + (bounds.max - bounds.min) / 2, 2.0};
  const double sphere_area = 4 * std::numbers::pi * sampling.radius * sampling.radius;
  const double p_mesh = surface_area(ball) / sphere_area, p_box = surface_area(aabb) / sphere_area;

  const RayScene mesh_scene(ball), box_scene(aabb);
  const ReferenceRays reference = trace_reference(mesh_scene, isotropic_lines(sampling, 400000, 3), {.rays = 1000});
  const ProxyMeasurement m = measure_proxy(reference, box_scene, ProxyKind::outside, {.rays = 1000});
  EXPECT_EQ(m.counts.total(), 400000u);
  EXPECT_EQ(m.counts.counts[1], 0u);  // no ray hits the sphere and misses its box
  EXPECT_EQ(m.f_hit.fraction(), 1.0);
  expect_within(Proportion{m.counts.counts[0] + m.counts.counts[1], m.counts.total()}, p_mesh, "P(hit mesh)");
  expect_within(m.f_miss, (1 - p_box) / (1 - p_mesh), "f_miss");
  expect_within(m.v_avg, 1 - p_mesh, "V_avg");
  EXPECT_LE(m.gssa_ratio_lower, p_box / p_mesh);
  EXPECT_GE(m.gssa_ratio_upper, p_box / p_mesh);
  EXPECT_EQ(m.probability_form, ProxyKind::outside);
  EXPECT_EQ(m.optimal.p3, 0.0);
  EXPECT_GT(m.proxy_ns_per_ray, 0.0);
  EXPECT_GT(m.mesh_ns_per_ray, 0.0);
}

// The unit cube and its inscribed ball as an inside proxy: f_miss = 1 and
// f_hit = area(ball) / area(cube) = pi / 6.
TEST(MeasureProxy, CubeAndInscribedBallMatchCauchysFormula) {
  const TriangleMesh cube = testing::unit_cube();
  const std::vector<Sphere> ball = {{{0.5, 0.5, 0.5}, 0.5}};
  const Sphere sampling = bounding_sphere(cube);
  const double sphere_area = 4 * std::numbers::pi * sampling.radius * sampling.radius;
  const RayScene mesh_scene(cube), ball_scene(ball);
  const ReferenceRays reference = trace_reference(mesh_scene, isotropic_lines(sampling, 400000, 5), {.rays = 1000});
  const ProxyMeasurement m = measure_proxy(reference, ball_scene, ProxyKind::inside, {.rays = 1000});
  EXPECT_EQ(m.counts.counts[2], 0u);  // no ray hits the ball and misses the cube
  EXPECT_EQ(m.f_miss.fraction(), 1.0);
  expect_within(m.f_hit, std::numbers::pi / 6, "f_hit");
  expect_within(m.v_avg, 1 - 6 / sphere_area, "V_avg");
  EXPECT_EQ(m.probability_form, ProxyKind::inside);
  EXPECT_EQ(m.optimal.p2, 0.0);
  EXPECT_LT(m.variance_optimal, m.variance_equal);
}

TEST(MeasureProxy, ContradictedClaimFallsBackToGeneralProbabilities) {
  RayTypeCounts counts;
  counts.counts = {500, 3, 200, 297};  // an "outside" proxy that 3 rays got past
  const ProxyMeasurement m = measure_from_counts(counts, ProxyKind::outside);
  EXPECT_EQ(m.rays_contradicting_claim, 3u);
  EXPECT_EQ(m.probability_form, ProxyKind::general);
  EXPECT_GT(m.optimal.p3, 0.0);
  EXPECT_TRUE(std::isfinite(m.variance_optimal));
}

TEST(MeasureProxy, DegenerateCountsGiveFiniteFigures) {
  for (const auto& n : std::vector<std::array<std::uint64_t, 4>>{{0, 0, 0, 0}, {10, 0, 0, 0}, {0, 0, 0, 10}, {0, 5, 5, 0}}) {
    RayTypeCounts counts;
    counts.counts = n;
    for (ProxyKind kind : {ProxyKind::outside, ProxyKind::inside, ProxyKind::general}) {
      const ProxyMeasurement m = measure_from_counts(counts, kind);
      EXPECT_TRUE(std::isfinite(m.optimal.p1) && std::isfinite(m.optimal.p2) && std::isfinite(m.optimal.p3));
      EXPECT_NEAR(m.optimal.p1 + m.optimal.p2 + m.optimal.p3, 1.0, 1e-15);
      EXPECT_TRUE(std::isfinite(m.variance_optimal));
      EXPECT_TRUE(std::isfinite(m.gssa_ratio));
    }
  }
}

// Embree, ray by ray, against a brute-force double-precision segment-triangle test on a
// real mesh. Rays may disagree only where they pass within float rounding of an edge.
TEST(MeasureProxy, EmbreeAgreesWithBruteForceRayByRay) {
  const TriangleMesh mesh = read_mesh(testing::cgal_mesh("knot1.off"));
  const RayScene scene(mesh);
  const Sphere sampling = bounding_sphere(mesh);
  const std::vector<Segment> rays = isotropic_lines(sampling, 3000, 9);
  const std::vector<std::uint8_t> blocked = scene.segments_blocked(rays);
  std::size_t hits = 0, disagreements = 0, grazing_disagreements = 0;
  const double scale = 2 * sampling.radius;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const Vertex origin = rays[i].from, direction = rays[i].to - rays[i].from;
    bool hit = false;
    double closest_margin = std::numeric_limits<double>::infinity();  // distance to an edge, relative
    for (const Triangle& t : mesh.triangles) {
      const Vertex a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
      const Vertex e1 = b - a, e2 = c - a, h = direction.cross(e2);
      const double det = e1.dot(h);
      if (std::abs(det) < 1e-300) continue;
      const Vertex s = origin - a, q = s.cross(e1);
      const double u = s.dot(h) / det, v = direction.dot(q) / det, tt = e2.dot(q) / det;
      if (tt <= 0 || tt >= 1) continue;
      const double margin = std::min({u, v, 1 - u - v});
      if (margin >= 0) hit = true;
      const double edge_length = std::max({e1.norm(), e2.norm(), (c - b).norm()});
      closest_margin = std::min(closest_margin, std::abs(margin) * edge_length / scale);
    }
    hits += hit;
    if (hit != (blocked[i] != 0)) {
      ++disagreements;
      if (closest_margin < 1e-6) ++grazing_disagreements;
    }
  }
  EXPECT_GT(hits, 300u);
  EXPECT_EQ(disagreements, grazing_disagreements);
  EXPECT_LE(disagreements, 2u);
}

}  // namespace
}  // namespace visproxy
