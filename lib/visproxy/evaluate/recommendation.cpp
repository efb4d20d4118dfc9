#include "visproxy/evaluate/recommendation.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <tuple>
#include <utility>

#include "visproxy/evaluate/measure_proxies.h"

namespace visproxy {
namespace {

using nlohmann::json;

std::string ratio_text(double value) {
  if (std::isinf(value)) return "unbounded";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%#.3g", value);
  return buffer;
}

std::string figures_text(const UseFigures& u) {
  return ratio_text(u.prediction.efficiency) + "x [" + ratio_text(u.interval.lower) + ", " +
         ratio_text(u.interval.upper) + "]";
}

json number_or_null(double value) { return std::isfinite(value) ? json(value) : json(nullptr); }

std::string rays_text(const json& rays) {
  const std::string kind = rays.value("kind", std::string());
  const std::string count = std::to_string(rays.value("count", 0));
  if (kind == "scene shadow segments")
    return count + " shadow rays of the scene " + rays.value("scene", std::string("?"));
  return count + " isotropic lines through the mesh's bounding sphere";
}

}  // namespace

std::string render_phrase(const Recommendation& r, const UseFigures& figures) {
  if (!std::isfinite(r.render_share) || std::isnan(figures.render_efficiency)) return "";
  char share[64];
  if (r.render_share_high > r.render_share_low)
    std::snprintf(share, sizeof share, "%.1f %% (%.1f-%.1f %% over the timed rounds)", 100 * r.render_share,
                  100 * r.render_share_low, 100 * r.render_share_high);
  else
    std::snprintf(share, sizeof share, "%.1f %%", 100 * r.render_share);
  return "; over the render of " + r.render_scene + ", whose samples spend " + share +
         " of their time testing shadow rays against the mesh, " + ratio_text(figures.render_efficiency) + "x [" +
         ratio_text(figures.render_interval.lower) + ", " + ratio_text(figures.render_interval.upper) + "]" +
         (figures.render_timed ? " (its render passes timed against exact's)" : "");
}

namespace {

std::string choice_sentence(const Recommendation& r, std::size_t u, int best, int next) {
  const ProxyUse use = kProxyUses[u];
  std::string text = use_phrase(use);
  if (best < 0) {
    if (r.proxies.empty()) return text + ", no proxy has been measured yet (visproxy measure).";
    const std::string why = r.proxies.front().uses[u].prediction.why_not;
    if (use == ProxyUse::bounds && why.find("proved") != std::string::npos)
      return text +
             ", no proxy is usable: bounds need an outside or inside proxy whose claim visproxy verify proved for "
             "these files.";
    return text + ", no proxy is usable: " + why + ".";
  }
  const ProxyEfficiency& p = r.proxies[static_cast<std::size_t>(best)];
  const UseFigures& figures = p.uses[u];
  const double point = figures.decisive_efficiency();
  const Interval interval = figures.decisive_interval();
  if (!figures.at_render()) {
    if (figures.shown_cheaper()) {
      text += ", " + p.name + " is predicted " + figures_text(figures) + " cheaper than the mesh at equal error";
    } else if (point < 1 && interval.upper < 1) {
      text += ", no proxy is predicted cheaper than the mesh: the best, " + p.name + ", is " + figures_text(figures) +
              " as efficient; trace the mesh";
    } else {
      text += ", the best, " + p.name + ", is predicted " + figures_text(figures) +
              " as efficient as the mesh: the interval holds 1, so no gain is shown; trace the mesh";
    }
  } else {
    // Over the render: the shadow ray's figure, then the render's, which decides.
    text += ", " + (figures.shown_cheaper() ? p.name : "the best, " + p.name + ",") + " is predicted " + figures_text(figures) +
            " as efficient as the mesh per shadow ray" + render_phrase(r, figures);
    if (figures.shown_cheaper())
      text += ": cheaper than the mesh over the render at equal error";
    else if (point < 1 && interval.upper < 1)
      text += ": no proxy is predicted to gain over the render; trace the mesh";
    else
      text += ": the interval holds 1, so no gain over the render is shown; trace the mesh";
  }
  if (next >= 0) {
    const ProxyEfficiency& runner = r.proxies[static_cast<std::size_t>(next)];
    const UseFigures& other = runner.uses[u];
    const Interval theirs = other.decisive_interval();
    if (theirs.upper >= interval.lower && interval.upper >= theirs.lower)
      text += " (" + runner.name + ", at " +
              (other.at_render() ? ratio_text(other.render_efficiency) + "x [" + ratio_text(theirs.lower) + ", " +
                                       ratio_text(theirs.upper) + "] over the render"
                                 : figures_text(other)) +
              ", is not told apart from it by the intervals" + (runner.primitives > p.primitives ? " and has more primitives" : "") + ")";
  }
  return text + ".";
}

}  // namespace

std::string use_phrase(ProxyUse use) {
  switch (use) {
    case ProxyUse::control_variate:
      return "For shadow rays through the control variate";
    case ProxyUse::term_choice:
      return "For shadow rays through eq. 8";
    case ProxyUse::bounds:
      return "For exact shadow rays through bounds";
  }
  return "?";
}

namespace {

// The render's variance ratio with a use (render_variance_ratio) and its 95 % interval over
// the sampling of the camera samples: the added noise's and the exact variance's standard
// errors, combined to first order (their covariance left out).
struct RenderNoiseRatio {
  double ratio = 1, low = 1, high = 1;
};

RenderNoiseRatio render_noise_ratio(const json& noise, ProxyUse use, const UseSetting& setting, const UseSetting& own_setting,
                                    const Recommendation& r) {
  const json& by_type = noise.at("squared_contribution_by_type");
  const json& squares_by_type = noise.at("squared_contribution_squares_by_type");
  const std::array<double, 4> added = added_variance_by_type(use, setting), own_added = added_variance_by_type(use, own_setting);
  double mean = 0, second = 0;  // of one camera sample's added variance
  bool unbounded = false;
  auto add = [&](double weighted, double squares, double g) {
    if (!(weighted > 0)) return;
    if (std::isinf(g)) unbounded = true;
    mean += weighted * g, second += squares * g * g;
  };
  for (std::size_t t = 0; t < 4; ++t) {
    add(by_type.at(t).get<double>(), squares_by_type.at(t).get<double>(), added[t]);
    add(r.own_noise[t], r.own_noise_squares[t], own_added[t]);
  }
  RenderNoiseRatio result;
  const double v = r.exact_variance;
  if (unbounded || (mean > 0 && !(v > 0))) {
    result.ratio = result.low = result.high = std::numeric_limits<double>::infinity();
    return result;
  }
  if (!(mean > 0)) return result;
  result.ratio = 1 + mean / v;
  // The two samples of a pair share a pixel: the pairs are the independent draws.
  const double n = std::max(r.noise_samples / 2, 1.0);
  const double added_error = std::sqrt(std::max(0.0, second - mean * mean) / n);
  const double error = std::hypot(added_error / v, mean * r.exact_variance_error / (v * v));
  result.low = std::max(1.0, result.ratio - 1.96 * error);
  result.high = result.ratio + 1.96 * error;
  return result;
}

// The probabilities `render --probabilities optimal` gives eq. 8: eq. 16's optimum over the
// render's own segments, one set per form of the rest of the scene. The segments from the
// mesh's instances share the proxy's set when their rest of the scene has the proxy's form
// (other instances of the mesh, or an outside proxy, whose form an exact rest shares);
// otherwise theirs is the optimum of their own segments (which agree: p1 = 1).
std::pair<Probabilities, Probabilities> render_optimal_probabilities(const json& noise, ProxyKind kind, std::size_t mesh_instances,
                                                                     const Recommendation& r) {
  RayTypeCounts others, own;
  for (std::size_t t = 0; t < 4; ++t) {
    others.counts[t] = noise.at("segments_by_type").at(t).get<std::uint64_t>();
    own.counts[t] = r.own_segments[t];
  }
  const OptimalProbabilityOptions options{.floor = UseOptions{}.floor};
  if (mesh_instances > 1 || kind == ProxyKind::outside) {
    RayTypeCounts mixed = others;
    for (std::size_t t = 0; t < 4; ++t) mixed.counts[t] += own.counts[t];
    const Probabilities p = optimal_probabilities(kind, RayTypeFractions::from(mixed), options);
    return {p, p};
  }
  return {optimal_probabilities(kind, RayTypeFractions::from(others), options),
          optimal_probabilities(ProxyKind::outside, RayTypeFractions::from(own), options)};
}

}  // namespace

Recommendation recommend_proxies(const json& manifest, const ProvedKind& proved_kind, std::size_t budget) {
  Recommendation r;
  if (const auto share = manifest.find("render_share"); share != manifest.end() && share->is_object()) {
    r.render_share = share->value("share", std::numeric_limits<double>::quiet_NaN());
    r.render_share_low = r.render_share_high = r.render_share;
    if (const auto range = share->find("share_range"); range != share->end() && range->is_array() && range->size() == 2) {
      r.render_share_low = std::min(r.render_share, range->at(0).get<double>());
      r.render_share_high = std::max(r.render_share, range->at(1).get<double>());
    }
    r.render_scene = share->value("scene", std::string());
    if (const auto noise = share->find("noise"); noise != share->end() && noise->is_object()) {
      r.exact_variance = noise->value("exact_variance_per_sample", std::numeric_limits<double>::quiet_NaN());
      r.exact_variance_error = noise->value("standard_error", 0.0);
      r.noise_samples = noise->value("camera_samples", 0.0);
      for (std::size_t t = 0; t < 4; ++t) {
        r.own_noise[t] = noise->at("own_instances_squared_contribution_by_type").at(t).get<double>();
        r.own_noise_squares[t] = noise->at("own_instances_squared_contribution_squares_by_type").at(t).get<double>();
        r.own_segments[t] = noise->at("own_instances_segments_by_type").at(t).get<std::uint64_t>();
      }
    }
  }
  for (const json& entry : manifest.at("proxies")) {
    if (!entry.contains("measure") || !entry["measure"].is_object()) continue;
    const json& measured = entry["measure"];
    if (r.proxies.empty() && measured.contains("rays")) {
      r.rays = rays_text(measured["rays"]);
      r.seed = measured["rays"].value("seed", std::uint64_t{0});
    }
    ProxyEfficiency p;
    p.name = entry.value("name", std::string("?"));
    p.primitives = entry.value("primitives", 0.0);
    p.proved = proved_kind(entry);
    RayTypeCounts counts;
    const json& c = measured.at("counts");
    for (std::size_t i = 0; i < 4; ++i) counts.counts[i] = c.at(i).get<std::uint64_t>();
    const json& cost = measured.at("cost_ns_per_ray");
    TraceCosts costs{cost.value("proxy", 0.0), cost.value("mesh", 0.0)};
    // The interval of the proxy's cost relative to the mesh's: the run's cost model with
    // its error, or the blocks' spread (manifests measured before either had none: the
    // cost as measured).
    if (const auto interval = cost_ratio_interval(measured)) {
      costs.proxy_ns_low = (*interval)[0] * costs.mesh_ns;
      costs.proxy_ns_high = (*interval)[1] * costs.mesh_ns;
    }
    const RayTypeFractions fractions = RayTypeFractions::from(counts);
    for (std::size_t u = 0; u < kProxyUses.size(); ++u) {
      UseFigures& figures = p.uses[u];
      figures.prediction = predict_use(kProxyUses[u], p.proved, fractions, costs);
      if (budget > 0 && p.primitives > static_cast<double>(budget)) {
        figures.prediction.usable = false, figures.prediction.efficiency = 0;
        figures.prediction.why_not = "over the budget of " + std::to_string(budget) + " primitives";
      }
      if (figures.prediction.usable) {
        figures.interval = efficiency_interval(kProxyUses[u], p.proved, counts, costs, figures.prediction.setting,
                                               r.seed + 0x9E3779B97F4A7C15ull * (r.proxies.size() * 3 + u + 1));
        if (std::isfinite(r.render_share)) {
          // The render efficiency is monotone in the share: its interval spans the ends of
          // the share's range.
          auto over_shares = [&](auto&& at) {
            const Interval a = at(r.render_share_low), b = at(r.render_share_high);
            return Interval{std::min(a.lower, b.lower), std::max(a.upper, b.upper)};
          };
          // The variance ratio at the prediction's point carries the interval's ends too.
          const double mesh_variance = fractions.v_avg() * (1 - fractions.v_avg());
          const double ratio = mesh_variance > 0 ? figures.prediction.variance / mesh_variance
                               : figures.prediction.variance > 0 ? std::numeric_limits<double>::infinity()
                                                                 : 1.0;
          const auto noise = measured.find("render_noise");
          if (std::isfinite(r.exact_variance) && noise != measured.end() && noise->is_object()) {
            // The render's own noise: what the use adds to the segments it changes, over
            // the exact render's variance (efficiency.h, render_variance_ratio).
            UseSetting setting = figures.prediction.setting, own_setting = setting;
            const double ray_cost_ratio = figures.prediction.ns_per_ray / costs.mesh_ns;
            double cost_ratio = ray_cost_ratio;
            if (kProxyUses[u] == ProxyUse::term_choice) {
              // Over the render, eq. 8 at the probabilities the renderer's optimal mode finds.
              const std::size_t instances = measured.contains("rays") ? measured["rays"].value("instances_of_mesh", std::size_t{1}) : 1;
              std::tie(setting.term, own_setting.term) = render_optimal_probabilities(*noise, p.proved, instances, r);
              cost_ratio = predict_use_at(ProxyUse::term_choice, p.proved, fractions, costs, setting).ns_per_ray / costs.mesh_ns;
            }
            const RenderNoiseRatio render = render_noise_ratio(*noise, kProxyUses[u], setting, own_setting, r);
            // The cost ratio at the ray interval's ends (efficiency = 1 / (ray variance ratio x
            // cost ratio)), scaled as the render's setting scales the prediction's cost.
            auto cost_at = [&](double efficiency) {
              const double at_end = efficiency > 0 && ratio > 0 && std::isfinite(ratio) ? 1 / (efficiency * ratio) : ray_cost_ratio;
              return ray_cost_ratio > 0 ? at_end * cost_ratio / ray_cost_ratio : cost_ratio;
            };
            const json* timed = nullptr;
            if (const auto times = measured.find("render_time"); times != measured.end() && times->is_object())
              if (const auto t = times->find(std::string(use_key(kProxyUses[u]))); t != times->end() && t->is_object())
                timed = &*t;
            if (timed) {
              // The render's own time with the use, timed in turns with exact's: it holds
              // what the renderer spends beyond the shadow rays' cost, which the share's
              // model leaves out. The interval spans the rounds' range.
              const double time = timed->at("pass_time_over_exact").get<double>();
              const double low = std::min(time, timed->at("range").at(0).get<double>());
              const double high = std::max(time, timed->at("range").at(1).get<double>());
              // The learned control variate traces the mesh alone wherever its proxy does not
              // pay: it adds the optimal probabilities' noise on the segments it estimates
              // only (1 - the share it traced exactly in its timed passes); without that
              // share, its noise lies between exact's and the optimal probabilities'.
              RenderNoiseRatio with_use = render;
              if (kProxyUses[u] == ProxyUse::control_variate) {
                const double exactly = timed->value("traced_exactly_share", std::nan(""));
                const double estimated = std::isfinite(exactly) ? 1 - std::clamp(exactly, 0.0, 1.0) : 1.0;
                auto scaled = [&](double added) { return std::isinf(added) && estimated == 0 ? 1.0 : 1 + estimated * (added - 1); };
                with_use = {scaled(render.ratio), std::isfinite(exactly) ? scaled(render.low) : 1.0, scaled(render.high)};
              }
              figures.render_efficiency = render_efficiency_timed(time, with_use.ratio);
              figures.render_timed = true;
              figures.render_interval = {render_efficiency_timed(high, with_use.high), render_efficiency_timed(low, with_use.low)};
            } else {
              figures.render_efficiency = render_efficiency_of(cost_ratio, render.ratio, r.render_share);
              figures.render_interval = over_shares([&](double share) {
                return Interval{render_efficiency_of(cost_at(figures.interval.lower), render.high, share),
                                render_efficiency_of(cost_at(figures.interval.upper), render.low, share)};
              });
            }
          } else {
            figures.render_efficiency = render_efficiency(figures.prediction.efficiency, ratio, r.render_share);
            figures.render_interval = over_shares([&](double share) {
              return Interval{render_efficiency(figures.interval.lower, ratio, share),
                              render_efficiency(figures.interval.upper, ratio, share)};
            });
          }
        }
      }
    }
    r.proxies.push_back(std::move(p));
  }
  for (std::size_t u = 0; u < kProxyUses.size(); ++u) {
    // Of the proxies shown cheaper than the mesh (interval above 1), the one whose interval
    // reaches highest at its lower end: the gain it guarantees, which the timing's noise
    // moves least. Then, of the proxies also shown cheaper whose intervals reach its
    // interval (not told apart from it), the one with the fewest primitives: a choice
    // that noise cannot flip between proxies the intervals do not separate. When no proxy
    // is shown cheaper, the advice is to trace the mesh, and the most efficient is named.
    auto shown_cheaper = [&](std::size_t i) { return r.proxies[i].uses[u].shown_cheaper(); };
    auto lower = [&](std::size_t i) { return r.proxies[i].uses[u].decisive_interval().lower; };
    auto upper = [&](std::size_t i) { return r.proxies[i].uses[u].decisive_interval().upper; };
    auto point = [&](std::size_t i) { return r.proxies[i].uses[u].decisive_efficiency(); };
    auto usable = [&](std::size_t i) { return r.proxies[i].uses[u].prediction.usable; };
    int top = -1;
    for (std::size_t i = 0; i < r.proxies.size(); ++i)
      if (shown_cheaper(i) && (top < 0 || lower(i) > lower(static_cast<std::size_t>(top)))) top = static_cast<int>(i);
    if (top < 0)
      for (std::size_t i = 0; i < r.proxies.size(); ++i)
        if (usable(i) && (top < 0 || point(i) > point(static_cast<std::size_t>(top)))) top = static_cast<int>(i);
    int best = top, next = -1;
    if (top >= 0) {
      const double reach = lower(static_cast<std::size_t>(top));
      for (std::size_t i = 0; i < r.proxies.size() && shown_cheaper(static_cast<std::size_t>(top)); ++i) {
        if (!shown_cheaper(i) || upper(i) < reach) continue;
        if (r.proxies[i].primitives < r.proxies[static_cast<std::size_t>(best)].primitives) best = static_cast<int>(i);
      }
      // The runner-up: the most efficient other proxy.
      for (std::size_t i = 0; i < r.proxies.size(); ++i) {
        if (static_cast<int>(i) == best || !usable(i)) continue;
        if (next < 0 || point(i) > point(static_cast<std::size_t>(next))) next = static_cast<int>(i);
      }
    }
    r.choices[u] = {kProxyUses[u], best, choice_sentence(r, u, best, next)};
  }
  return r;
}

json recommendation_json(const Recommendation& r, const json& manifest) {
  json uses = json::object();
  for (const UseChoice& choice : r.choices) {
    json object = {{"sentence", choice.sentence}, {"proxy", nullptr}, {"efficiency", nullptr}, {"interval", nullptr}};
    if (choice.best >= 0) {
      const std::size_t u = static_cast<std::size_t>(&choice - r.choices.data());
      const ProxyEfficiency& p = r.proxies[static_cast<std::size_t>(choice.best)];
      object["proxy"] = p.name;
      object["efficiency"] = number_or_null(p.uses[u].prediction.efficiency);
      object["interval"] = {number_or_null(p.uses[u].interval.lower), number_or_null(p.uses[u].interval.upper)};
      object["beats_mesh"] = p.uses[u].shown_cheaper();
      if (!std::isnan(p.uses[u].render_efficiency)) {
        object["render_efficiency"] = number_or_null(p.uses[u].render_efficiency);
        object["render_interval"] = {number_or_null(p.uses[u].render_interval.lower),
                                     number_or_null(p.uses[u].render_interval.upper)};
      }
    }
    uses[std::string(use_key(choice.use))] = object;
  }
  json proxies = json::array();
  for (const ProxyEfficiency& p : r.proxies) {
    json entry = {{"name", p.name}, {"primitives", p.primitives}, {"proved_kind", kind_name(p.proved)}};
    for (std::size_t u = 0; u < kProxyUses.size(); ++u) {
      const UseFigures& f = p.uses[u];
      json figures = {{"usable", f.prediction.usable}};
      if (!f.prediction.usable) {
        figures["why_not"] = f.prediction.why_not;
      } else {
        figures["efficiency"] = number_or_null(f.prediction.efficiency);
        figures["interval"] = {number_or_null(f.interval.lower), number_or_null(f.interval.upper)};
        figures["variance"] = f.prediction.variance;
        figures["ns_per_ray"] = f.prediction.ns_per_ray;
        if (!std::isnan(f.render_efficiency)) {
          figures["render_efficiency"] = number_or_null(f.render_efficiency);
          figures["render_interval"] = {number_or_null(f.render_interval.lower), number_or_null(f.render_interval.upper)};
          figures["render_timed"] = f.render_timed;
        }
        if (kProxyUses[u] == ProxyUse::control_variate)
          figures["setting"] = {{"after_miss", f.prediction.setting.correction.after_miss},
                                {"after_hit", f.prediction.setting.correction.after_hit}};
        else if (kProxyUses[u] == ProxyUse::term_choice)
          figures["setting"] = {{"p1", f.prediction.setting.term.p1},
                                {"p2", f.prediction.setting.term.p2},
                                {"p3", f.prediction.setting.term.p3}};
      }
      entry[std::string(use_key(kProxyUses[u]))] = figures;
    }
    proxies.push_back(entry);
  }
  return {
      {"format", "visproxy-recommendation"},
      {"format_version", 1},
      {"mesh", manifest.at("mesh").value("path", std::string())},
      {"rays", r.rays},
      {"seed", r.seed},
      {"efficiency",
       "(Var(V) c_mesh) / (Var c): how many times cheaper than tracing the mesh alone at equal error, with Var(V) = "
       "V_avg (1 - V_avg) and c the measured nanoseconds per ray on one core; intervals are 95 % over the sampling "
       "of the measured rays, widened by the spread of the proxy's cost over the timing blocks"},
      {"render_share", std::isfinite(r.render_share) ? json{{"share", r.render_share},
                                                             {"share_range", {r.render_share_low, r.render_share_high}},
                                                             {"scene", r.render_scene}}
                                                      : json(nullptr)},
      {"uses", uses},
      {"proxies", proxies}};
}

}  // namespace visproxy
