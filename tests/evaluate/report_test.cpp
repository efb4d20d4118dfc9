// The report's page: the recommendation first, one figure of four embedded PNGs per proxy,
// the plots inline, names that would break the HTML or a file name escaped.

#include "visproxy/evaluate/report.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "visproxy/image/image.h"

namespace visproxy {
namespace {

using nlohmann::json;

std::size_t occurrences(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

json measured(const std::string& name, const std::string& kind, double primitives,
              std::array<std::uint64_t, 4> counts) {
  return {{"name", name},
          {"kind", kind},
          {"primitives", primitives},
          {"primitive_type", "triangle"},
          {"measure",
           {{"rays", {{"kind", "isotropic lines"}, {"count", 10000}, {"seed", 3}}},
            {"counts", counts},
            {"f_miss", {{"value", 0.8}, {"lower", 0.79}, {"upper", 0.81}}},
            {"cost_ns_per_ray", {{"proxy", 20.0}, {"mesh", 200.0}, {"proxy_over_mesh", 0.1}}}}}};
}

struct Fixture {
  json manifest;
  ReportFigures figures;
};

Fixture fixture() {
  Fixture f;
  f.manifest = {
      {"mesh", {{"path", "meshes/<knot>.off"}, {"vertices", 3}, {"triangles", 1}, {"bbox", {{"diagonal", 1.0}}}}},
      {"proxies",
       {measured("hull", "outside", 64, {3000, 0, 400, 6600}),
        measured("a<b>\"c", "general", 512, {2800, 200, 300, 6700}),
        measured("../up", "general", 8, {2000, 1000, 1000, 6000})}}};
  f.figures.recommendation = recommend_proxies(
      f.manifest, [](const json& e) { return e.at("kind") == "outside" ? ProxyKind::outside : ProxyKind::general; });
  Image tiny(4, 4);
  tiny.at(1, 2) = Color(1, 0, 0);
  const std::string png = encode_png(tiny);
  f.figures.pictured = true;
  f.figures.picture_options.size = 4;
  f.figures.mesh_shadow_png = png;
  for (const char* name : {"hull", "a<b>\"c", "../up"}) f.figures.pictures[name] = {png, png, png, 0.0, 0.25};
  return f;
}

TEST(Report, TheRecommendationComesFirstAndEveryProxyHasItsFourPictures) {
  const Fixture f = fixture();
  const std::string html = report_html(f.manifest, f.figures);
  const std::size_t recommendation = html.find("<section id=\"recommendation\">");
  ASSERT_NE(recommendation, std::string::npos);
  EXPECT_LT(recommendation, html.find("<table"));
  // What to ship, then the recommendation: one line per use in each.
  const std::size_t ship = html.find("<section id=\"ship\">");
  ASSERT_NE(ship, std::string::npos);
  EXPECT_LT(ship, recommendation);
  EXPECT_EQ(occurrences(html, "<li data-use="), 6u);
  for (const ShippingLine& line : shipping_lines(f.figures, f.manifest))
    EXPECT_NE(html.find(escape_html(line.text)), std::string::npos) << line.text;
  EXPECT_NE(html.find(escape_html(f.figures.recommendation.choices[0].sentence)), std::string::npos);
  EXPECT_EQ(occurrences(html, "<figure class=\"proxy\""), 3u);
  EXPECT_EQ(occurrences(html, "src=\"data:image/png;base64,iVBORw0KGgo"), 12u);  // the PNG signature, base64
  EXPECT_EQ(html.find("a<b>"), std::string::npos);                               // escaped everywhere
  EXPECT_NE(html.find("missed shadow 0.0 %, extra shadow 25.0 %"), std::string::npos);
  // Both plots inline; the efficiency plot has a point per proxy and usable use.
  EXPECT_EQ(occurrences(html, "<svg"), 2u);
  const std::string efficiency = efficiency_plot_svg(f.manifest, f.figures.recommendation);
  EXPECT_EQ(occurrences(efficiency, "<g class=\"point\">"),
            3u + 3u + 1u);  // control variate, eq. 8: 3 each; bounds: hull
  EXPECT_NE(efficiency.find("the mesh alone"), std::string::npos);
  EXPECT_NE(efficiency.find("class=\"front\""), std::string::npos);
}

TEST(Report, MarkdownLinksThePicturesUnderSafeNames) {
  const Fixture f = fixture();
  const std::string md = report_markdown(f.manifest, f.figures);
  ASSERT_NE(md.find("## Recommendation"), std::string::npos);
  EXPECT_LT(md.find("## Recommendation"), md.find("| proxy | kind |"));
  EXPECT_NE(md.find("(pictures/hull-overlay.png)"), std::string::npos);
  EXPECT_NE(md.find("(pictures/_._up-shadow.png)"), std::string::npos);  // no way out of pictures/
  EXPECT_EQ(picture_stem("../up"), "_._up");
  EXPECT_EQ(picture_stem(".hidden"), "_hidden");
  EXPECT_EQ(picture_stem(""), "proxy");
  EXPECT_NE(md.find("(efficiency.svg)"), std::string::npos);
}

TEST(Report, WithoutFiguresThePageIsTheTableAlone) {
  const Fixture f = fixture();
  const std::string html = report_html(f.manifest);
  EXPECT_EQ(html.find("id=\"recommendation\""), std::string::npos);
  EXPECT_EQ(html.find("<img"), std::string::npos);
  EXPECT_NE(html.find("<table"), std::string::npos);
}

}  // namespace
}  // namespace visproxy
