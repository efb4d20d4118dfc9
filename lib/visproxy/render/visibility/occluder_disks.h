#pragma once
// Occluder disks (occluding-spheres paper §2): from a shading point x, a ball (O, R) at
// distance t = |O - x| hides the cone of directions within gamma of O - x, cos gamma =
// sqrt(t^2 - R^2) / t; a segment to y at distance z is occluded when the angle delta
// between y - x and O - x has cos delta > cos gamma, and t < z. Per shading point each
// ball costs one direction and one cosine; each segment then costs a dot product and two
// comparisons per ball.

#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <span>
#include <vector>

#include "visproxy/render/world/box_tree.h"
#include "visproxy/render/world/render_world.h"
#include "visproxy/render/options/render_stats.h"
#include "visproxy/render/visibility/visibility.h"

namespace visproxy {

/// A run of disks [begin, begin + count), then padding, with the cone of a bound that
/// holds their balls (cos < -1: every direction, for no bound or a point inside it), as
/// OccluderDisks keeps them. A group with span > 0 has no disks of its own: it heads the
/// next `span` groups, and its bound holds all their balls.
struct DiskGroup {
  float ux = 0, uy = 0, uz = 1, cos = -2;
  std::uint32_t begin = 0, count = 0, span = 0;
};

/// The bounds of clusters (SphereCluster::bound and least_radius) in structure-of-arrays
/// form, so that their cones from a point are made many at a time.
struct ClusterBounds {
  std::vector<double> x, y, z, radius, least;
  void push(const SphereCluster& cluster) {
    x.push_back(cluster.bound.center.x()), y.push_back(cluster.bound.center.y()), z.push_back(cluster.bound.center.z());
    radius.push_back(cluster.bound.radius), least.push_back(cluster.least_radius);
  }
  std::size_t size() const { return x.size(); }
  void clear() { x.clear(), y.clear(), z.clear(), radius.clear(), least.clear(); }
};

/// The cones of clusters' bounds from one point, as OccluderDisks::bound_cone() makes them
/// (cos < -1: every direction), in structure-of-arrays form.
struct BoundCones {
  std::vector<float> ux, uy, uz, cos;
};

/// The balls of a set as occluder disks from one point, in structure-of-arrays form
/// (single precision), in groups: the balls of one cluster (SphereCluster) after each other,
/// padded to a multiple of kDiskBlock with disks that hide nothing (a ball left out, behind
/// the tangent plane or skipped by the self-shadowing heuristic, keeps its place as one). A group with a bound
/// has that bound's cone too, widened by what the single-precision test of its smallest
/// ball can err (bound_cone): a segment that the single-precision test finds outside it is
/// one that the same test finds outside every cone of the group's balls, so the group's balls
/// need no test. The answers are those of testing every ball.
class OccluderDisks {
 public:
  static constexpr std::size_t kDiskBlock = 16;

  /// Starts over for the point `x` with unit normal `n`. Balls entirely behind the tangent
  /// plane (n . (O - x) <= -R) cannot hide a segment that leaves towards n and are left out.
  void reset(const Vertex& x, const Vertex& n);
  /// Adds the balls of `spheres` as one group without a bound; `self_heuristic` skips those
  /// with t < 2R (the shading point's own object, §4.2). A ball holding x (t <= R) hides
  /// every segment longer than t.
  void add(const std::vector<Sphere>& spheres, bool self_heuristic);
  /// The same, one group per cluster (clusters over `spheres` as cluster_spheres() returns
  /// them, heads of clusters included); a cluster whose bound lies behind the tangent plane
  /// is left out whole, with the clusters it heads.
  void add(const std::vector<Sphere>& spheres, const std::vector<SphereCluster>& clusters, bool self_heuristic);
  /// The same with the clusters' cones already made: those of `cones` from `offset` on, one
  /// per cluster in the clusters' order (bound_cones() of their bounds).
  void add(const std::vector<Sphere>& spheres, const std::vector<SphereCluster>& clusters, bool self_heuristic, const BoundCones& cones,
           std::size_t offset);
  /// The cones bound_cone() gives for every cluster of `bounds`, from this point, into
  /// `cones` (vectorised across clusters).
  void bound_cones(const ClusterBounds& bounds, BoundCones& cones) const;
  /// Call after the last add() and before occludes(). With `grid`, also sorts the disks
  /// into a grid over the stereographic projection of the hemisphere around n (a spherical
  /// cap projects to a disc): each cell lists the disks whose cap can reach it, so that the
  /// group form of occludes() compares a segment only with its cell's disks. The answers
  /// are the same with and without the grid.
  void finish(bool grid = false);

  /// Whether the segment from x to `end` is occluded by a disk; adds the comparisons made
  /// (bounds and disks) to `tests`.
  bool occludes(const Vertex& end, std::uint64_t& tests) const;
  /// occludes() for many segments from x: hidden[i] for the segment to ends[i]. Chunk by
  /// chunk of kChunk segments (disk_groups_hide_chunks): a group's disks only where some
  /// segment of the chunk not hidden yet lies in its bound's cone; with the grid, cell by
  /// cell: each cell's disks across the segments whose direction falls into it.
  void occludes(std::span<const Vertex> ends, std::span<std::uint8_t> hidden, std::uint64_t& tests) const;
  /// Adds the balls [first, last) as one group, with `cone` when it is given: the cone
  /// bound_cone() gives for a ball that holds them and the least of their radii. One
  /// cluster of a set, as add() with clusters adds it.
  void add_run(const Sphere* first, const Sphere* last, bool self_heuristic, const DiskGroup* cone) {
    add_balls(first, last, self_heuristic, cone);
  }
  /// occludes() for the groups [first, last) alone (as groups() counts them; a head's span
  /// must end within the range): a set's groups, added by one add().
  bool occludes_groups(const Vertex& end, std::size_t first, std::size_t last, std::uint64_t& tests) const;
  /// Whether the disks of group `g` (one without span) hide the segment w = (wx, wy, wz)
  /// from x of length z (as occludes() rounds them), its bound's cone not tested; adds the
  /// disks compared to `tests`.
  bool group_disks_occlude(std::size_t g, float wx, float wy, float wz, float z, std::uint64_t& tests) const;
  /// Disks kept (padding not counted).
  std::size_t size() const { return count_; }
  /// Groups kept.
  std::size_t groups() const { return groups_.size(); }

  /// Grid cells per side over [-1, 1]^2 of the projection.
  static constexpr int kGridSide = 8;

  /// The cone from x of `bound`, a ball that holds balls whose least radius is
  /// `least_radius`, widened so that every segment the single-precision disk test finds in
  /// one of their cones is found in it by the same test (cos < -1, every direction, when x
  /// is inside the bound). The disk test w . u > cos gamma |w| in float errs by at most
  /// kDiskTestError |w|: in units of 2^-24 |w|, 0.5 for rounding w, 2.5 for u and 3 for
  /// cos gamma (each made in single precision from |v|^2 and |v|^2 - R^2 rounded from
  /// double), 3 for the dot product, 1 for rounding |w| and the product with cos gamma:
  /// 10, taken as 16; a ball whose cone has half-angle g is then passed
  /// by directions up to acos(cos g - kDiskTestError) - g beyond it, which is largest for
  /// the smallest cone: sin g >= least_radius / (|O - x| + R) for a bound (O, R).
  DiskGroup bound_cone(const Sphere& bound, double least_radius) const;
  static constexpr double kDiskTestError = 0x1.0p-20;
  /// Whether a ball lies wholly behind the tangent plane at x, so that none it holds can
  /// hide a segment; the test add() makes for each cluster.
  bool behind(const Sphere& bound) const { return n_.dot(bound.center - x_) <= -bound.radius; }

 private:
  struct Soa {
    std::vector<float> ux, uy, uz, cos, t;
    void clear() { ux.clear(), uy.clear(), uz.clear(), cos.clear(), t.clear(); }
    void resize(std::size_t n) { ux.resize(n), uy.resize(n), uz.resize(n), cos.resize(n), t.resize(n); }
    void pad_to(std::size_t multiple) {
      // Disks that hide nothing: cos gamma above any cosine.
      const std::size_t n = ux.size(), padded = (n + multiple - 1) / multiple * multiple;
      ux.resize(padded, 0), uy.resize(padded, 0), uz.resize(padded, 1), cos.resize(padded, 2), t.resize(padded, 0);
    }
  };
  void add_balls(const Sphere* first, const Sphere* last, bool self_heuristic, const DiskGroup* cone);

  Vertex x_ = Vertex::Zero(), n_ = Vertex::UnitZ(), tangent_ = Vertex::UnitX(), bitangent_ = Vertex::UnitY();
  std::size_t count_ = 0;
  Soa disks_;
  std::vector<DiskGroup> groups_;
  bool grid_ = false;
  Soa cells_;                            // every cell's disks, one after the other
  std::vector<std::size_t> cell_start_;  // kGridSide^2 + 1 offsets into cells_
};

/// Which instances a shading point's occluder disks stand for. Prepares `disks` at
/// `position` (moved off `hit`) with the balls of every instance that has a sphere set,
/// except the own instance when `trace_own` (its balls with t < 2R skipped when
/// `own_heuristic`), sorted into the grid when there are at least `grid_from`. `traced`:
/// the instances to trace exactly instead (those without a sphere set, and the own one when
/// `trace_own`); `disks`: the others. With
/// `clusters`, each instance's balls come in the groups of RenderWorld::occluder_clusters.
struct DiskPartition {
  unsigned traced = 0, disks = 0;  ///< instance_bit()s
  /// The own instance's bit when it is traced, no other traced instance shares the bit and
  /// its mesh lies behind the hit triangle's plane: segments that clear that plane
  /// (SurfaceHit::own_mesh_clear_of) need not trace it (ExactConnections::skip_own_where_clear).
  unsigned own_alone = 0;
};
/// `bounds`, when given, holds the bounds of every instance's clusters, one instance's after
/// another (OccluderDiskIndex keeps them), so that the point makes all their cones at once.
DiskPartition prepare_occluder_disks(OccluderDisks& disks, const RenderWorld& world, std::size_t instances, const SurfaceHit& hit,
                                     const Vertex& position, bool trace_own, bool own_heuristic, std::size_t grid_from,
                                     bool clusters = true, const ClusterBounds* bounds = nullptr);

/// The instances' sphere sets, indexed once per render for PointDisks: which instances have
/// one, how many with and without one share each mask bit, and, from `lazy_from` instances
/// with a sphere set on, a tree over the boxes that hold the balls of each cluster of every
/// instance (RenderWorld::occluder_clusters, the clusters that head none).
class OccluderDiskIndex {
 public:
  OccluderDiskIndex(const RenderWorld& world, std::size_t instances, std::size_t lazy_from);
  /// Whether points make an instance's disks only when a segment may meet its balls.
  bool lazy() const { return lazy_; }

 private:
  friend class PointDisks;
  const RenderWorld* world_;
  std::size_t instances_ = 0;
  bool lazy_ = false;
  std::vector<std::uint8_t> has_spheres_;
  ClusterBounds bounds_;  // not lazy: every instance's clusters, one instance's after another
  std::array<std::uint32_t, 31> with_spheres_{}, without_spheres_{};  // instances per mask bit
  unsigned with_bits_ = 0, without_bits_ = 0;
  struct Run {
    std::uint32_t instance, cluster;
  };
  std::vector<Run> runs_;  // the tree's items
  BoxTree tree_;
};

/// A shading point's occluder disks and partition, as prepare_occluder_disks() gives them.
/// With an index that is not lazy every disk is made at begin(). With a lazy one, begin()
/// costs the same whatever the instances, and a cluster's disks are made the first time a
/// segment from the point may meet its balls: the index's tree is searched with the
/// segment lengthened, and the boxes grown, by 2^-8 of its length, which holds every
/// segment the single-precision test can find hidden (it errs by at most
/// sqrt(2 kDiskTestError) < 1.5e-3 radians, for the smallest balls), so that the answers are
/// those of every disk. A cluster the search
/// finds is first tested by the cone of its bound alone, made once per point, and its
/// disks are made only for a segment inside that cone (with clusters; the same test the
/// cluster's group makes before its disks).
class PointDisks {
 public:
  DiskPartition begin(const OccluderDiskIndex& index, const SurfaceHit& hit, const Vertex& position, bool trace_own,
                      bool own_heuristic, std::size_t grid_from, bool clusters);
  /// Whether a disk hides the segment to `end`; adds the comparisons made to `tests` and,
  /// with a lazy index, the clusters the tree gave the segment to `clusters`.
  bool occludes(const Vertex& end, std::uint64_t& tests, std::uint64_t* clusters = nullptr);
  void occludes(std::span<const Vertex> ends, std::span<std::uint8_t> hidden, std::uint64_t& tests,
                std::uint64_t* clusters = nullptr);
  /// Disks made so far (padding not counted).
  std::size_t size() const { return disks_.size(); }

 private:
  const OccluderDiskIndex* index_ = nullptr;
  OccluderDisks disks_;
  Vertex x_ = Vertex::Zero();
  int own_ = -1;
  bool skip_own_ = false, own_heuristic_ = false, clusters_ = true;
  std::uint32_t stamp_ = 0;
  std::vector<std::uint32_t> seen_;  // per run of the index: stamp_ once the point has its cone
  std::vector<std::uint32_t> group_;  // per run: its group in disks_, none (no ball in front of the point), or not made yet
  std::vector<DiskGroup> cone_;       // per run: its bound's cone from the point
};

/// A shading point's disks and the instances traced exactly instead, begun together:
/// `disks` as PointDisks::begin with the options' self-shadowing heuristic, grid and
/// clusters, `traced` over the partition's traced instances, leaving out the own one where
/// the segment clears it. `trace_own`: the own instance is traced exactly (the control
/// variate's splitting, or spheres visibility's exact self-shadowing).
DiskPartition begin_point_disks(PointDisks& disks, ExactConnections& traced, const OccluderDiskIndex& index, const RenderWorld& world,
                                const RenderOptions& options, const SurfaceHit& hit, const Vertex& position, bool trace_own);

/// Whether any of the n disks (n a multiple of OccluderDisks::kDiskBlock) hides the
/// segment to w = (wx, wy, wz) at distance z = |w|: w . u_j > cos_j z (cos delta > cos
/// gamma) and t_j < z. Vectorised across disks, blocks of kDiskBlock at a time, with AVX2
/// where the processor has it.
bool any_disk_occludes(const float* ux, const float* uy, const float* uz, const float* cos_gamma, const float* t, std::size_t n,
                       float wx, float wy, float wz, float z);
/// hidden[k] |= whether disk j hides segment k, for every disk j < n and segment k < m
/// (segments given as above: w_k and z_k). Vectorised across segments.
void disks_hide_segments(const float* ux, const float* uy, const float* uz, const float* cos_gamma, const float* t, std::size_t n,
                         const float* wx, const float* wy, const float* wz, const float* z, std::size_t m, std::int32_t* hidden);
/// Segments per chunk of disk_groups_hide_chunks().
inline constexpr std::size_t kChunk = 8;
/// hidden[k] |= whether a disk of the groups hides segment k < m (segments as above), chunk
/// of kChunk segments by chunk: a group's disks are compared with a chunk only when some
/// segment of it, not hidden yet, lies in the group's cone, and a chunk stops once every
/// segment in it is hidden. Every array runs to m rounded up to a multiple of kChunk.
/// Returns the comparisons made (bounds and disks, over the chunk's segments below m).
std::uint64_t disk_groups_hide_chunks(const DiskGroup* groups, std::size_t group_count, const float* ux, const float* uy, const float* uz,
                                      const float* cos_gamma, const float* t, const float* wx, const float* wy, const float* wz,
                                      const float* z, std::size_t m, std::int32_t* hidden);
/// The same, one disk at a time with an early exit and no vectorisation: the baseline the
/// benchmark compares with.
bool any_disk_occludes_scalar(const float* ux, const float* uy, const float* uz, const float* cos_gamma, const float* t,
                              std::size_t n, float wx, float wy, float wz, float z);

/// The definition evaluated in double for one ball, for tests: cos delta > cos gamma and t < z,
/// with a ball holding x hiding every segment longer than t.
bool disk_occludes_reference(const Vertex& x, const Sphere& ball, const Vertex& end);

}  // namespace visproxy
