// build_proxies on the inputs that break naive code, every method, checked for what each
// kind promises: outside proxies contain every input vertex (exact), counts respect N,
// no degenerate triangles.

#include "visproxy/proxy/build_proxies.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <mutex>
#include <string>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/inspect/exact_checks.h"
#include "visproxy/mesh/mesh_topology.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/mesh/sphere_set.h"
#include "test_meshes.h"
#include "test_support.h"
#include "visproxy/verify/containment.h"

namespace visproxy {
namespace {

// Small budgets keep the run short; the real-mesh defaults are exercised by the CLI tests.
// The cluster cell is small because the far-apart parts make the bounding box 1000 units
// wide: a larger cell merges each part into a point (tested below).
const std::vector<std::string> kEverySpec = {"aabb",     "obb",        "hull",       "hull:8",
                                             "wrap:alpha=0.1", "outer:64", "quadric:16", "cluster:0.0002"};

TriangleMesh single_triangle() {
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0.5}, {0.2, 1, 0}};
  mesh.triangles = {{0, 1, 2}};
  return mesh;
}

TriangleMesh flat_grid() {  // a 6 x 6 grid of squares in the plane z = 1
  TriangleMesh mesh;
  for (int y = 0; y <= 6; ++y)
    for (int x = 0; x <= 6; ++x) mesh.positions.emplace_back(x, y, 1);
  for (VertexIndex y = 0; y < 6; ++y)
    for (VertexIndex x = 0; x < 6; ++x) {
      const VertexIndex v = 7 * y + x;
      mesh.triangles.push_back({v, v + 1, v + 8});
      mesh.triangles.push_back({v, v + 8, v + 7});
    }
  return mesh;
}

TriangleMesh two_far_apart() {
  TriangleMesh mesh = testing::unit_cube();
  TriangleMesh far = testing::tetrahedron();
  for (Vertex& p : far.positions) p = 2.0 * p + Vertex(1000, 0, 0);
  append_mesh(mesh, far);
  return mesh;
}

TriangleMesh duplicated_vertices() {  // a cube whose every triangle has its own corners (a soup)
  const TriangleMesh cube = testing::unit_cube();
  TriangleMesh soup;
  for (const Triangle& t : cube.triangles) {
    const auto base = static_cast<VertexIndex>(soup.positions.size());
    for (VertexIndex v : t) soup.positions.push_back(cube.positions[v]);
    soup.triangles.push_back({base, base + 1, base + 2});
  }
  return soup;
}

struct Input {
  const char* name;
  TriangleMesh (*make)();
};

TriangleMesh elephant() { return read_mesh(testing::cgal_mesh("elephant-with-holes.off")); }
TriangleMesh pig() { return read_mesh(testing::cgal_mesh("pig.stl")); }

class AwkwardInput : public ::testing::TestWithParam<Input> {};

TEST_P(AwkwardInput, EveryMethodKeepsItsPromise) {
  const TriangleMesh mesh = GetParam().make();
  const std::vector<BuiltProxy> proxies = build_proxies(mesh, "input", parse_proxy_specs(kEverySpec));
  ASSERT_EQ(proxies.size(), kEverySpec.size());
  for (const BuiltProxy& proxy : proxies) {
    SCOPED_TRACE(proxy.spec.text);
    ASSERT_FALSE(proxy.mesh.triangles.empty());
    for (const Vertex& p : proxy.mesh.positions) ASSERT_TRUE(p.allFinite());
    EXPECT_TRUE(find_degenerate_triangles(proxy.mesh).empty());
    EXPECT_TRUE(std::isfinite(proxy.error.at("hausdorff_relative").get<double>()));
    if (proxy.spec.kind() == ProxyKind::outside) {
      EXPECT_TRUE(analyze_topology(proxy.mesh).closed());
      EXPECT_EQ(check_containment(proxy.mesh, mesh, {.check_surface = false}).vertices_outside, 0u);
    }
    if (proxy.spec.is("quadric")) {
      EXPECT_LE(proxy.mesh.triangles.size(), 16u);
    }
    if (proxy.spec.is("outer_hull") && proxy.result.at("reached_target").get<bool>()) {
      EXPECT_LE(proxy.mesh.triangles.size(), 64u);
    }
    if (proxy.spec.is("bounded_hull")) {
      EXPECT_LE(proxy.result.at("faces").get<std::size_t>(), 8u);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Inputs, AwkwardInput,
                         ::testing::Values(Input{"single_triangle", single_triangle}, Input{"flat_grid", flat_grid},
                                           Input{"two_far_apart", two_far_apart},
                                           Input{"duplicated_vertices", duplicated_vertices},
                                           Input{"elephant_with_holes", elephant}, Input{"pig_non_manifold", pig}),
                         [](const auto& param_info) { return std::string(param_info.param.name); });

TEST(BuildProxies, PerComponentBuildsOnePerComponent) {
  const TriangleMesh mesh = two_far_apart();
  BuildOptions options;
  options.per_component = true;
  const std::vector<BuiltProxy> proxies = build_proxies(mesh, "two", parse_proxy_specs({"aabb", "hull", "hull:6"}), options);
  EXPECT_EQ(proxies[0].primitives, 2u);
  EXPECT_EQ(proxies[0].primitive_type, PrimitiveType::box);
  EXPECT_EQ(proxies[0].result.at("components").size(), 2u);
  // Per component the aabb of the cube is the cube itself: 12 + 12 triangles.
  EXPECT_EQ(proxies[0].mesh.triangles.size(), 24u);
  EXPECT_EQ(analyze_topology(proxies[1].mesh).components, 2u);
  for (const BuiltProxy& proxy : proxies)
    EXPECT_EQ(check_containment(proxy.mesh, mesh, {.check_surface = false}).vertices_outside, 0u) << proxy.spec.text;
  // One hull of both is one component and much larger in volume than the two.
  const std::vector<BuiltProxy> joined = build_proxies(mesh, "two", parse_proxy_specs({"hull"}));
  EXPECT_EQ(analyze_topology(joined[0].mesh).components, 1u);
  EXPECT_GT(joined[0].result.at("volume").get<double>(),
            10 * (proxies[1].result.at("components")[0].at("volume").get<double>() +
                  proxies[1].result.at("components")[1].at("volume").get<double>()));
}

// The default set leaves out a proxy that is not much simpler than the mesh (the convex
// hull of a finely tessellated ball is the ball), saying why; asked for by name, it stays.
TEST(BuildProxies, TheDefaultSetLeavesOutAProxyNearlyAsLargeAsTheMesh) {
  const TriangleMesh ball = sphere_set_mesh({{{0.3, -2, 5}, 1.5}}, 5);
  ASSERT_GE(ball.triangles.size(), 4 * kLargeProxyPrimitives);
  std::vector<std::string> skipped;
  BuildOptions options;
  options.default_set = true;
  options.on_skip = [&](std::string_view name, std::string_view reason) {
    skipped.push_back(std::string(name) + ": " + std::string(reason));
  };
  const std::vector<BuiltProxy> kept = build_proxies(ball, "ball", parse_proxy_specs({"aabb", "hull", "hull:64"}), options);
  ASSERT_EQ(kept.size(), 2u);
  EXPECT_EQ(kept[0].name, "aabb");
  EXPECT_EQ(kept[1].name, "hull-64");
  ASSERT_EQ(skipped.size(), 1u);
  EXPECT_EQ(skipped[0].rfind("hull: it has ", 0), 0u) << skipped[0];
  EXPECT_NE(skipped[0].find("100 % of the mesh's"), std::string::npos) << skipped[0];
  const std::vector<BuiltProxy> asked = build_proxies(ball, "ball", parse_proxy_specs({"hull"}));
  ASSERT_EQ(asked.size(), 1u);
  EXPECT_EQ(asked[0].primitives, ball.triangles.size());
}

// quadric:P% and meshopt:P% take P % of the input's triangles as their budget, of each
// component's with --per-component, and record the count they were given.
TEST(BuildProxies, ABudgetAsAShareIsTheInputsTriangles) {
  const TriangleMesh ball = sphere_set_mesh({{{0.3, -2, 5}, 1.5}}, 4);  // 5120 triangles
  const std::vector<BuiltProxy> built = build_proxies(ball, "ball", parse_proxy_specs({"quadric:10%", "meshopt:5%"}));
  ASSERT_EQ(built.size(), 2u);
  EXPECT_EQ(built[0].name, "quadric-10pct");
  EXPECT_EQ(built[0].params.at("max_triangles"), 512);
  EXPECT_DOUBLE_EQ(built[0].params.at("share_of_triangles").get<double>(), 0.1);
  EXPECT_LE(built[0].primitives, 512u);
  EXPECT_GT(built[0].primitives, 256u);
  EXPECT_EQ(built[1].params.at("max_triangles"), 256);
  EXPECT_LE(built[1].primitives, 256u);
  // Two balls, one four times as finely tessellated: each gets its own share.
  TriangleMesh two = sphere_set_mesh({{{0, 0, 0}, 1.0}}, 2);  // 320 triangles
  append_mesh(two, sphere_set_mesh({{{5, 0, 0}, 1.0}}, 3));   // 1280 triangles
  BuildOptions options;
  options.per_component = true;
  const std::vector<BuiltProxy> parts = build_proxies(two, "two", parse_proxy_specs({"quadric:25%"}), options);
  EXPECT_EQ(parts[0].params.at("max_triangles"), 80 + 320);
  const nlohmann::json& components = parts[0].result.at("components");
  ASSERT_EQ(components.size(), 2u);
  EXPECT_LE(components[0].at("triangles").get<std::size_t>(), 80u);
  EXPECT_LE(components[1].at("triangles").get<std::size_t>(), 320u);
}

TEST(BuildProxies, InputErrorsNameTheSourceAndTheSpec) {
  TriangleMesh line;
  line.positions = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}};
  line.triangles = {{0, 1, 2}};
  try {
    build_proxies(line, "line.obj", parse_proxy_specs({"aabb"}));
    FAIL() << "a collinear mesh got a box";
  } catch (const InvalidInputError& error) {
    EXPECT_EQ(error.file(), "line.obj");
    EXPECT_EQ(std::string(error.what()).rfind("line.obj: aabb: ", 0), 0u) << error.what();
  }
  EXPECT_THROW(build_proxies(TriangleMesh{}, "empty.obj", parse_proxy_specs({"hull"})), InvalidInputError);
  // A cell larger than the gap between the parts merges each part into a point.
  try {
    build_proxies(two_far_apart(), "two.obj", parse_proxy_specs({"cluster:0.5"}));
    FAIL() << "an empty proxy was returned";
  } catch (const InvalidInputError& error) {
    EXPECT_NE(std::string(error.what()).find("two.obj: cluster:0.5: every triangle collapsed"), std::string::npos)
        << error.what();
  }
}

// Specs built at once give the proxies of one after another, bit for bit, and in spec
// order: the same manifests but for the build seconds, on a closed mesh with every kind
// (spheres with two levels) and on one with boundaries, per component.
TEST(BuildProxies, BuildingAtOnceGivesTheProxiesOfOneAfterAnother) {
  struct Case {
    const char* name;
    TriangleMesh mesh;
    std::vector<std::string> specs;
    bool per_component;
  };
  const std::vector<Case> cases = {
      {"knot1", read_mesh(testing::cgal_mesh("knot1.off")),
       {"aabb", "obb", "hull", "hull:16", "wrap", "outer:64", "inner:64", "quadric:64", "cluster:0.05", "inside:8",
        "spheres:20,10"},
       false},
      {"two far apart, per component", two_far_apart(), {"cluster:0.0002", "hull:8", "aabb", "outer:64"}, true},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const std::vector<ProxySpec> specs = parse_proxy_specs(c.specs);
    std::vector<std::string> started;
    std::mutex started_mutex;
    auto build = [&](std::size_t at_once) {
      BuildOptions options{.per_component = c.per_component, .hausdorff_samples = 2000, .seed = 4,
                           .on_start = [&](std::string_view name) {
                             const std::lock_guard lock(started_mutex);
                             started.emplace_back(name);
                           },
                           .gssa_lines = 5000};
      options.builders_at_once = at_once;
      return build_proxies(c.mesh, "mesh.off", specs, options);
    };
    const std::vector<BuiltProxy> one = build(1);
    ASSERT_EQ(started.size(), specs.size());
    for (const std::size_t at_once : {2u, 3u, 8u}) {  // 8: more workers than threads
      SCOPED_TRACE(at_once);
      started.clear();
      const std::vector<BuiltProxy> many = build(at_once);
      EXPECT_EQ(started.size(), specs.size());
      ASSERT_EQ(many.size(), one.size());
      for (std::size_t i = 0; i < one.size(); ++i) {
        SCOPED_TRACE(one[i].name);
        EXPECT_EQ(many[i].name, one[i].name);
        EXPECT_EQ(many[i].mesh.positions, one[i].mesh.positions);
        EXPECT_EQ(many[i].mesh.triangles, one[i].mesh.triangles);
        EXPECT_EQ(many[i].result, one[i].result);
        EXPECT_EQ(many[i].error, one[i].error);
        EXPECT_EQ(many[i].params, one[i].params);
      }
    }
  }
}

// When several specs fail, the error is the first failing one's in spec order, as one
// after another would give, although the workers take the slow kinds first: cluster:0.5
// (first, taken last) and inside:8 (third, taken early) both fail on an open mesh of two
// far-apart parts while outer:64 (second) runs.
TEST(BuildProxies, BuildingAtOnceThrowsTheFirstFailureInSpecOrder) {
  TriangleMesh open = two_far_apart();
  open.triangles.pop_back();
  const std::vector<ProxySpec> specs = parse_proxy_specs({"cluster:0.5", "outer:64", "inside:8"});
  for (const std::size_t at_once : {1u, 2u, 3u}) {
    SCOPED_TRACE(at_once);
    BuildOptions options;
    options.builders_at_once = at_once;
    try {
      build_proxies(open, "open.obj", specs, options);
      FAIL() << "failing specs built";
    } catch (const InvalidInputError& error) {
      EXPECT_NE(std::string(error.what()).find("open.obj: cluster:0.5: every triangle collapsed"), std::string::npos)
          << error.what();
    }
  }
  // Without the first, the third's error.
  BuildOptions options;
  options.builders_at_once = 2;
  try {
    build_proxies(open, "open.obj", parse_proxy_specs({"outer:64", "inside:8"}), options);
    FAIL() << "inside:8 built on an open mesh";
  } catch (const InvalidInputError& error) {
    EXPECT_NE(std::string(error.what()).find("open.obj: inside:8: "), std::string::npos) << error.what();
  }
}

TEST(BuildProxies, BuildersAtOnceFollowsTheMeshSize) {
  EXPECT_EQ(builders_at_once(3, 10'000'000), 3u);
  EXPECT_EQ(builders_at_once(0, kConcurrentBuildTriangles + 1), 1u);
  EXPECT_EQ(builders_at_once(0, 1000), static_cast<std::size_t>(tbb::this_task_arena::max_concurrency()));
}

}  // namespace
}  // namespace visproxy
