#include "visproxy/runtime/runtime.h"

#include <embree3/rtcore.h>
#include <gtest/gtest.h>

#include <random>
#include <string>

#include "visproxy/core/errors.h"
#include "visproxy/folder/proxy_folder.h"
#include "visproxy/folder/verdict.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/mesh/write_mesh.h"
#include "visproxy/proxy/build_proxies.h"
#include "visproxy/folder/proxy_folder.h"
#include "test_meshes.h"
#include "test_support.h"

namespace visproxy {
namespace {

// A proxy folder of the knot (hull:32, inside:10), written as `visproxy build` writes it.
class Runtime : public testing::ScratchFolder {
 protected:
  void SetUp() override {
    ScratchFolder::SetUp();
    mesh_path_ = testing::cgal_mesh("knot1.off");
    knot_ = read_mesh(mesh_path_);
    const std::vector<ProxySpec> specs = parse_proxy_specs({"hull:32", "inside:10"});
    BuildOptions options;
    options.hausdorff_samples = 200;
    options.gssa_lines = 1000;
    const std::vector<BuiltProxy> proxies = build_proxies(knot_, mesh_path_, specs, options);
    write_proxy_folder(folder_, {.path = mesh_path_, .weld = "auto", .vertices = knot_.positions.size(),
                                 .triangles = knot_.triangles.size(), .components = 1, .bounds = bounding_box(knot_)},
                       proxies, options);
  }

  std::string load_error(std::string_view name, const std::filesystem::path& mesh, RuntimeLoadOptions options = {}) {
    try {
      RuntimeProxy::load(folder_, name, mesh, options);
      return "loaded";
    } catch (const InvalidInputError& error) {
      return error.what();
    }
  }

  // Segment ends for the estimators: the knot's centre (inside its hull, between the
  // strands: in the hull, not in the mesh) and two points ten diagonals away, the segment
  // between which the hull's outside claim covers.
  struct Ends {
    Vertex centre, far_a, far_b;
  };
  Ends segment_ends() const {
    const BoundingBox box = bounding_box(knot_);
    const Vertex centre = 0.5 * (box.min + box.max);
    return {centre, centre + Vertex(10, 0, 0) * box.diagonal(), centre + Vertex(0, 10, 0) * box.diagonal()};
  }

  std::filesystem::path mesh_path_;
  TriangleMesh knot_;
};

TEST_F(Runtime, LoadsAProvedProxyAndRefusesWhatIsNotProved) {
  const RuntimeProxy hull = RuntimeProxy::load(folder_, "hull-32", mesh_path_);  // verified on load
  EXPECT_EQ(hull.kind(), ProxyKind::outside);
  EXPECT_TRUE(hull.note().empty());
  EXPECT_EQ(RuntimeProxy::load(folder_, "inside-10", mesh_path_).kind(), ProxyKind::inside);
  EXPECT_EQ(RuntimeProxy::load(folder_, "inside-10", mesh_path_).sphere_set().size(), 10u);

  // No recorded verdict and no verifying now: not proved.
  EXPECT_NE(load_error("hull-32", mesh_path_, {.require_proof = true, .verify_now = false}).find("is not proved"),
            std::string::npos);
  const RuntimeProxy general = RuntimeProxy::load(folder_, "hull-32", mesh_path_, {.require_proof = false, .verify_now = false});
  EXPECT_EQ(general.kind(), ProxyKind::general);
  EXPECT_NE(general.note().find("used as a general proxy"), std::string::npos);

  EXPECT_NE(load_error("hull-33", mesh_path_).find("no proxy named 'hull-33' (it lists hull-32, inside-10)"), std::string::npos);
  const std::string other = load_error("hull-32", testing::cgal_mesh("knot2.off"));
  EXPECT_NE(other.find("knot2.off"), std::string::npos) << other;
}

TEST_F(Runtime, AHullEditedByHandIsRefusedWithItsCounterexample) {
  TriangleMesh hull = read_mesh(folder_ / "hull-32.ply", {.weld = Weld::never, .on_warning = {}});
  Vertex center = Vertex::Zero();
  for (const Vertex& p : hull.positions) center += p / static_cast<double>(hull.positions.size());
  for (Vertex& p : hull.positions) p = center + 0.97 * (p - center);  // pulled in: mesh vertices now outside
  write_mesh(folder_ / "hull-32.ply", hull);
  const std::string error = load_error("hull-32", mesh_path_);
  EXPECT_NE(error.find("hull-32.ply: proxy hull-32: its outside claim (contains the mesh) is not proved"), std::string::npos)
      << error;
  EXPECT_NE(error.find("vertex"), std::string::npos) << error;
  EXPECT_EQ(RuntimeProxy::load(folder_, "hull-32", mesh_path_, {.require_proof = false}).kind(), ProxyKind::general);
}

// Embree scenes in the float coordinates a user's renderer hands over.
struct EmbreeWorld {
  RTCDevice device = rtcNewDevice(nullptr);
  RTCScene proxy = rtcNewScene(device), mesh = rtcNewScene(device);
  ~EmbreeWorld() {
    rtcReleaseScene(proxy);
    rtcReleaseScene(mesh);
    rtcReleaseDevice(device);
  }
  void add_mesh(const TriangleMesh& m, const Eigen::Affine3d& t) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, m.positions.size()));
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
      const Vertex p = t * m.positions[i];
      for (int k = 0; k < 3; ++k) v[3 * i + static_cast<std::size_t>(k)] = static_cast<float>(p[k]);
    }
    auto* f = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, m.triangles.size()));
    for (std::size_t i = 0; i < m.triangles.size(); ++i)
      for (std::size_t k = 0; k < 3; ++k) f[3 * i + k] = m.triangles[i][k];
    rtcCommitGeometry(g);
    rtcAttachGeometry(mesh, g);
    rtcReleaseGeometry(g);
  }
  static bool occluded(RTCScene scene, const Vertex& from, const Vertex& to) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    const Vertex d = to - from;
    RTCRay ray{};
    ray.org_x = float(from.x()), ray.org_y = float(from.y()), ray.org_z = float(from.z());
    ray.dir_x = float(d.x()), ray.dir_y = float(d.y()), ray.dir_z = float(d.z());
    ray.tnear = 0, ray.tfar = 1, ray.mask = ~0u;
    rtcOccluded1(scene, &context, &ray);
    return ray.tfar < 0;
  }
};

// Far from the origin, in float, the hull must still block every segment the mesh blocks
// (and the balls must block none that it lets through), on segments aimed where rounding
// bites: where the hull's faces touch the mesh, and along the balls' silhouettes. Without
// the rounding bound (PlacedProxy's scaling and shrinking), 90 of about 3000 segments the
// mesh blocks miss the hull, and 6 that the balls block miss the mesh.
// The claims under `far`, a placement far from the origin; the inside balls only when it is
// a similarity (`with_balls`).
void expect_claims_survive_float_rays(const std::filesystem::path& folder, const std::filesystem::path& mesh_path,
                                      const TriangleMesh& knot, const Eigen::Affine3d& far, bool with_balls) {
  const RuntimeProxy hull = RuntimeProxy::load(folder, "hull-32", mesh_path);
  const RuntimeProxy inside = RuntimeProxy::load(folder, "inside-10", mesh_path);
  const PlacedProxy placed_hull = hull.place({.transform = far});
  const PlacedProxy placed_inside = with_balls ? inside.place({.transform = far}) : inside.place({.transform = Eigen::Affine3d(Eigen::Translation3d(far.translation()))});
  ASSERT_EQ(placed_hull.kind(), ProxyKind::outside) << placed_hull.note();
  ASSERT_EQ(placed_inside.kind(), ProxyKind::inside) << placed_inside.note();
  EXPECT_GT(placed_hull.rounding_bound(), 1e-3);  // 2^-21 of 3e4: coarse floats

  EmbreeWorld hull_world, ball_world;
  hull_world.add_mesh(knot, far);
  ball_world.add_mesh(knot, far);
  placed_hull.attach(hull_world.device, hull_world.proxy);
  placed_inside.attach(ball_world.device, ball_world.proxy);
  for (RTCScene s : {hull_world.proxy, hull_world.mesh, ball_world.proxy, ball_world.mesh}) rtcCommitScene(s);

  std::mt19937_64 random(42);
  std::normal_distribution<double> normal;
  auto direction = [&] { return Vertex(normal(random), normal(random), normal(random)).normalized(); };
  const BoundingBox box = bounding_box(knot);
  const double reach = 2 * box.diagonal();
  // Where the hull touches the mesh: for each of its faces, the mesh vertex nearest the
  // face's plane (its support point). Segments run along the face through that point, a
  // few float ulps (at 3e4) inside or outside the plane.
  std::size_t hull_segments = 0, mesh_hits = 0, hull_misses_where_mesh_hits = 0;
  const TriangleMesh& faces = hull.mesh();
  for (int i = 0; i < 6000; ++i) {
    const Triangle& f = faces.triangles[static_cast<std::size_t>(i) % faces.triangles.size()];
    const Vertex n = (faces.positions[f[1]] - faces.positions[f[0]]).cross(faces.positions[f[2]] - faces.positions[f[0]]).normalized();
    const Vertex* support = &knot.positions[0];
    for (const Vertex& p : knot.positions)
      if (p.dot(n) > support->dot(n)) support = &p;
    Vertex along = n.cross(direction()).normalized();
    const Vertex through = far * (*support + 4e-3 * normal(random) * n);
    along = far.linear() * along;
    const Vertex from = through - reach * along, to = through + reach * along;
    ASSERT_TRUE(placed_hull.claim_covers(from, to));
    ++hull_segments;
    if (EmbreeWorld::occluded(hull_world.mesh, from, to)) {
      ++mesh_hits;
      if (!EmbreeWorld::occluded(hull_world.proxy, from, to)) ++hull_misses_where_mesh_hits;
    }
  }
  EXPECT_GT(mesh_hits, 100u);
  EXPECT_EQ(hull_misses_where_mesh_hits, 0u) << "of " << mesh_hits << " segments the mesh blocks";
  if (!with_balls) return;

  std::size_t ball_hits = 0, balls_hit_where_mesh_misses = 0;
  for (int i = 0; i < 3000; ++i) {
    const Sphere& s = inside.sphere_set()[static_cast<std::size_t>(i) % inside.sphere_set().size()];
    const Vertex d = direction(), side = d.cross(direction()).normalized();
    const Vertex grazing = far * (s.center + s.radius * (1 + 1e-4 * normal(random)) * side);
    const Vertex along = far.linear() * d;
    const Vertex from = grazing - reach * along, to = grazing + reach * along;
    ASSERT_TRUE(placed_inside.claim_covers(from, to));
    if (EmbreeWorld::occluded(ball_world.proxy, from, to)) {
      ++ball_hits;
      if (!EmbreeWorld::occluded(ball_world.mesh, from, to)) ++balls_hit_where_mesh_misses;
    }
  }
  EXPECT_GT(ball_hits, 100u);
  EXPECT_EQ(balls_hit_where_mesh_misses, 0u) << "of " << ball_hits << " segments the balls block";
}

TEST_F(Runtime, FarFromTheOriginTheClaimsSurviveFloatRays) {
  expect_claims_survive_float_rays(folder_, mesh_path_, knot_,
                                   Eigen::Translation3d(2.0e4, -1.5e4, 3.0e4) * Eigen::AngleAxisd(0.7, Vertex(1, 2, 3).normalized()), true);
}

// A mirror keeps both claims (the balls stay balls); uneven scale and shear keep the hull's
// (a convex hull stays convex under any affine map) and were refused before for want of balls.
TEST_F(Runtime, MirroredAndUnevenlyScaledPlacementsKeepTheirClaims) {
  const Eigen::Affine3d rotated = Eigen::Translation3d(2.0e4, -1.5e4, 3.0e4) * Eigen::AngleAxisd(0.7, Vertex(1, 2, 3).normalized());
  expect_claims_survive_float_rays(folder_, mesh_path_, knot_, rotated * Eigen::Scaling(-1.0, 1.0, 1.0), true);
  Eigen::Matrix3d sheared = Eigen::Vector3d(1.7, 0.6, 1.1).asDiagonal();
  sheared(0, 1) = 0.4;
  Eigen::Affine3d uneven = rotated;
  uneven.linear() = uneven.linear() * sheared;
  expect_claims_survive_float_rays(folder_, mesh_path_, knot_, uneven, false);
  Eigen::Affine3d mirrored_uneven = uneven;
  mirrored_uneven.linear() = mirrored_uneven.linear() * Eigen::Vector3d(1, -1, 1).asDiagonal();
  expect_claims_survive_float_rays(folder_, mesh_path_, knot_, mirrored_uneven, false);
  // Balls refuse what would make them ellipsoids; a transform that is not invertible is refused.
  const RuntimeProxy inside = RuntimeProxy::load(folder_, "inside-10", mesh_path_);
  EXPECT_THROW(inside.place({.transform = uneven}), Error);
  Eigen::Affine3d flat = Eigen::Affine3d::Identity();
  flat.linear()(2, 2) = 0;
  EXPECT_THROW(RuntimeProxy::load(folder_, "hull-32", mesh_path_).place({.transform = flat}), Error);
}

// A manifest whose kinds were swapped by hand (files and verdicts untouched): each verdict
// proves its own kind's claim only, so neither is trusted: refused with one line, or
// demoted with one line when proof is not required.
TEST_F(Runtime, SwappedKindsAreNotTrusted) {
  for (const char* name : {"hull-32", "inside-10"}) RuntimeProxy::load(folder_, name, mesh_path_);  // proved
  // Record the verdicts as `visproxy verify` would, then swap the kinds.
  nlohmann::json manifest = read_manifest(folder_);
  for (nlohmann::json& entry : manifest["proxies"])
    entry["verify"] = verify_proxy(knot_, manifest, entry, read_proxy_geometry(folder_, entry));
  write_manifest(folder_, manifest);
  EXPECT_EQ(RuntimeProxy::load(folder_, "hull-32", mesh_path_, {.require_proof = true, .verify_now = false}).kind(), ProxyKind::outside);
  std::swap(manifest["proxies"][0]["kind"], manifest["proxies"][1]["kind"]);
  write_manifest(folder_, manifest);
  for (const char* name : {"hull-32", "inside-10"}) {
    const std::string error = load_error(name, mesh_path_);
    EXPECT_NE(error.find("is not proved"), std::string::npos) << error;
    EXPECT_EQ(error.find('\n'), std::string::npos) << error;
    for (const bool verify_now : {false, true}) {
      const RuntimeProxy demoted = RuntimeProxy::load(folder_, name, mesh_path_, {.require_proof = false, .verify_now = verify_now});
      EXPECT_EQ(demoted.kind(), ProxyKind::general) << name;
      EXPECT_NE(demoted.note().find("used as a general proxy"), std::string::npos) << demoted.note();
      EXPECT_EQ(demoted.note().find('\n'), std::string::npos) << demoted.note();
    }
  }
}

// E[estimate] over u, exactly: the estimate is constant on each interval of u between the
// breakpoints, so sum each interval's length times its value.
template <class Estimate>
double mean_over_u(const std::vector<double>& breakpoints, Estimate&& estimate) {
  double mean = 0, begin = 0;
  for (double end : breakpoints) {
    if (end > begin) mean += (end - begin) * estimate(0.5 * (begin + end));
    begin = std::max(begin, end);
  }
  return mean;
}

TEST_F(Runtime, EstimatesAreUnbiasedWhereTheClaimCoversASegmentAndWhereItDoesNot) {
  const RuntimeProxy hull = RuntimeProxy::load(folder_, "hull-32", mesh_path_);
  const PlacedProxy placed = hull.place();
  const ShadowEstimator estimator(placed);
  const auto [centre, far_a, far_b] = segment_ends();
  // A light inside the hull (between the knot's strands: in the hull, not in the mesh).
  ASSERT_EQ(estimator.form(far_a, far_b), ProxyKind::outside);
  ASSERT_EQ(estimator.form(centre, far_b), ProxyKind::general);
  ASSERT_EQ(estimator.form(far_a, centre), ProxyKind::general);

  const Probabilities outside = equal_probabilities(ProxyKind::outside), general = equal_probabilities(ProxyKind::general);
  for (const auto& [from, to, form] : {std::tuple{far_a, far_b, outside}, std::tuple{centre, far_b, general}}) {
    for (const bool proxy_hit : {false, true})
      for (const bool mesh_hit : {false, true}) {
        // Where the claim covers the segment, the mesh cannot block what the hull lets through.
        if (estimator.form(from, to) == ProxyKind::outside && mesh_hit && !proxy_hit) continue;
        auto proxy = [&](const Vertex&, const Vertex&) { return proxy_hit; };
        auto mesh = [&](const Vertex&, const Vertex&) { return mesh_hit; };
        const double exact = mesh_hit ? 0.0 : 1.0;
        const double eq8 = mean_over_u({form.p1, form.p1 + form.p2, 1.0},
                                       [&](double u) { return estimator.eq8(from, to, u, proxy, mesh); });
        EXPECT_NEAR(eq8, exact, 1e-12) << "proxy " << proxy_hit << " mesh " << mesh_hit;
        LearnedCorrections learned;
        learned.record(true, true);  // some evidence, so that q is not 1/2 everywhere
        const CorrectionProbabilities q = learned.probabilities(estimator.form(from, to));
        const double chance = proxy_hit ? q.after_hit : q.after_miss;
        const double cv = mean_over_u({chance, 1.0}, [&](double u) {
          LearnedCorrections copy = learned;
          return estimator.control_variate(from, to, u, copy, proxy, mesh);
        });
        EXPECT_NEAR(cv, exact, 1e-12) << "proxy " << proxy_hit << " mesh " << mesh_hit;
      }
  }
  // The light inside the hull, with the mesh in the way and the hull's surface not crossed
  // (type 2): the outside form would give 1, the estimator gives 0 on average.
  auto misses = [](const Vertex&, const Vertex&) { return false; };
  auto blocks = [](const Vertex&, const Vertex&) { return true; };
  const double mean = mean_over_u({general.p1, general.p1 + general.p2, 1.0},
                                  [&](double u) { return estimator.eq8(centre, far_b, u, misses, blocks); });
  EXPECT_NEAR(mean, 0.0, 1e-12);
}

// The control variate weighing your costs: where the proxy does not pay (a proxy query as
// costly as the exact one), every segment gets the exact answer, for every u; the proxy
// is traced only to explore, for u < 1/8 while the evidence is short, and never when no
// evidence could make it pay. Where it pays (a cheap proxy that has never been wrong), q
// drops below 1 and the estimate stays unbiased over u. Costs it cannot use (NaN) give the
// cost-blind rule.
TEST_F(Runtime, ControlVariateWithCostsTracesExactlyWhereTheProxyDoesNotPay) {
  const RuntimeProxy hull = RuntimeProxy::load(folder_, "hull-32", mesh_path_);
  const PlacedProxy placed = hull.place();
  const ShadowEstimator estimator(placed);
  const auto [centre, far_a, far_b] = segment_ends();
  ASSERT_EQ(estimator.form(far_a, far_b), ProxyKind::outside);
  const CorrectionOptions options{.scale = 2, .floor = 0.05};
  for (const bool mesh_hit : {false, true}) {
    int proxy_calls = 0, mesh_calls = 0;
    auto proxy = [&](const Vertex&, const Vertex&) { return ++proxy_calls, true; };
    auto mesh = [&](const Vertex&, const Vertex&) { return ++mesh_calls, mesh_hit; };
    const double exact = mesh_hit ? 0.0 : 1.0;
    // The proxy costs what the mesh does: never pays, never explored.
    LearnedCorrections costly(options, {.base = 10, .correction = 10, .exact = 10, .variance = 0.2});
    EXPECT_TRUE(costly.choice(ProxyKind::outside).trace_exactly);
    for (const double u : {0.01, 0.5, 0.99}) EXPECT_EQ(estimator.control_variate(far_a, far_b, u, costly, proxy, mesh), exact);
    EXPECT_EQ(proxy_calls, 0);
    EXPECT_EQ(mesh_calls, 3);
    // Cheap, but said to be wrong on most of its hits: gated, and explored for u < 1/8.
    LearnedCorrections wrong(options, {.base = 2, .correction = 10, .exact = 10, .variance = 0.01},
                             {.share = {0.2, 0.8}, .disagreeing = {0.001, 0.9}, .weight = 16});
    ASSERT_TRUE(wrong.choice(ProxyKind::outside).trace_exactly);
    proxy_calls = 0;
    EXPECT_EQ(estimator.control_variate(far_a, far_b, 0.5, wrong, proxy, mesh), exact);
    EXPECT_EQ(proxy_calls, 0);
    EXPECT_EQ(estimator.control_variate(far_a, far_b, 0.1, wrong, proxy, mesh), exact);
    EXPECT_EQ(proxy_calls, 1);
    EXPECT_EQ(wrong.evidence().answered[1], 1u);
    EXPECT_EQ(wrong.evidence().seen[1], 1u);
  }
  // Cheap and never wrong: the control variate, q below 1 after a hit, unbiased over u.
  LearnedCorrections cheap(options, {.base = 2, .correction = 10, .exact = 10, .variance = 0.2},
                           {.share = {0.5, 0.5}, .disagreeing = {0.001, 0.001}, .weight = 16});
  const LearnedChoice choice = cheap.choice(ProxyKind::outside);
  ASSERT_FALSE(choice.trace_exactly);
  ASSERT_LT(choice.q.after_hit, 1.0);
  for (const bool mesh_hit : {false, true}) {
    auto proxy = [](const Vertex&, const Vertex&) { return true; };
    auto mesh = [&](const Vertex&, const Vertex&) { return mesh_hit; };
    const double mean = mean_over_u({choice.q.after_hit, 1.0}, [&](double u) {
      LearnedCorrections copy = cheap;
      return estimator.control_variate(far_a, far_b, u, copy, proxy, mesh);
    });
    EXPECT_NEAR(mean, mesh_hit ? 0.0 : 1.0, 1e-12);
  }
  // Unusable costs: the cost-blind probabilities.
  LearnedCorrections blind(options, {.base = std::nan(""), .correction = 1, .exact = 1, .variance = 1});
  EXPECT_FALSE(blind.choice(ProxyKind::outside).trace_exactly);
  EXPECT_EQ(blind.probabilities(ProxyKind::outside).after_hit,
            correction_probabilities(ProxyKind::outside, blind.evidence(), options).after_hit);
}

}  // namespace
}  // namespace visproxy
