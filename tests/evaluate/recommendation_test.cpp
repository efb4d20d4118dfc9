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

// An entry whose cost was timed in blocks: proxy / mesh over the blocks from `low` to `high`.
json timed_entry(const std::string& name, std::array<std::uint64_t, 4> counts, double proxy_ns, double mesh_ns, double low,
                 double high, double primitives) {
  json e = entry(name, "outside", counts, proxy_ns, mesh_ns, primitives);
  e["measure"]["cost_ns_per_ray"]["proxy_over_mesh_range"] = {low, high};
  return e;
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
  EXPECT_NE(r.choices[index_of(ProxyUse::bounds)].sentence.find("; trace the mesh"), std::string::npos)
      << r.choices[index_of(ProxyUse::bounds)].sentence;
}

// The proxy's cost as timed in blocks beside the mesh: the interval takes in the blocks'
// spread (its ends at the dearest and the cheapest block), still holds the prediction, and
// is the sampling interval alone when the blocks agree.
TEST(Recommendation, TheTimingSpreadWidensTheInterval) {
  const std::array<std::uint64_t, 4> counts = {3000, 0, 400, 6600};
  const Recommendation spread = recommend_proxies(manifest_of({timed_entry("a", counts, 20, 200, 0.05, 0.2, 12)}), as_claimed());
  const Recommendation tight = recommend_proxies(manifest_of({timed_entry("a", counts, 20, 200, 0.1, 0.1, 12)}), as_claimed());
  const Recommendation as_measured = recommend_proxies(manifest_of({entry("a", "outside", counts, 20, 200)}), as_claimed());
  for (std::size_t u = 0; u < kProxyUses.size(); ++u) {
    const UseFigures &s = spread.proxies[0].uses[u], &t = tight.proxies[0].uses[u], &m = as_measured.proxies[0].uses[u];
    EXPECT_DOUBLE_EQ(s.prediction.efficiency, t.prediction.efficiency);
    EXPECT_LT(s.interval.lower, t.interval.lower * 0.9) << use_name(kProxyUses[u]);
    EXPECT_GT(s.interval.upper, t.interval.upper * 1.1) << use_name(kProxyUses[u]);
    EXPECT_LE(s.interval.lower, s.prediction.efficiency);
    EXPECT_GE(s.interval.upper, s.prediction.efficiency);
    EXPECT_DOUBLE_EQ(t.interval.lower, m.interval.lower);
    EXPECT_DOUBLE_EQ(t.interval.upper, m.interval.upper);
  }
}

// Two proxies whose intervals overlap: which one the timing noise puts ahead changes from
// run to run, the recommendation does not. It goes to the one with fewer primitives, and
// names the other; a proxy the intervals do separate still wins on efficiency.
TEST(Recommendation, NoiseBetweenRunsDoesNotFlipTheChoice) {
  const std::array<std::uint64_t, 4> counts = {3000, 0, 400, 6600};
  for (const double big_ratio : {0.08, 0.1, 0.12}) {  // three runs: the big proxy's cost moved by noise
    const json manifest = manifest_of({timed_entry("big", counts, big_ratio * 200, 200, big_ratio * 0.7, big_ratio * 1.4, 5000),
                                       timed_entry("small", counts, 20, 200, 0.07, 0.14, 800)});
    const Recommendation r = recommend_proxies(manifest, as_claimed());
    for (const UseChoice& choice : r.choices) {
      ASSERT_EQ(choice.best, 1) << "run with ratio " << big_ratio << ": " << choice.sentence;
      EXPECT_NE(choice.sentence.find("big, at"), std::string::npos) << choice.sentence;
      EXPECT_NE(choice.sentence.find("has more primitives"), std::string::npos) << choice.sentence;
    }
  }
  // A smaller proxy not told apart from the best but not itself shown cheaper than the mesh
  // is not chosen over it; when the best is not shown cheaper, it is the one named.
  const std::array<std::uint64_t, 4> half = {3000, 0, 2000, 5000}, few = {3, 0, 2, 5};  // 10 rays: a wide interval
  const json edge = manifest_of({timed_entry("big", half, 20, 200, 0.09, 0.11, 5000),
                                 timed_entry("small", few, 60, 200, 0.25, 0.35, 10)});
  const Recommendation edge_r = recommend_proxies(edge, as_claimed());
  const UseFigures& big_bounds = edge_r.proxies[0].uses[index_of(ProxyUse::bounds)];
  const UseFigures& small_bounds = edge_r.proxies[1].uses[index_of(ProxyUse::bounds)];
  ASSERT_GT(big_bounds.interval.lower, 1.0);
  ASSERT_GE(small_bounds.interval.upper, big_bounds.interval.lower);  // not told apart
  ASSERT_LT(small_bounds.interval.lower, 1.0);                        // but not shown cheaper
  const std::array<std::uint64_t, 4> even = {30, 0, 20, 50};
  EXPECT_EQ(edge_r.choices[index_of(ProxyUse::bounds)].best, 0) << edge_r.choices[index_of(ProxyUse::bounds)].sentence;
  const Recommendation alone = recommend_proxies(manifest_of({timed_entry("small", even, 50, 100, 0.45, 0.55, 10),
                                                              timed_entry("tiny", even, 52, 100, 0.47, 0.57, 2)}),
                                                 as_claimed());
  EXPECT_EQ(alone.choices[index_of(ProxyUse::bounds)].best, 0) << alone.choices[index_of(ProxyUse::bounds)].sentence;
  EXPECT_NE(alone.choices[index_of(ProxyUse::bounds)].sentence.find("trace the mesh"), std::string::npos);
  // Separated: the big proxy at a third of the small one's cost with tight blocks.
  const json manifest = manifest_of({timed_entry("big", counts, 6, 200, 0.029, 0.031, 5000),
                                     timed_entry("small", counts, 60, 200, 0.29, 0.31, 800)});
  for (const UseChoice& choice : recommend_proxies(manifest, as_claimed()).choices) EXPECT_EQ(choice.best, 0) << choice.sentence;
}

// A proxy whose point estimate is highest but whose interval holds 1 (its cost is not
// pinned down) does not hide one shown cheaper: the choice goes by the gain the interval
// guarantees, so that a run where noise lifts the uncertain proxy's point does not turn
// the advice into "trace the mesh" (armadillo's control variate flipped that way).
TEST(Recommendation, AShownGainIsNotHiddenByAnUncertainHigherPoint) {
  const std::array<std::uint64_t, 4> counts = {3000, 0, 400, 6600};
  const json manifest = manifest_of({timed_entry("uncertain", counts, 10, 200, 0.02, 1.5, 40),
                                     timed_entry("sure", counts, 40, 200, 0.19, 0.21, 400)});
  const Recommendation r = recommend_proxies(manifest, as_claimed());
  const std::size_t u = index_of(ProxyUse::bounds);
  ASSERT_GT(r.proxies[0].uses[u].prediction.efficiency, r.proxies[1].uses[u].prediction.efficiency);
  ASSERT_LT(r.proxies[0].uses[u].interval.lower, 1.0);
  ASSERT_GT(r.proxies[1].uses[u].interval.lower, 1.0);
  EXPECT_EQ(r.choices[u].best, 1) << r.choices[u].sentence;
  EXPECT_NE(r.choices[u].sentence.find("sure is predicted"), std::string::npos) << r.choices[u].sentence;
}

// A run that fitted a cost model gives each proxy the model's interval of its cost ratio,
// wider than its blocks': the recommendation reads that one, and the blocks' alone only
// from manifests measured without a model.
TEST(Recommendation, TheCostModelsIntervalIsTheOneRead) {
  const std::array<std::uint64_t, 4> counts = {3000, 0, 400, 6600};
  json blocks = timed_entry("a", counts, 20, 200, 0.095, 0.105, 12);
  json modelled = blocks;
  modelled["measure"]["cost_ns_per_ray"]["predicted"] = {{"proxy_over_mesh", 0.11}, {"interval", {0.06, 0.16}}};
  const Recommendation rb = recommend_proxies(manifest_of({blocks}), as_claimed());
  const UseFigures& b = rb.proxies[0].uses[index_of(ProxyUse::bounds)];
  const Recommendation rm = recommend_proxies(manifest_of({modelled}), as_claimed());
  const UseFigures& m = rm.proxies[0].uses[index_of(ProxyUse::bounds)];
  EXPECT_DOUBLE_EQ(b.prediction.efficiency, m.prediction.efficiency);  // the point is the timed median
  EXPECT_LT(m.interval.lower, b.interval.lower * 0.95);
  EXPECT_GT(m.interval.upper, b.interval.upper * 1.05);
}

// A budget of primitives: a proxy over it is usable for no use, says why, keeps its row,
// and the recommendation goes to the best one within the budget.
TEST(Recommendation, ABudgetLeavesOutTheLargerProxies) {
  const json manifest = manifest_of({entry("big", "outside", {3000, 0, 100, 6900}, 20, 200, 5000),
                                     entry("small", "outside", {3000, 0, 900, 6100}, 20, 200, 300)});
  const Recommendation any = recommend_proxies(manifest, as_claimed());
  EXPECT_EQ(any.choices[index_of(ProxyUse::bounds)].best, 0);
  const Recommendation within = recommend_proxies(manifest, as_claimed(), 1000);
  ASSERT_EQ(within.proxies.size(), 2u);
  for (std::size_t u = 0; u < kProxyUses.size(); ++u) {
    EXPECT_EQ(within.choices[u].best, 1) << within.choices[u].sentence;
    EXPECT_FALSE(within.proxies[0].uses[u].prediction.usable);
    EXPECT_EQ(within.proxies[0].uses[u].prediction.why_not, "over the budget of 1000 primitives");
  }
  const Recommendation none = recommend_proxies(manifest, as_claimed(), 100);
  for (const UseChoice& choice : none.choices) EXPECT_EQ(choice.best, -1) << choice.sentence;
  EXPECT_NE(none.choices[0].sentence.find("over the budget of 100 primitives"), std::string::npos) << none.choices[0].sentence;
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

// Over the render, each use's figure comes from the render's own noise when the manifest
// has it: bounds add no noise (Amdahl's law alone); a noisier exact render dilutes what eq.
// 8 and the control variate add, so their figures rise, their intervals holding them; eq.
// 8 takes the probabilities the renderer's optimal mode finds, with the mesh's own
// segments where they share the proxy's form and apart where they do not; and a manifest
// measured before the noise was recorded keeps the shadow ray's ratio.
TEST(Recommendation, TheRenderFiguresComeFromTheRendersNoise) {
  auto manifest_with = [](const std::string& kind, double exact_variance, double own_weight, bool noise) {
    json box = entry("box", kind, {6000, 0, 300, 3700}, 30, 200);
    box["measure"]["rays"]["kind"] = "scene shadow segments";
    box["measure"]["rays"]["instances_of_mesh"] = 1;
    box["measure"]["render_noise"] = {{"segments_by_type", {6000, 0, 300, 3700}},
                                      {"squared_contribution_by_type", {0.05, 0.0, 0.04, 0.2}},
                                      {"squared_contribution_squares_by_type", {0.01, 0.0, 0.01, 0.05}}};
    json m = manifest_of({box});
    m["render_share"] = {{"share", 0.3}, {"scene", "s.json"}};
    if (noise)
      m["render_share"]["noise"] = {{"camera_samples", 40000},
                                    {"exact_variance_per_sample", exact_variance},
                                    {"standard_error", 0.01 * exact_variance},
                                    {"own_instances_squared_contribution_by_type", {0.02, 0.0, 0.0, own_weight}},
                                    {"own_instances_squared_contribution_squares_by_type", {0.001, 0.0, 0.0, 0.05}},
                                    {"own_instances_segments_by_type", {500, 0, 0, 3000}}};
    return m;
  };
  auto figures = [](const json& m, ProxyUse use) { return recommend_proxies(m, as_claimed()).proxies.at(0).uses[index_of(use)]; };
  const double s = 0.3;
  const UseFigures bounds = figures(manifest_with("outside", 0.5, 0.3, true), ProxyUse::bounds);
  EXPECT_NEAR(bounds.render_efficiency, 1 / ((1 - s) + s * bounds.prediction.ns_per_ray / 200), 1e-12);
  for (const ProxyUse use : {ProxyUse::term_choice, ProxyUse::control_variate}) {
    const UseFigures quiet = figures(manifest_with("outside", 0.5, 0.3, true), use);
    const UseFigures noisy = figures(manifest_with("outside", 5.0, 0.3, true), use);
    EXPECT_GT(quiet.render_efficiency, 0) << use_name(use);
    EXPECT_LT(quiet.render_efficiency, noisy.render_efficiency) << use_name(use);
    for (const UseFigures& f : {quiet, noisy}) {
      EXPECT_LE(f.render_interval.lower, f.render_efficiency) << use_name(use);
      EXPECT_GE(f.render_interval.upper, f.render_efficiency) << use_name(use);
    }
  }
  // Eq. 8 over the render: the probabilities of the renderer's optimal mode, one set for the
  // proxy's segments and the mesh's own when an outside proxy shares its form with the
  // exact rest of the scene; then the own segments' noise counts with those probabilities.
  {
    const UseFigures f = figures(manifest_with("outside", 0.5, 0.3, true), ProxyUse::term_choice);
    const Probabilities p = optimal_probabilities(ProxyKind::outside, RayTypeFractions::from(RayTypeCounts{{6500, 0, 300, 6700}}),
                                                  {.floor = UseOptions{}.floor});
    UseSetting setting;
    setting.term = p;
    const std::array<double, 4> g = added_variance_by_type(ProxyUse::term_choice, setting);
    const double added = 0.05 * g[0] + 0.04 * g[2] + 0.2 * g[3] + 0.02 * g[0] + 0.3 * g[3];
    const RayTypeFractions fractions = RayTypeFractions::from(RayTypeCounts{{6000, 0, 300, 3700}});
    const double cost = predict_use_at(ProxyUse::term_choice, ProxyKind::outside, fractions, TraceCosts{30, 200}, setting).ns_per_ray / 200;
    EXPECT_NEAR(f.render_efficiency, render_efficiency_of(cost, 1 + added / 0.5, s), 1e-9);
  }
  // A general proxy of a mesh placed once: the mesh's own segments see an exact rest of the
  // scene, of the outside form, whose probabilities the renderer finds from them alone.
  {
    const UseFigures f = figures(manifest_with("general", 0.5, 0.3, true), ProxyUse::term_choice);
    UseSetting others, own;
    others.term = optimal_probabilities(ProxyKind::general, RayTypeFractions::from(RayTypeCounts{{6000, 0, 300, 3700}}),
                                        {.floor = UseOptions{}.floor});
    own.term = optimal_probabilities(ProxyKind::outside, RayTypeFractions::from(RayTypeCounts{{500, 0, 0, 3000}}),
                                     {.floor = UseOptions{}.floor});
    EXPECT_GT(own.term.p1, others.term.p1);
    const std::array<double, 4> g = added_variance_by_type(ProxyUse::term_choice, others),
                                own_g = added_variance_by_type(ProxyUse::term_choice, own);
    const double added = 0.05 * g[0] + 0.04 * g[2] + 0.2 * g[3] + 0.02 * own_g[0] + 0.3 * own_g[3];
    const RayTypeFractions fractions = RayTypeFractions::from(RayTypeCounts{{6000, 0, 300, 3700}});
    const double cost = predict_use_at(ProxyUse::term_choice, ProxyKind::general, fractions, TraceCosts{30, 200}, others).ns_per_ray / 200;
    EXPECT_NEAR(f.render_efficiency, render_efficiency_of(cost, 1 + added / 0.5, s), 1e-9);
  }
  // More weight on the mesh's own segments, more of eq. 8's noise.
  EXPECT_GT(figures(manifest_with("outside", 0.5, 0.3, true), ProxyUse::term_choice).render_efficiency,
            figures(manifest_with("outside", 0.5, 3.0, true), ProxyUse::term_choice).render_efficiency);
  // Without the noise: the shadow ray's ratio, as before.
  const UseFigures old = figures(manifest_with("outside", 0.5, 0.3, false), ProxyUse::term_choice);
  const RayTypeFractions fractions = RayTypeFractions::from(RayTypeCounts{{6000, 0, 300, 3700}});
  const double ratio = old.prediction.variance / (fractions.v_avg() * (1 - fractions.v_avg()));
  EXPECT_NEAR(old.render_efficiency, render_efficiency(old.prediction.efficiency, ratio, s), 1e-12);
}

// The render share is timed in rounds; the render interval spans the share's range (the
// render's gain is monotone in it), the point stays at the median share, and a range edited
// by hand so that it leaves out the share is widened to hold it.
TEST(Recommendation, TheRenderIntervalSpansTheSharesRange) {
  auto manifest_with = [](const json& range) {
    json box = entry("box", "outside", {6000, 0, 300, 3700}, 30, 200);
    box["measure"]["rays"]["kind"] = "scene shadow segments";
    json m = manifest_of({box});
    m["render_share"] = {{"share", 0.3}, {"scene", "s.json"}};
    if (!range.is_null()) m["render_share"]["share_range"] = range;
    return m;
  };
  auto bounds = [](const json& m) { return recommend_proxies(m, as_claimed()).proxies.at(0).uses[index_of(ProxyUse::bounds)]; };
  const UseFigures narrow = bounds(manifest_with(nullptr)), wide = bounds(manifest_with({0.1, 0.5}));
  EXPECT_DOUBLE_EQ(narrow.render_efficiency, wide.render_efficiency);
  ASSERT_GT(wide.prediction.efficiency, 1);  // a gain: more share, more of it
  EXPECT_LT(wide.render_interval.lower, narrow.render_interval.lower);
  EXPECT_GT(wide.render_interval.upper, narrow.render_interval.upper);
  EXPECT_NEAR(wide.render_interval.upper, render_efficiency(wide.interval.upper, 1, 0.5), 1e-12);
  EXPECT_NEAR(wide.render_interval.lower, render_efficiency(wide.interval.lower, 1, 0.1), 1e-12);
  const UseFigures edited = bounds(manifest_with({0.4, 0.6}));
  EXPECT_NEAR(edited.render_interval.lower, render_efficiency(edited.interval.lower, 1, 0.3), 1e-12);
  const json out = recommendation_json(recommend_proxies(manifest_with({0.4, 0.6}), as_claimed()), manifest_with({0.4, 0.6}));
  EXPECT_EQ(out["render_share"]["share_range"], json({0.3, 0.6}));
  testing::expect_described(out, "recommendation.schema.json");
}

// Measured on a scene, the advice weighs the render: a box that makes a shadow ray 2x
// cheaper, in a scene whose samples spend 1 % of their time on the mesh's shadow rays,
// gains nothing worth shipping (its render interval holds 1 once the share's rounds spread
// it); in a scene that spends 60 % there it is shipped. Per shadow ray it is cheaper both
// times, and the sentence says so before the render's verdict.
TEST(Recommendation, OnASceneTheRendersFiguresDecide) {
  auto manifest_with = [](double share, const json& range) {
    json box = entry("box", "outside", {3000, 0, 100, 6900}, 50, 200);
    box["measure"]["rays"]["kind"] = "scene shadow segments";
    json m = manifest_of({box});
    m["render_share"] = {{"share", share}, {"scene", "s.json"}, {"share_range", range}};
    return m;
  };
  for (const bool busy : {false, true}) {
    const json m = busy ? manifest_with(0.6, {0.55, 0.65}) : manifest_with(0.01, {0.0, 0.02});
    const Recommendation r = recommend_proxies(m, as_claimed());
    const UseFigures& f = r.proxies.at(0).uses[index_of(ProxyUse::bounds)];
    ASSERT_TRUE(f.at_render());
    EXPECT_GT(f.interval.lower, 1.5) << busy;  // per shadow ray: clearly cheaper
    EXPECT_EQ(f.shown_cheaper(), busy);
    if (!busy) {
      EXPECT_LE(f.render_interval.lower, 1.0);
    }
    const json out = recommendation_json(r, m);
    EXPECT_EQ(out["uses"]["bounds"]["beats_mesh"], busy);
    const std::string sentence = out["uses"]["bounds"]["sentence"];
    EXPECT_NE(sentence.find("as efficient as the mesh per shadow ray"), std::string::npos) << sentence;
    EXPECT_EQ(sentence.find("trace the mesh") != std::string::npos, !busy) << sentence;
    if (busy) {
      EXPECT_NE(sentence.find("cheaper than the mesh over the render"), std::string::npos) << sentence;
    } else {
      EXPECT_NE(sentence.find("no gain over the render is shown"), std::string::npos) << sentence;
    }
  }
}

// With the render's own passes timed against exact's (render_time), the render figure is
// 1 / (noise ratio x time ratio) and its interval spans the rounds' range: bounds, which add
// no noise, at 1 / time; a proxy 1.5x cheaper per shadow ray whose render passes took 1.05x
// exact's is not advised. A range edited by hand to leave out the median is widened to hold
// it; a use without a timed pass keeps the share's model.
TEST(Recommendation, TimedRenderPassesReplaceTheSharesModel) {
  auto manifest_with = [](const json& time) {
    json box = entry("box", "outside", {3000, 0, 100, 6900}, 50, 200);
    box["measure"]["rays"]["kind"] = "scene shadow segments";
    box["measure"]["rays"]["instances_of_mesh"] = 1;
    box["measure"]["render_noise"] = {{"segments_by_type", {3000, 0, 100, 6900}},
                                      {"squared_contribution_by_type", {0.05, 0.0, 0.04, 0.2}},
                                      {"squared_contribution_squares_by_type", {0.01, 0.0, 0.01, 0.05}}};
    box["measure"]["render_time"] = {{"rounds", 6}, {"width", 128}, {"height", 96}, {"bounds", time}};
    json m = manifest_of({box});
    m["render_share"] = {{"share", 0.5}, {"scene", "s.json"}, {"share_range", {0.45, 0.55}}};
    m["render_share"]["noise"] = {{"camera_samples", 40000},
                                  {"exact_variance_per_sample", 0.5},
                                  {"standard_error", 0.005},
                                  {"own_instances_squared_contribution_by_type", {0.0, 0.0, 0.0, 0.0}},
                                  {"own_instances_squared_contribution_squares_by_type", {0.0, 0.0, 0.0, 0.0}},
                                  {"own_instances_segments_by_type", {0, 0, 0, 0}}};
    return m;
  };
  const json m = manifest_with({{"pass_time_over_exact", 1.05}, {"range", {1.02, 1.09}}});
  const Recommendation r = recommend_proxies(m, as_claimed());
  const UseFigures& bounds = r.proxies.at(0).uses[index_of(ProxyUse::bounds)];
  EXPECT_GT(bounds.interval.lower, 1.5);  // per shadow ray: far cheaper
  EXPECT_TRUE(bounds.render_timed);
  EXPECT_NEAR(bounds.render_efficiency, 1 / 1.05, 1e-12);
  EXPECT_NEAR(bounds.render_interval.lower, 1 / 1.09, 1e-12);
  EXPECT_NEAR(bounds.render_interval.upper, 1 / 1.02, 1e-12);
  EXPECT_FALSE(bounds.shown_cheaper());
  const json out = recommendation_json(r, m);
  EXPECT_EQ(out["uses"]["bounds"]["beats_mesh"], false);
  EXPECT_NE(out["uses"]["bounds"]["sentence"].get<std::string>().find("its render passes timed against exact's"), std::string::npos);
  EXPECT_EQ(out["proxies"][0]["bounds"]["render_timed"], true);
  EXPECT_EQ(out["proxies"][0]["control_variate"]["render_timed"], false);  // not timed: the share's model
  // The learned control variate, timed: its noise lies between exact's (where it traces the
  // mesh alone) and the optimal probabilities' (the point), and its interval reaches both.
  {
    json cv = m;
    cv["proxies"][0]["measure"]["render_time"]["control_variate"] = {{"pass_time_over_exact", 1.02}, {"range", {1.0, 1.04}}};
    const UseFigures f = recommend_proxies(cv, as_claimed()).proxies.at(0).uses[index_of(ProxyUse::control_variate)];
    EXPECT_TRUE(f.render_timed);
    EXPECT_LT(f.render_efficiency, 1 / 1.02);  // the proxy's noise, at the optimal probabilities
    EXPECT_NEAR(f.render_interval.upper, 1 / 1.0, 1e-12);  // exact's noise, the fastest round
    EXPECT_LT(f.render_interval.lower, f.render_efficiency);
  }
  // Where it traced every timed segment exactly, its noise is exact's: 1 / time.
  {
    json cv = m;
    cv["proxies"][0]["measure"]["render_time"]["control_variate"] = {
        {"pass_time_over_exact", 1.02}, {"range", {1.0, 1.04}}, {"warm_up_passes", 16}, {"traced_exactly_share", 1.0}};
    const UseFigures f = recommend_proxies(cv, as_claimed()).proxies.at(0).uses[index_of(ProxyUse::control_variate)];
    EXPECT_NEAR(f.render_efficiency, 1 / 1.02, 1e-12);
    EXPECT_NEAR(f.render_interval.lower, 1 / 1.04, 1e-12);
    EXPECT_NEAR(f.render_interval.upper, 1 / 1.0, 1e-12);
    // Half traced exactly: half the added noise.
    cv["proxies"][0]["measure"]["render_time"]["control_variate"]["traced_exactly_share"] = 0.5;
    const UseFigures half = recommend_proxies(cv, as_claimed()).proxies.at(0).uses[index_of(ProxyUse::control_variate)];
    const UseFigures none = recommend_proxies(m, as_claimed()).proxies.at(0).uses[index_of(ProxyUse::control_variate)];
    ASSERT_FALSE(none.render_timed);
    EXPECT_LT(half.render_efficiency, 1 / 1.02);
  }
  testing::expect_described(out, "recommendation.schema.json");
  // Faster passes: shipped.
  EXPECT_TRUE(recommend_proxies(manifest_with({{"pass_time_over_exact", 0.8}, {"range", {0.78, 0.83}}}), as_claimed())
                  .proxies.at(0).uses[index_of(ProxyUse::bounds)].shown_cheaper());
  // Edited so that the range leaves out the median.
  const UseFigures edited = recommend_proxies(manifest_with({{"pass_time_over_exact", 1.2}, {"range", {0.9, 1.0}}}), as_claimed())
                                .proxies.at(0).uses[index_of(ProxyUse::bounds)];
  EXPECT_NEAR(edited.render_interval.lower, 1 / 1.2, 1e-12);
  EXPECT_NEAR(edited.render_interval.upper, 1 / 0.9, 1e-12);
}
}  // namespace
}  // namespace visproxy
