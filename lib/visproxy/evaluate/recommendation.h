#pragma once
// Which proxy of a folder to ship, for each way a renderer can use one: the predicted
// efficiency against tracing the mesh (estimator/efficiency.h) of every measured proxy,
// with its 95 % interval, and the proxy chosen for each use, in one sentence per use.

#include <array>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "visproxy/core/proxy_kind.h"
#include "visproxy/estimator/efficiency.h"

namespace visproxy {

inline constexpr std::array<ProxyUse, 3> kProxyUses = {ProxyUse::control_variate, ProxyUse::term_choice,
                                                       ProxyUse::bounds};

struct UseFigures {
  UsePrediction prediction;  ///< at the use's most efficient setting (predict_use)
  Interval interval;         ///< 95 %, over the sampling of the measured rays
  /// Over a render of the scene the proxies were measured in: the use's cost and the
  /// render's noise with it (render_efficiency_of, from the manifest's render_share and the
  /// proxy's render_noise; manifests measured before the noise was: render_efficiency, which
  /// takes visibility for the render's only noise); NaN when measured on isotropic lines or
  /// before the share was. Eq. 8 is taken at the probabilities `render --probabilities
  /// optimal` finds (eq. 16's optimum over the render's segments), the other uses at
  /// `prediction`'s setting.
  double render_efficiency = std::numeric_limits<double>::quiet_NaN();
  /// `interval`'s ends carried to the render, with the noise ratio's own 95 % interval and
  /// the render share's range over its timed rounds.
  Interval render_interval;
  /// The render figure takes the render's own time with the use, timed against exact's
  /// (the proxy's render_time), in place of the share's model.
  bool render_timed = false;

  /// Whether the figures reach the render (measured on a scene). The choice of proxy and
  /// the advice weigh the render's figures then, the shadow ray's otherwise: a proxy that
  /// halves a shadow ray's cost gains nothing where shadow rays take no time.
  bool at_render() const { return !std::isnan(render_efficiency); }
  double decisive_efficiency() const { return at_render() ? render_efficiency : prediction.efficiency; }
  Interval decisive_interval() const { return at_render() ? render_interval : interval; }
  /// Usable, and predicted more efficient than the mesh with its whole interval above 1.
  bool shown_cheaper() const { return prediction.usable && decisive_efficiency() > 1 && decisive_interval().lower > 1; }
};

struct ProxyEfficiency {
  std::string name;
  double primitives = 0;
  /// The kind whose claim is proved for the files: the entry's kind when its verdict
  /// proves it, general otherwise (bounds then cannot use it).
  ProxyKind proved = ProxyKind::general;
  std::array<UseFigures, 3> uses;  ///< in the order of kProxyUses
};

struct UseChoice {
  ProxyUse use = ProxyUse::control_variate;
  /// Index into Recommendation::proxies of the proxy chosen, by the decisive figures (over
  /// the render when measured on a scene): of those shown cheaper than the mesh, the one
  /// whose interval's lower end is highest (or, among those its interval does
  /// not tell apart from it, the one with the fewest primitives); when none is shown
  /// cheaper, the most efficient usable one. -1 when none is usable (no proxy measured,
  /// costs not timed, no proved proxy for bounds).
  int best = -1;
  /// One sentence: "For shadow rays through the control variate, outer-512 is predicted
  /// 1.83x [1.61, 2.04] cheaper than the mesh at equal error." Cheaper only when the whole
  /// interval is above 1; "no proxy is predicted cheaper" when it is below 1; "as
  /// efficient as the mesh" when it holds 1. A runner-up whose interval reaches the best's
  /// is named.
  std::string sentence;
};

struct Recommendation {
  std::string rays;  ///< the rays it was predicted on, in words
  std::uint64_t seed = 0;
  /// The share of a sample's time that testing shadow rays against the mesh took in the
  /// scene measured (manifest render_share); NaN when there is none.
  double render_share = std::numeric_limits<double>::quiet_NaN();
  /// The least and greatest share over the timed rounds (render_share.share_range); the
  /// share itself when the manifest has no range. The render intervals span it.
  double render_share_low = std::numeric_limits<double>::quiet_NaN();
  double render_share_high = std::numeric_limits<double>::quiet_NaN();
  std::string render_scene;
  /// The exact render's variance of one camera sample within its pixel, its standard error
  /// and the camera samples it was found on (manifest render_share.noise); NaN when there
  /// is none (then the render prediction takes visibility for the render's only noise).
  double exact_variance = std::numeric_limits<double>::quiet_NaN();
  double exact_variance_error = 0;
  double noise_samples = 0;
  /// The same noise's segments from the mesh's own instances, by ray type (and squared).
  std::array<double, 4> own_noise{}, own_noise_squares{};
  std::array<std::uint64_t, 4> own_segments{};  ///< how many of those segments, by type
  std::vector<ProxyEfficiency> proxies;  ///< every measured proxy, in manifest order
  std::array<UseChoice, 3> choices;      ///< in the order of kProxyUses
};

/// How a sentence about a use begins: "For shadow rays through the control variate", "For
/// shadow rays through eq. 8", "For exact shadow rays through bounds".
std::string use_phrase(ProxyUse use);

/// "; over the render of SCENE, whose samples spend S % of their time testing shadow rays
/// against the mesh, Xx [A, B]": a use's render-level figures, or "" without a render share.
std::string render_phrase(const Recommendation& recommendation, const UseFigures& figures);

/// Decides the kind proved for a manifest entry (from its verify object and the files).
using ProvedKind = std::function<ProxyKind(const nlohmann::json& entry)>;

/// The recommendation from a measured manifest: each entry with a `measure` object (its
/// ray-type counts and costs per ray) is predicted for every use, its interval drawn with
/// the measurement's seed. Entries not measured are left out.
/// With `budget` above 0, a proxy of more primitives (triangles, boxes or spheres) is not
/// usable for any use ("over the budget of N primitives"), but keeps its row.
Recommendation recommend_proxies(const nlohmann::json& manifest, const ProvedKind& proved_kind, std::size_t budget = 0);

/// recommendation.json (data/schemas/recommendation.schema.json): the rays, the seed, one
/// object per use with the sentence and the chosen proxy, and every proxy's figures.
/// Unbounded efficiencies (a use with no variance where the mesh has some) are null.
nlohmann::json recommendation_json(const Recommendation& recommendation, const nlohmann::json& manifest);

}  // namespace visproxy
