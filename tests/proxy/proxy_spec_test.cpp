#include "visproxy/proxy/proxy_spec.h"

#include <gtest/gtest.h>

#include <string>

#include "visproxy/core/errors.h"

namespace visproxy {
namespace {

TEST(ProxySpec, ParsesEveryMethodAndNamesIt) {
  EXPECT_TRUE(parse_proxy_spec("aabb").is("aabb"));
  EXPECT_EQ(parse_proxy_spec("obb").name(), "obb");
  EXPECT_TRUE(parse_proxy_spec("hull").is("convex_hull"));
  const ProxySpec bounded = parse_proxy_spec("hull:32");
  EXPECT_TRUE(bounded.is("bounded_hull"));
  EXPECT_EQ(bounded.count, 32u);
  EXPECT_EQ(bounded.name(), "hull-32");
  const ProxySpec outer = parse_proxy_spec("outer:512");
  EXPECT_TRUE(outer.is("outer_hull"));
  EXPECT_EQ(outer.name(), "outer-512");
  EXPECT_EQ(outer.kind(), ProxyKind::outside);
  const ProxySpec quadric = parse_proxy_spec("quadric:512");
  EXPECT_EQ(quadric.count, 512u);
  EXPECT_EQ(quadric.kind(), ProxyKind::general);
  const ProxySpec cluster = parse_proxy_spec("cluster:0.03");
  EXPECT_DOUBLE_EQ(cluster.cell_size_relative, 0.03);
  EXPECT_EQ(cluster.name(), "cluster-0.03");
  EXPECT_EQ(cluster.kind(), ProxyKind::general);
}

// A simplifier's budget as a share of the mesh's triangles, as Blender's Decimate ratio:
// parsed as the share, named without a '%', refused outside (0, 100] or for methods whose
// N is not a triangle budget of a simplifier.
TEST(ProxySpec, SimplifiersTakeABudgetAsAShareOfTheTriangles) {
  const ProxySpec quadric = parse_proxy_spec("quadric:10%");
  EXPECT_DOUBLE_EQ(quadric.count_share, 0.1);
  EXPECT_EQ(quadric.count, 0u);
  EXPECT_EQ(quadric.name(), "quadric-10pct");
  EXPECT_DOUBLE_EQ(parse_proxy_spec("meshopt:2.5%").count_share, 0.025);
  EXPECT_EQ(parse_proxy_spec("meshopt:100%").name(), "meshopt-100pct");
  EXPECT_DOUBLE_EQ(parse_proxy_spec("quadric:512").count_share, 0.0);
  for (const char* bad : {"quadric:0%", "quadric:150%", "quadric:%", "quadric:ten%", "quadric:-5%", "meshopt:nan%",
                          "outer:10%", "hull:10%", "inside:10%"}) {
    try {
      parse_proxy_spec(bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const Error& error) {
      EXPECT_NE(std::string(error.what()).find(bad), std::string::npos) << error.what();
    }
  }
}

TEST(ProxySpec, InnerHullTakesABudgetAndAGrid) {
  const ProxySpec inner = parse_proxy_spec("inner:512");
  EXPECT_TRUE(inner.is("inner_hull"));
  EXPECT_EQ(inner.count, 512u);
  EXPECT_EQ(inner.grid_cells, 0u);  // chosen from the budget
  EXPECT_EQ(inner.kind(), ProxyKind::inside);
  EXPECT_EQ(inner.name(), "inner-512");
  const ProxySpec gridded = parse_proxy_spec("inner:256,grid=48");
  EXPECT_EQ(gridded.count, 256u);
  EXPECT_EQ(gridded.grid_cells, 48u);
  EXPECT_EQ(gridded.name(), "inner-256-grid=48");
  for (const char* bad : {"inner", "inner:", "inner:3", "inner:x", "inner:64,grid=3", "inner:64,grid=2000",
                          "inner:64,cells=8", "inner:64,grid="}) {
    try {
      parse_proxy_spec(bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const Error& error) {
      EXPECT_NE(std::string(error.what()).find(std::string("'") + bad + "'"), std::string::npos) << error.what();
    }
  }
}

TEST(ProxySpec, WrapParametersDefaultAndOverride) {
  const ProxySpec plain = parse_proxy_spec("wrap");
  EXPECT_DOUBLE_EQ(plain.alpha_relative, 1.0 / 20);
  EXPECT_DOUBLE_EQ(plain.offset_relative, 1.0 / 600);
  const ProxySpec custom = parse_proxy_spec("wrap:alpha=0.02,offset=0.001");
  EXPECT_DOUBLE_EQ(custom.alpha_relative, 0.02);
  EXPECT_DOUBLE_EQ(custom.offset_relative, 0.001);
  EXPECT_EQ(custom.name(), "wrap-alpha=0.02-offset=0.001");
  const ProxySpec alpha_only = parse_proxy_spec("wrap:alpha=0.1");
  EXPECT_DOUBLE_EQ(alpha_only.alpha_relative, 0.1);
  EXPECT_DOUBLE_EQ(alpha_only.offset_relative, 1.0 / 600);
}

TEST(ProxySpec, DefaultSetIsThePapersSet) {
  std::vector<std::string> names;
  for (const ProxySpec& spec : default_proxy_specs()) names.push_back(spec.name());
  EXPECT_EQ(names, (std::vector<std::string>{"aabb", "obb", "hull", "hull-32", "wrap", "outer-512", "quadric-512",
                                             "cluster-0.03", "inside-40", "spheres-100"}));
}

TEST(ProxySpec, SphereSpecsNameEveryLevel) {
  const ProxySpec inside = parse_proxy_spec("inside:40");
  EXPECT_TRUE(inside.is("inscribed_spheres"));
  EXPECT_EQ(inside.count, 40u);
  EXPECT_EQ(inside.kind(), ProxyKind::inside);
  EXPECT_EQ(inside.output_names(), std::vector<std::string>{"inside-40"});

  const ProxySpec levels = parse_proxy_spec("spheres:100,1000,10,25,250");
  EXPECT_TRUE(levels.is("sphere_set"));
  EXPECT_EQ(levels.kind(), ProxyKind::general);
  EXPECT_EQ(levels.levels, (std::vector<std::size_t>{1000, 250, 100, 25, 10}));
  EXPECT_EQ(levels.output_names(),
            (std::vector<std::string>{"spheres-1000", "spheres-250", "spheres-100", "spheres-25", "spheres-10"}));
  EXPECT_EQ(levels.name(), "spheres-1000");
  EXPECT_EQ(levels.pair_distance, PairDistance::d2);
  EXPECT_EQ(levels.merge_radius, MergeRadius::exact);
  EXPECT_EQ(levels.samples, 0u);

  const ProxySpec options = parse_proxy_spec("spheres:100,pair=d1,merge=analytic,samples=20000");
  EXPECT_EQ(options.levels, std::vector<std::size_t>{100});
  EXPECT_EQ(options.pair_distance, PairDistance::d1);
  EXPECT_EQ(options.merge_radius, MergeRadius::analytic);
  EXPECT_EQ(options.samples, 20000u);
  EXPECT_EQ(options.name(), "spheres-100");

  // Levels of different specs share one name space.
  EXPECT_THROW(parse_proxy_specs({"spheres:100,10", "spheres:10,pair=d1"}), Error);
  EXPECT_EQ(parse_proxy_specs({"spheres:100", "spheres:10,pair=d1", "inside:10"}).size(), 3u);
}

class BadProxySpec : public ::testing::TestWithParam<std::pair<const char*, const char*>> {};

TEST_P(BadProxySpec, IsRejectedWithAMessageNamingTheSpec) {
  const auto [text, fragment] = GetParam();
  try {
    parse_proxy_spec(text);
    FAIL() << text << " was accepted";
  } catch (const Error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(std::string("'") + text + "'"), std::string::npos) << message;
    EXPECT_NE(message.find(fragment), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Specs, BadProxySpec,
    ::testing::Values(std::pair{"sphere", "unknown proxy"}, std::pair{"", "unknown proxy"},
                      std::pair{"aabb:3", "takes no parameters"}, std::pair{"hull:0", "at least 1"},
                      std::pair{"hull:3", "at least 4 faces"}, std::pair{"hull:-2", "whole number"},
                      std::pair{"hull:12x", "whole number"}, std::pair{"quadric", "expected quadric:N"},
                      std::pair{"quadric:", "expected quadric:N"}, std::pair{"quadric:1e3", "whole number"},
                      std::pair{"outer:2", "at least 4 triangles"}, std::pair{"cluster:0", "(0, 1]"},
                      std::pair{"cluster:nan", "must be a number"}, std::pair{"cluster:2", "(0, 1]"},
                      std::pair{"wrap:alpha", "expected alpha=A"}, std::pair{"wrap:beta=1", "unknown wrap parameter"},
                      std::pair{"wrap:alpha=0.1,alpha=0.2", "given twice"}, std::pair{"wrap:offset=-1", "(0, 1]"},
                      std::pair{"quadric:999999999999", "at most"}, std::pair{"inside", "expected inside:N"},
                      std::pair{"inside:0", "at least 1"}, std::pair{"spheres", "expected spheres:N"},
                      std::pair{"spheres:0", "at least 1"}, std::pair{"spheres:10,10", "given twice"},
                      std::pair{"spheres:pair=d1", "at least one sphere count"},
                      std::pair{"spheres:10,pair=d3", "unknown spheres parameter"},
                      std::pair{"spheres:10,merge=fit", "unknown spheres parameter"},
                      std::pair{"spheres:10,samples=2", "at least 4"},
                      std::pair{"spheres:10,pair=d1,pair=d2", "given twice"}));

TEST(ProxySpec, SameProxyTwiceIsRejected) {
  EXPECT_THROW(parse_proxy_specs({"hull:32", "aabb", "hull:32"}), Error);
  EXPECT_EQ(parse_proxy_specs({"hull:32", "hull:18"}).size(), 2u);
}

}  // namespace
}  // namespace visproxy
