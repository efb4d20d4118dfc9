#pragma once
// Lightcuts (Walter, Fernandez, Arbree, Bala, Donikian, Greenberg: "Lightcuts: a scalable
// approach to illumination", SIGGRAPH 2005): point lights in a binary tree of clusters; a
// shading point's cut, refined from the root until every cluster's error bound (material x
// geometric x visibility) is below a fraction of the cut's total, shades each cluster with
// its representative light, traced exactly. With visibility bounds (the
// lightcuts-visibility-bounds paper), clusters proved unoccluded or occluded by proxies
// (cluster_visibility.h) need no shadow ray and have tighter error bounds.

#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <vector>

#include "visproxy/render/world/cluster_visibility.h"
#include "visproxy/render/world/render_world.h"
#include "visproxy/render/options/render_options.h"
#include "visproxy/render/world/virtual_point_lights.h"
#include "visproxy/scene/scene.h"

namespace visproxy {

/// A point light of a cut: a point on an area light (a cosine emitter) or a virtual point
/// light. A shading point x (unit normal n) receives brdf x intensity x G x V, with
/// G = max(0, n . w) max(0, cos_l) / d^2 (w the unit direction to the light, cos_l = -normal . w,
/// its absolute value for two-sided lights), at most max_geometric.
struct PointLight {
  Vertex position;
  Vertex normal;       ///< unit
  Color intensity;     ///< area lights: radiance x area / K; VPLs: power x the surface's BRDF
  bool two_sided = false;
  bool on_light = false;  ///< a point on an area light (segments to it end on a light)
  double max_geometric = std::numeric_limits<double>::infinity();
  /// VPLs: the fixed end of every segment to it (moved off its surface); area-light points
  /// move their end off the light towards each shading point (segment_end).
  Vertex end = Vertex::Zero();
  /// How far the segments' end may lie from `position` (world units): the cluster boxes
  /// hold that much around each light.
  double end_offset = 0;
};

/// K points on each area light (stratified over its area: K strata of equal area along
/// its triangles, one point in each), each carrying radiance x area / K. Deterministic for a
/// seed.
std::vector<PointLight> area_light_points(const Scene& scene, const RenderWorld& world, int per_light, std::uint64_t seed);
/// The VPLs as point lights, their geometric term clamped to `max_geometric`.
std::vector<PointLight> vpl_point_lights(const RenderWorld& world, const std::vector<VirtualPointLight>& lights,
                                         double max_geometric);

/// The light tree: a binary tree over the lights, points on area lights apart from VPLs at
/// the first split, then split at the median of the longest axis of each node's box; each node holds its lights' box (grown by their end offsets), the
/// cone of their normals, their total intensity and two representative lights chosen by the
/// luminance-weighted centroid of its lights (deterministic; see `central`).
class LightTree {
 public:
  struct Node {
    BoundingBox box;
    Vertex axis = Vertex::Zero();  ///< of the normals' cone
    double cos_half = -1;          ///< cone half-angle's cosine; -1: no bound (two-sided lights among them)
    Color intensity = Color::Zero();
    std::uint32_t representative = 0;  ///< a light index: the one traced for the cluster
    std::uint32_t central = 0;         ///< the light nearest the cluster's centroid: shades it where visibility is proved
    std::int32_t left = -1, right = -1;  ///< children; -1 for a leaf (one light)
    std::uint32_t lights = 0;           ///< how many lights it holds
    bool on_lights = true;               ///< every light lies on an area light
    double max_geometric = 0;            ///< the largest clamp of its lights
    double min_geometric = 0;            ///< the smallest
  };
  explicit LightTree(std::vector<PointLight> lights);
  const std::vector<PointLight>& lights() const { return lights_; }
  const std::vector<Node>& nodes() const { return nodes_; }
  bool empty() const { return lights_.empty(); }
  static constexpr std::uint32_t root = 0;

 private:
  std::vector<PointLight> lights_;
  std::vector<Node> nodes_;
};

/// Bounds over a cluster of what its lights give a shading point, per unit intensity and
/// BRDF: lower <= max(0, n . w) G_l <= upper for every point of the node's box and every
/// normal of its cone (the cosines through the cones of directions from the point to the
/// box's bounding ball), clamps applied.
struct ClusterGeometry {
  double lower = 0, upper = 0;
};
ClusterGeometry cluster_geometry(const LightTree::Node& node, const Vertex& x, const Vertex& n);

/// What one light gives per unit intensity and BRDF: max(0, n . w) max(0, cos_l) / d^2, clamped.
double light_geometry(const PointLight& light, const Vertex& x, const Vertex& n);

struct CutResult {
  Color radiance = Color::Zero();  ///< reflected: brdf x sum over the cut
  int size = 0;                    ///< clusters in the final cut
  int shadow_rays = 0;
  int proved_unoccluded = 0, proved_occluded = 0;  ///< clusters proved (each time one entered the cut)
  int proofs_tried = 0;
  int disagreements = 0;  ///< check_proofs: proved clusters whose traced representative disagreed
  bool stopped_at_max_cut = false;  ///< refinement stopped by CutOptions::max_cut before the error bound was met
};

/// One thread's cut evaluator. `blocked(light, end)` traces the segment from the shading
/// point to the light's segment end exactly.
class CutEvaluator {
 public:
  CutEvaluator(const LightTree& tree, const ClusterProofs* proofs) : tree_(tree), proofs_(proofs ? std::make_optional<ClusterProofs::Point>(*proofs) : std::nullopt) {}
  /// x: the shading point (moved off the surface by `offset`), hit: the surface.
  CutResult evaluate(const Vertex& x, const SurfaceHit& hit, double offset, const Color& brdf, const CutOptions& options,
                     const std::function<bool(std::uint32_t light)>& blocked);

 private:
  struct Entry {
    std::uint32_t node = 0;
    Color estimate = Color::Zero();
    double error = 0;
    signed char visibility = -1;  ///< of the representative: 0, 1, or -1 not known
    bool proved_unoccluded = false;
    unsigned char lower_failures = 0;  ///< generations in a row whose lower bound proof failed
  };
  const LightTree& tree_;
  std::optional<ClusterProofs::Point> proofs_;
  std::vector<Entry> heap_;
};

}  // namespace visproxy
