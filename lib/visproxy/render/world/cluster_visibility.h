#pragma once
// Proofs about every segment from a shading point to a box of point lights at once, for
// lightcuts' visibility bounds (the lightcuts-visibility-bounds paper, whose occlusion test
// is sampled, made proofs here):
//  - unoccluded: the shaft, the convex hull of the point and the box, is separated by a
//    plane from everything that could block it (each other instance's outside proxy, the
//    own instance's triangles), so no segment in it is blocked;
//  - occluded: every such segment enters an inside proxy (an inscribed ball, or crosses a
//    triangle of an inner mesh) of an instance whose solid holds the segment's light end
//    outside it, so every segment crosses that instance's mesh.
// Every separation and crossing is required by a margin of the instance's float rounding
// bound (InstanceSolids::pad), so that Embree's float rays agree with the proof.

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "visproxy/mesh/sphere_set.h"
#include "visproxy/mesh/triangle_mesh.h"
#include "visproxy/render/world/render_world.h"

namespace visproxy {

/// The convex hull of an apex and a box, as supporting planes n . p <= d of all nine points:
/// the three coordinate axes both ways, and the planes through the apex and each edge of the
/// box that are faces of the hull. Any plane with every point behind it separates the hull
/// from what lies beyond it.
class Shaft {
 public:
  Shaft(const Vertex& apex, const BoundingBox& box);
  const Vertex& apex() const { return points_[0]; }
  const std::array<Vertex, 9>& points() const { return points_; }

  /// Whether `box` lies beyond one of the shaft's planes by more than `margin`.
  bool separated_from(const BoundingBox& box, double margin) const;
  /// Whether triangle abc is separated from the shaft by more than `margin`: beyond one of
  /// the shaft's planes, or with every point of the shaft beyond the triangle's own plane
  /// (the apex by more than `apex_margin`, the box corners by more than `margin`).
  bool separated_from(const Vertex& a, const Vertex& b, const Vertex& c, double margin, double apex_margin) const;
  /// Whether the ball lies beyond one of the shaft's planes by more than `margin`.
  bool separated_from(const Sphere& ball, double margin) const;

 private:
  std::array<Vertex, 9> points_;
  // Unit normal, offset: n . p <= offset for the nine points. At most 6 axis planes and 6
  // silhouette edges (a box seen from outside has at most 6).
  std::array<std::pair<Vertex, double>, 18> planes_;
  int plane_count_ = 0;
};

/// Whether every segment from `apex` to a point of `box` enters the ball shrunk by `margin`.
/// With t = |c - x| and r' = r - margin < t, the tangent cone from x has half-angle gamma,
/// cos gamma = sqrt(t^2 - r'^2) / t; a ray at angle delta < gamma from the axis enters the
/// ball at distance t cos delta - sqrt(r'^2 - t^2 sin^2 delta), which grows with delta up to
/// the tangent length L = sqrt(t^2 - r'^2). So the box must lie inside the cone (its corners
/// suffice: the cone is convex) and at least L + margin from x.
bool ball_blocks_box(const Vertex& apex, const Sphere& ball, const BoundingBox& box, double margin);

/// The k-th corner of a box (bit 0: x at max, bit 1: y, bit 2: z).
Vertex box_corner(const BoundingBox& box, int k);

/// A triangle as seen from an apex, for triangle_blocks_box on many boxes: its plane
/// (normal towards the apex, the apex's height above it) and the three planes through the
/// apex and an edge (normals inwards). Not valid when the apex lies in the triangle's plane
/// or the triangle is degenerate.
struct TriangleCone {
  TriangleCone() = default;
  TriangleCone(const Vertex& from, const Vertex& a, const Vertex& b, const Vertex& c);
  bool blocks(const BoundingBox& box, double margin) const;
  Vertex apex = Vertex::Zero(), corner = Vertex::Zero(), normal = Vertex::Zero();
  double apex_height = 0;
  std::array<Vertex, 3> sides{};
  bool valid = false;
};

/// Whether every segment from `apex` to a point of `box` crosses triangle abc at a point at
/// least `margin` inside it: the apex strictly on one side of its plane, every corner beyond
/// it by more than `margin`, and every corner inside the three planes through the apex and
/// an edge, so that the crossing point lies more than `margin` from each edge's plane.
bool triangle_blocks_box(const Vertex& apex, const Vertex& a, const Vertex& b, const Vertex& c, const BoundingBox& box,
                         double margin);

/// A bounding-volume hierarchy over world-space triangles (double precision), for shaft
/// queries.
class TriangleTree {
 public:
  TriangleTree() = default;
  explicit TriangleTree(const TriangleMesh& mesh);
  bool empty() const { return nodes_.empty(); }
  /// Whether every triangle is separated from the shaft (Shaft::separated_from).
  bool shaft_misses(const Shaft& shaft, double margin, double apex_margin) const;

 private:
  struct Node {
    BoundingBox box;
    std::uint32_t first = 0, count = 0;  // leaf: triangles [first, first + count); else count 0, children first, first + 1
  };
  std::vector<Node> nodes_;
  std::vector<std::array<Vertex, 3>> triangles_;
};

/// Counts of what the proofs did, summed over threads.
struct ClusterProofCounts {
  std::uint64_t unoccluded_tried = 0, unoccluded = 0, occluded_tried = 0, occluded = 0;
};

/// The scene's geometry for cluster proofs (a world made with keep_solids), shared by
/// every thread; begin() a Point per shading point.
class ClusterProofs {
 public:
  explicit ClusterProofs(const RenderWorld& world, std::size_t instances);

  /// One thread's proofs from one shading point.
  class Point {
   public:
    explicit Point(const ClusterProofs& proofs) : proofs_(&proofs) {}
    /// `x` is the shading point (moved off the surface by `offset`), `hit` the surface,
    /// `lights` a box holding every light the cuts may reach and `on_lights` one holding
    /// every light on an area light (empty if none), which cull instances and occluders once.
    void begin(const Vertex& x, const SurfaceHit& hit, double offset, const BoundingBox& lights, const BoundingBox& on_lights);
    /// Every segment from the point to `box` is unblocked. `on_lights`: every light of the
    /// cluster lies on an area light (which RenderWorld checked to lie outside the traced
    /// outside proxies' solids).
    bool unoccluded(const BoundingBox& box, bool on_lights);
    /// Every segment from the point to `box` is blocked; only for clusters on lights.
    bool occluded(const BoundingBox& box, bool on_lights);

   private:
    bool instance_clear(std::size_t instance, const Shaft& shaft, bool on_lights) const;
    void prepare_lower();
    void prepare_upper();
    BoundingBox lights_, on_lights_;
    bool lower_ready_ = false, upper_ready_ = false;
    const ClusterProofs* proofs_;
    Vertex x_ = Vertex::Zero();
    const SurfaceHit* hit_ = nullptr;
    double apex_margin_ = 0;
    unsigned x_shells_ = 0;
    std::vector<std::size_t> near_;              // instances the shaft to every light may meet
    std::vector<bool> x_outside_;                // per near instance: x outside its convex outside solid
    std::vector<std::pair<Sphere, double>> balls_;  // candidate balls with their instance's pad, largest first
    struct Face {
      TriangleCone cone;
      double pad;
      double size;  // area over squared distance from the point
    };
    std::vector<Face> faces_;
    int last_ball_ = -1, last_face_ = -1, last_blocker_ = -1;
  };

 private:
  const RenderWorld* world_;
  std::size_t instances_ = 0;
  std::vector<TriangleTree> mesh_trees_, outside_trees_;  // per instance (outside: empty when it is the mesh)
};

}  // namespace visproxy
