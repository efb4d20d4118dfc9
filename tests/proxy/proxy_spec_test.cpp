#include "proxy/proxy_spec.h"

#include <gtest/gtest.h>

#include "core/errors.h"

namespace visproxy {
namespace {

TEST(ProxySpec, ParsesEveryMethodAndNamesIt) {
  EXPECT_EQ(parse_proxy_spec("aabb").method, ProxyMethod::aabb);
  EXPECT_EQ(parse_proxy_spec("obb").name(), "obb");
  EXPECT_EQ(parse_proxy_spec("hull").method, ProxyMethod::convex_hull);
  const ProxySpec bounded = parse_proxy_spec("hull:32");
  EXPECT_EQ(bounded.method, ProxyMethod::bounded_hull);
  EXPECT_EQ(bounded.count, 32u);
  EXPECT_EQ(bounded.name(), "hull-32");
  const ProxySpec outer = parse_proxy_spec("outer:512");
  EXPECT_EQ(outer.method, ProxyMethod::outer_hull);
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
                                             "cluster-0.03"}));
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
                      std::pair{"quadric:999999999999", "at most"}));

TEST(ProxySpec, SameProxyTwiceIsRejected) {
  EXPECT_THROW(parse_proxy_specs({"hull:32", "aabb", "hull:32"}), Error);
  EXPECT_EQ(parse_proxy_specs({"hull:32", "hull:18"}).size(), 2u);
}

}  // namespace
}  // namespace visproxy
