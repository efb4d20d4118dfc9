#pragma once
// Proxies in your own renderer: load a proxy with its proof, add it to your Embree scene
// as conservative geometry, and estimate shadow-ray visibility with it through callables
// that trace your geometry.
//
//   const visproxy::RuntimeProxy proxy = visproxy::RuntimeProxy::load("bunny-proxies", "hull-32", "bunny.off");
//   const visproxy::PlacedProxy placed = proxy.place(bunny_to_world);
//   placed.attach(device, proxy_scene);                     // your RTCScene, your RTCDevice
//   visproxy::ShadowEstimator estimator(placed);
//   double v = estimator.eq8(x, y, u,
//       [&](const Vertex& a, const Vertex& b) { return occluded(proxy_scene, a, b); },
//       [&](const Vertex& a, const Vertex& b) { return occluded(mesh_scene, a, b); });
//
// apps/examples/embree_shadow.cpp is a whole program. Nothing here includes Embree: the
// scene and device are Embree's opaque handles, declared below exactly as rtcore declares them.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "visproxy/core/proxy_kind.h"
#include "visproxy/estimator/probabilities.h"
#include "visproxy/mesh/sphere_set.h"
#include "visproxy/mesh/triangle_mesh.h"

typedef struct RTCDeviceTy* RTCDevice;
typedef struct RTCSceneTy* RTCScene;

namespace visproxy {

struct RuntimeLoadOptions {
  /// Refuse (throw) a proxy whose outside or inside claim is not proved for this mesh and
  /// these files. Otherwise such a proxy is loaded as a general one (its estimator then
  /// needs all three terms) and `note()` says why.
  bool require_proof = true;
  /// When the manifest holds no verdict for these very files (none recorded, or the mesh
  /// or proxy changed since), verify the claim now (exactly, as `visproxy verify` does).
  /// false: such a claim counts as not proved.
  bool verify_now = true;
};

/// Where your renderer's single-precision coordinates come from.
struct Placement {
  /// World from mesh: the instance's transform, finite and invertible. Triangle proxies keep
  /// their claims under any such map (shear, uneven scale and mirrors included); sphere
  /// proxies need a similarity (rotation or reflection, translation, uniform scale).
  Eigen::Affine3d transform = Eigen::Affine3d::Identity();
  /// The world point your Embree coordinates are relative to (0 if you pass world
  /// coordinates as they are): vertices are handed over as world - origin.
  Vertex origin = Vertex::Zero();
  /// The largest |coordinate| (world - origin) of any ray end you trace against the
  /// proxy; the proxy's own is used when it is larger. Rounding bounds grow with it.
  double ray_magnitude = 0;
};

class PlacedProxy;

/// A proxy read back from a folder `visproxy build` wrote, with what is proved of it.
class RuntimeProxy {
 public:
  /// Reads proxy `name` (its manifest name: "hull-32", "inside-40", "spheres-100") from
  /// `folder`, and the mesh it was built from at `mesh_path` (read as the build read it and
  /// checked against the manifest). An outside or inside claim counts as proved when the
  /// manifest's verdict for it holds and was made on these very files (content hashes), or,
  /// with options.verify_now, when verifying it now holds. Throws InvalidInputError naming
  /// the file at fault: no such proxy, a file that does not hold what the manifest says, a
  /// mesh that is not the one it was built from, and (options.require_proof) a claim that
  /// is not proved, with the counterexample.
  static RuntimeProxy load(const std::filesystem::path& folder, std::string_view name,
                           const std::filesystem::path& mesh_path, const RuntimeLoadOptions& options = {});

  const std::string& name() const { return name_; }
  /// The claim as it may be used: the manifest's kind when proved, else general.
  ProxyKind kind() const { return kind_; }
  /// Why a claim is not used, or empty.
  const std::string& note() const { return note_; }
  bool spheres() const { return !spheres_.empty(); }
  /// The proxy in mesh coordinates: triangles, or spheres (then mesh() is empty).
  const TriangleMesh& mesh() const { return mesh_; }
  const std::vector<Sphere>& sphere_set() const { return spheres_; }
  /// The mesh the proxy stands in for (it is needed for the rounding proof of non-convex
  /// proxies and is what your renderer traces exactly).
  const TriangleMesh& source_mesh() const { return source_; }

  /// The proxy placed in your world, made conservative for single-precision rays (see PlacedProxy).
  PlacedProxy place(const Placement& placement = {}) const;

 private:
  std::string name_;
  ProxyKind kind_ = ProxyKind::general;
  std::string note_;
  TriangleMesh mesh_;
  std::vector<Sphere> spheres_;
  TriangleMesh source_;
};

/// A proxy in world space, ready for float ray tests: what its claim still promises after
/// Embree rounds vertices and rays to float.
///  - outside, convex (at most 16 384 triangles): scaled about its centroid so that every
///    point within the rounding bound of it stays inside;
///  - outside or inside, not convex: used as claimed only when its surface keeps twice the
///    rounding bound away from the mesh's (exact distance test), else as general;
///  - inside spheres: every radius shrunk by the rounding bound (balls smaller than it dropped);
///  - general: as it is.
/// The rounding bound is 2^-21 (8 float ulps) of the largest coordinate magnitude involved:
/// the proxy's world - origin and Placement::ray_magnitude.
class PlacedProxy {
 public:
  ProxyKind kind() const { return kind_; }
  const std::string& note() const { return note_; }
  /// The geometry handed to Embree, relative to the placement's origin, in float.
  const std::vector<float>& vertices() const { return vertices_; }        ///< x y z per vertex
  const std::vector<std::uint32_t>& indices() const { return indices_; }  ///< 3 per triangle
  const std::vector<float>& spheres() const { return spheres_; }          ///< x y z r per ball
  double rounding_bound() const { return pad_; }

  /// Adds the proxy to `scene` (created on `device`) as one committed geometry: a triangle
  /// mesh, or RTC_GEOMETRY_TYPE_SPHERE_POINT balls. Returns its geometry ID. The caller
  /// commits the scene. Throws visproxy::Error when Embree refuses.
  unsigned attach(RTCDevice device, RTCScene scene) const;

  /// Whether the claim speaks of the segment from `from` to `to` (world coordinates):
  /// no end may lie in the solid whose crossing the claim is about, the outside proxy's
  /// (a light inside a proxy, a shading point on the mesh itself) or, for an inside proxy,
  /// the mesh's. Tested conservatively (convex proxies by their planes, others by their
  /// boxes), padded by the rounding bound. false for general proxies.
  bool claim_covers(const Vertex& from, const Vertex& to) const;

 private:
  friend class RuntimeProxy;
  ProxyKind kind_ = ProxyKind::general;
  std::string note_;
  std::vector<float> vertices_;
  std::vector<std::uint32_t> indices_;
  std::vector<float> spheres_;
  double pad_ = 0;
  Vertex origin_ = Vertex::Zero();
  // The solid the claim is about, in world coordinates: planes (n, d) with n.x <= d, or a box.
  std::vector<Eigen::Vector4d> planes_;
  BoundingBox box_;
};

/// Evidence for the control variate's learned probabilities: one per pixel (or region) of
/// yours. A segment's probabilities depend only on earlier segments' corrections, which
/// keeps every estimate unbiased (Russian roulette with a probability fixed before the draw).
///
/// Given your renderer's costs (what a segment costs with the proxy query, a correction, and
/// with the exact query, each with its share of the camera ray and shading, in any one unit,
/// and your exact render's noise per segment: CorrectionCosts), it also weighs the control
/// variate's variance x cost against exact tracing's (learned_choice()), and
/// ShadowEstimator::control_variate traces your exact geometry alone where the proxy does
/// not pay. `prior`: what you know of the proxy before any evidence (its rates on segments
/// you traced both ways).
class LearnedCorrections {
 public:
  explicit LearnedCorrections(CorrectionOptions options = {}) : options_(options) {}
  LearnedCorrections(CorrectionOptions options, const CorrectionCosts& costs, const CorrectionPrior& prior = {})
      : options_(options), costs_(costs), prior_(prior) {}
  CorrectionProbabilities probabilities(ProxyKind kind) const {
    return costs_ ? choice(kind).q : correction_probabilities(kind, evidence_, options_);
  }
  /// With costs, the cost-aware choice; without, the cost-blind probabilities, never exact.
  LearnedChoice choice(ProxyKind kind) const {
    if (costs_) return learned_choice(kind, evidence_, *costs_, options_, prior_);
    LearnedChoice blind;
    blind.q = correction_probabilities(kind, evidence_, options_);
    return blind;
  }
  bool weighs_costs() const { return costs_.has_value(); }
  void record(bool proxy_blocked, bool mesh_blocked) { evidence_.add(proxy_blocked, mesh_blocked); }
  /// A segment the proxy answered (traced or not): the share of each answer.
  void answered(bool proxy_blocked) { evidence_.answer(proxy_blocked); }
  const CorrectionEvidence& evidence() const { return evidence_; }

 private:
  CorrectionOptions options_;
  CorrectionEvidence evidence_;
  std::optional<CorrectionCosts> costs_;
  CorrectionPrior prior_;
};

/// Stochastic visibility of shadow segments with a placed proxy (Billen et al. eq. 8, or
/// the proxy as a control variate). Each call takes two callables that you implement with
/// your own ray tracer, `bool blocked(const Vertex& from, const Vertex& to)`: one tests the
/// proxy (attached to your scene), one your exact geometry. Every estimate's mean is the
/// exact visibility V (1: unoccluded) for any u uniform in [0, 1): the proxy's zero
/// probabilities are used only where its claim covers the segment (claim_covers); else
/// the general form is used, which is unbiased for any proxy.
/// It keeps a reference to the PlacedProxy, which must outlive it.
class ShadowEstimator {
 public:
  /// `claimed`: eq. 8's probabilities for segments the claim covers (the kind's equal ones
  /// by default; `visproxy measure` reports the optimal ones); `general` for the others.
  explicit ShadowEstimator(const PlacedProxy& proxy, std::optional<Probabilities> claimed = std::nullopt,
                           Probabilities general = equal_probabilities(ProxyKind::general))
      : proxy_(proxy), claimed_(claimed.value_or(equal_probabilities(proxy.kind()))), general_(general) {}

  /// The kind whose form applies to a segment.
  ProxyKind form(const Vertex& from, const Vertex& to) const {
    return proxy_.claim_covers(from, to) ? proxy_.kind() : ProxyKind::general;
  }

  /// Eq. 8: u picks term (a) V'/p1, (b) (1 - V') V / p2 or (c) -V' (1 - V) / p3, where V'
  /// is the proxy's visibility and V the exact one. The mesh is traced only by (b) after
  /// the proxy blocked and (c) after it let the segment through.
  template <class ProxyBlocked, class MeshBlocked>
  double eq8(const Vertex& from, const Vertex& to, double u, ProxyBlocked&& proxy_blocked, MeshBlocked&& mesh_blocked) const {
    const Probabilities& p = form(from, to) == ProxyKind::general ? general_ : claimed_;
    const bool proxy_hit = proxy_blocked(from, to);
    if (u < p.p1) return proxy_hit ? 0.0 : 1.0 / p.p1;
    if (u < p.p1 + p.p2) return proxy_hit && !mesh_blocked(from, to) ? 1.0 / p.p2 : 0.0;
    return !proxy_hit && mesh_blocked(from, to) ? -1.0 / p.p3 : 0.0;
  }

  /// The control variate: V' + (V - V') [u < q] / q, with q chosen by the proxy's answer
  /// from `learned` (which then records the correction when one was traced). When `learned`
  /// weighs costs and says the proxy does not pay, the exact answer: your exact geometry
  /// alone, or, while the evidence is short (fewer than 16 answers) and the proxy could pay,
  /// for u < 1/8 both, to keep learning.
  template <class ProxyBlocked, class MeshBlocked>
  double control_variate(const Vertex& from, const Vertex& to, double u, LearnedCorrections& learned,
                         ProxyBlocked&& proxy_blocked, MeshBlocked&& mesh_blocked) const {
    const LearnedChoice choice = learned.choice(form(from, to));
    const CorrectionProbabilities& q = choice.q;
    if (choice.trace_exactly) {
      if (!(learned_keeps_exploring(choice.can_pay, learned.evidence()) && u * kLearnedExploreOneIn < 1))
        return mesh_blocked(from, to) ? 0.0 : 1.0;
      const bool proxy_hit = proxy_blocked(from, to), mesh_hit = mesh_blocked(from, to);
      learned.answered(proxy_hit);
      learned.record(proxy_hit, mesh_hit);
      return mesh_hit ? 0.0 : 1.0;
    }
    const bool proxy_hit = proxy_blocked(from, to);
    if (learned.weighs_costs()) learned.answered(proxy_hit);
    const double v_proxy = proxy_hit ? 0.0 : 1.0;
    const double chance = proxy_hit ? q.after_hit : q.after_miss;
    if (!(u < chance)) return v_proxy;
    const bool mesh_hit = mesh_blocked(from, to);
    learned.record(proxy_hit, mesh_hit);
    return v_proxy + ((mesh_hit ? 0.0 : 1.0) - v_proxy) / chance;
  }

 private:
  const PlacedProxy& proxy_;
  Probabilities claimed_, general_;
};

}  // namespace visproxy
