// The recommendation: the proxy it names for each use is the one whose predicted efficiency
// is largest, its figures are estimator/efficiency.h's, bounds never rest on a claim that
// is not proved, a proxy worse than the mesh is not called cheaper, and the JSON matches
// its schema.

#include "visproxy/evaluate/recommendation.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "schema_support.h"

namespace visproxy {
namespace {

using nlohmann::json;

json entry(const std::string& name, const std::string& kind, std::array<std::uint64_t, 4> counts, double proxy_ns,
           double mesh_ns, double primitives = 12) {
  return {
      {"name", name},
      {"kind", kind},
      {"primitives", primitives},
      {"measure",
       {{"rays", {{"kind", "isotropic lines"}, {"count", counts[0] + counts[1] + counts[2] + counts[3]}, {"seed", 7}}},
        {"counts", counts},
        {"cost_ns_per_ray", {{"proxy", proxy_ns}, {"mesh", mesh_ns}}}}}};
}

json manifest_of(json proxies) { return {{"mesh", {{"path", "mesh.off"}}}, {"proxies", std::move(proxies)}}; }

ProvedKind as_claimed() {
  return [](const json& e) {
    const std::string kind = e.at("kind");
    return kind == "outside" ? ProxyKind::outside : kind == "inside" ? ProxyKind::inside : ProxyKind::general;
  };
}

std::size_t index_of(ProxyUse use) {
  return static_cast<std::size_t>(std::find(kProxyUses.begin(), kProxyUses.end(), use) - kProxyUses.begin());
}

TEST(Recommendation, NamesTheMostEfficientProxyForEachUseWithTheEstimatorsFigures) {
  // A tight outside proxy (few rays where it disagrees) that is cheap, a loose one, and a
  // general proxy.
  const json manifest = manifest_of({entry("tight", "outside", {3000, 0, 400, 6600}, 20, 200),
                                     entry("loose", "outside", {3000, 0, 3000, 4000}, 10, 200),
                                     entry("rough", "general", {2800, 200, 300, 6700}, 15, 200)});
  const Recommendation r = recommend_proxies(manifest, as_claimed());
  ASSERT_EQ(r.proxies.size(), 3u);
  EXPECT_NE(r.rays.find("10000 isotropic lines"), std::string::npos) << r.rays;
  for (std::size_t u = 0; u < kProxyUses.size(); ++u) {
    const UseChoice& choice = r.choices[u];
    ASSERT_GE(choice.best, 0) << choice.sentence;
    for (const ProxyEfficiency& p : r.proxies) {
      const UseFigures& f = p.uses[u];
      if (!f.prediction.usable) continue;
      // The chosen one is the largest.
      EXPECT_LE(f.prediction.efficiency,
                r.proxies[static_cast<std::size_t>(choice.best)].uses[u].prediction.efficiency);
      // The figures are the estimator's, for the proved kind.
      RayTypeCounts counts;
      const json& c = manifest["proxies"][static_cast<std::size_t>(&p - r.proxies.data())]["measure"]["counts"];
      for (std::size_t i = 0; i < 4; ++i) counts.counts[i] = c[i].get<std::uint64_t>();
      const json& cost =
          manifest["proxies"][static_cast<std::size_t>(&p - r.proxies.data())]["measure"]["cost_ns_per_ray"];
      const UsePrediction direct = predict_use(kProxyUses[u], p.proved, RayTypeFractions::from(counts),
                                               {cost["proxy"].get<double>(), cost["mesh"].get<double>()});
      EXPECT_DOUBLE_EQ(f.prediction.efficiency, direct.efficiency);
      EXPECT_LE(f.interval.lower, f.prediction.efficiency * 1.05);
      EXPECT_GE(f.interval.upper, f.prediction.efficiency * 0.95);
    }
    const std::string& name = r.proxies[static_cast<std::size_t>(choice.best)].name;
    EXPECT_NE(choice.sentence.find(name), std::string::npos) << choice.sentence;
    EXPECT_NE(choice.sentence.find(" cheaper than the mesh"), std::string::npos) << choice.sentence;
  }
  // Bounds use only the outside proxies: the tight one traces the mesh on 34 % of rays, the loose one on 60 %.
  EXPECT_EQ(r.proxies[static_cast<std::size_t>(r.choices[index_of(ProxyUse::bounds)].best)].name, "tight");
  EXPECT_FALSE(r.proxies[2].uses[index_of(ProxyUse::bounds)].prediction.usable);
}

TEST(Recommendation, BoundsNeverRestOnAClaimThatIsNotProved) {
  // Both claim outside; the verdict proves neither (files edited since, or no verify).
  const json manifest = manifest_of(
      {entry("a", "outside", {3000, 0, 400, 6600}, 20, 200), entry("b", "inside", {2000, 1000, 0, 7000}, 20, 200)});
  const Recommendation r = recommend_proxies(manifest, [](const json&) { return ProxyKind::general; });
  const UseChoice& bounds = r.choices[index_of(ProxyUse::bounds)];
  EXPECT_EQ(bounds.best, -1);
  EXPECT_NE(bounds.sentence.find("no proxy is usable"), std::string::npos) << bounds.sentence;
  EXPECT_NE(bounds.sentence.find("verify"), std::string::npos) << bounds.sentence;
  for (const ProxyEfficiency& p : r.proxies) EXPECT_EQ(p.proved, ProxyKind::general);
  // The stochastic uses still apply, as general proxies.
  EXPECT_GE(r.choices[index_of(ProxyUse::control_variate)].best, 0);
}

TEST(Recommendation, AProxyCostlierThanTheMeshIsNotCalledCheaper) {
  // A proxy that costs more than the mesh and disagrees often.
  const json manifest = manifest_of({entry("slow", "general", {2000, 1000, 1000, 6000}, 400, 100)});
  const Recommendation r = recommend_proxies(manifest, as_claimed());
  for (std::size_t u = 0; u < 2; ++u) {
    const UseChoice& choice = r.choices[u];
    ASSERT_EQ(choice.best, 0);
    EXPECT_LT(r.proxies[0].uses[u].prediction.efficiency, 1.0);
    EXPECT_NE(choice.sentence.find("no proxy is predicted cheaper than the mesh"), std::string::npos)
        << choice.sentence;
    EXPECT_NE(choice.sentence.find("trace the mesh"), std::string::npos) << choice.sentence;
  }
}

TEST(Recommendation, CloseRivalsAreSaidToBeCloseAndUnmeasuredProxiesLeftOut) {
  // The same counts and costs: the intervals cannot tell them apart.
  const json manifest = manifest_of({entry("one", "outside", {3000, 0, 400, 6600}, 20, 200),
                                     entry("two", "outside", {3000, 0, 400, 6600}, 20, 200),
                                     {{"name", "unmeasured"}, {"kind", "outside"}, {"primitives", 6}}});
  const Recommendation r = recommend_proxies(manifest, as_claimed());
  EXPECT_EQ(r.proxies.size(), 2u);
  EXPECT_NE(r.choices[0].sentence.find("is not told apart from it by the intervals"), std::string::npos)
      << r.choices[0].sentence;

  const Recommendation none =
      recommend_proxies(manifest_of(json::array({{{"name", "x"}, {"kind", "outside"}}})), as_claimed());
  for (const UseChoice& choice : none.choices) {
    EXPECT_EQ(choice.best, -1);
    EXPECT_NE(choice.sentence.find("no proxy has been measured"), std::string::npos) << choice.sentence;
  }
}

TEST(Recommendation, AnIntervalHoldingOneClaimsNoGain) {
  // Bounds trace the proxy on every ray and the mesh on the half the proxy blocks; the
  // proxy costs half the mesh: 50 + 100 / 2 = 100 ns, the mesh's own cost, on only 100 rays.
  const json manifest = manifest_of({entry("even", "outside", {30, 0, 20, 50}, 50, 100)});
  const Recommendation r = recommend_proxies(manifest, as_claimed());
  const UseFigures& f = r.proxies[0].uses[index_of(ProxyUse::bounds)];
  ASSERT_LT(f.interval.lower, 1.0);
  ASSERT_GT(f.interval.upper, 1.0);
  EXPECT_NE(r.choices[index_of(ProxyUse::bounds)].sentence.find("as efficient as the mesh: the interval holds 1"),
            std::string::npos)
      << r.choices[index_of(ProxyUse::bounds)].sentence;
}

TEST(Recommendation, UntimedCostsMakeNoClaim) {
  const json manifest = manifest_of({entry("a", "outside", {3000, 0, 400, 6600}, 0, 0)});
  const Recommendation r = recommend_proxies(manifest, as_claimed());
  for (const UseChoice& choice : r.choices) {
    EXPECT_EQ(choice.best, -1);
    EXPECT_NE(choice.sentence.find("cost per ray not measured"), std::string::npos) << choice.sentence;
  }
}

TEST(Recommendation, JsonMatchesItsSchemaAndIsReproducible) {
  const json manifest = manifest_of({entry("tight", "outside", {3000, 0, 400, 6600}, 20, 200),
                                     entry("rough", "general", {2800, 200, 300, 6700}, 15, 200),
                                     entry("exact", "general", {3000, 0, 0, 7000}, 15, 200)});
  const json a = recommendation_json(recommend_proxies(manifest, as_claimed()), manifest);
  const json b = recommendation_json(recommend_proxies(manifest, as_claimed()), manifest);
  EXPECT_EQ(a, b);
  testing::expect_described(a, "recommendation.schema.json");
  EXPECT_EQ(a["uses"]["bounds"]["proxy"], "tight");
  EXPECT_EQ(a["proxies"][1]["bounds"]["usable"], false);
  EXPECT_TRUE(a["proxies"][0]["control_variate"].contains("setting"));
  EXPECT_EQ(a["seed"], 7);
}

}  // namespace
}  // namespace visproxy
