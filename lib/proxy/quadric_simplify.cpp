// Quadric edge-collapse decimation.
//
// M. Garland, P. S. Heckbert. Surface simplification using quadric error metrics.
// SIGGRAPH 1997. Vertex quadrics are sums of area-weighted triangle plane quadrics; border
// edges add a plane through the edge perpendicular to its triangle (§6 of the paper); the
// merged vertex minimises the summed quadric, or, when that 3x3 system is ill-conditioned,
// is the best of the end points and the midpoint.
//
// The error of a quadric is divided by the area it stands for (as meshoptimizer does), so
// errors are squared distances and the order of collapses does not favour small triangles.
//
// Data layout: flat arrays of vertices, quadrics and triangles; each vertex owns a slice of
// one array of incident triangle ids, re-appended after each collapse (dead triangles are
// skipped, the array is compacted when it has grown); candidate collapses sit in a binary
// heap with lazy deletion: an entry carries the versions of its two vertices and is dropped
// when popped if either vertex changed since.

#include "proxy/quadric_simplify.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

#include "core/errors.h"

namespace visproxy {
namespace {

using Vec3 = Eigen::Vector3d;

// Border planes weigh this much per squared edge length (a triangle's plane weighs its area).
constexpr double kBorderWeight = 10.0;
// The quadric's 3x3 part is solved for the optimal position only if det(A) / (trace(A)/3)^3,
// which is 1 for an isotropic quadric and 0 for a flat or ridge-like one, exceeds this.
constexpr double kMinRelativeDeterminant = 1e-3;
// A collapse is a flip if a moved triangle's normal turns by this much or more (cosine).
constexpr double kMinNormalCosine = 0.0;
// The heap is purged of stale entries when it holds more than this many per live triangle
// (a mesh has about 1.5 edges per triangle).
constexpr std::size_t kStaleHeapFactor = 2;
constexpr std::uint32_t kDeadTriangle = std::numeric_limits<std::uint32_t>::max();

// Symmetric 4x4 quadric [A b; b^T c] in its 10 distinct entries, with the area it stands for.
struct Quadric {
  double xx = 0, xy = 0, xz = 0, xw = 0, yy = 0, yz = 0, yw = 0, zz = 0, zw = 0, ww = 0;
  double weight = 0;

  // weight * (n.p + d)^2 for a unit normal n.
  static Quadric plane(const Vec3& n, double d, double weight) {
    Quadric q;
    q.xx = weight * n.x() * n.x();
    q.xy = weight * n.x() * n.y();
    q.xz = weight * n.x() * n.z();
    q.xw = weight * n.x() * d;
    q.yy = weight * n.y() * n.y();
    q.yz = weight * n.y() * n.z();
    q.yw = weight * n.y() * d;
    q.zz = weight * n.z() * n.z();
    q.zw = weight * n.z() * d;
    q.ww = weight * d * d;
    q.weight = weight;
    return q;
  }

  Quadric& operator+=(const Quadric& o) {
    xx += o.xx, xy += o.xy, xz += o.xz, xw += o.xw, yy += o.yy;
    yz += o.yz, yw += o.yw, zz += o.zz, zw += o.zw, ww += o.ww;
    weight += o.weight;
    return *this;
  }
  friend Quadric operator+(Quadric a, const Quadric& b) { return a += b; }

  // Squared distance of p to the planes, averaged by weight; 0 for an empty quadric.
  double error(const Vec3& p) const {
    const double x = p.x(), y = p.y(), z = p.z();
    const double sum = xx * x * x + yy * y * y + zz * z * z + 2 * (xy * x * y + xz * x * z + yz * y * z) +
                       2 * (xw * x + yw * y + zw * z) + ww;
    return weight > 0 && sum > 0 ? sum / weight : 0.0;
  }

  // The minimiser of the quadric if A is well-conditioned.
  bool minimiser(Vec3& out) const {
    const double c00 = yy * zz - yz * yz, c01 = xz * yz - xy * zz, c02 = xy * yz - xz * yy;
    const double det = xx * c00 + xy * c01 + xz * c02;
    const double third_trace = (xx + yy + zz) / 3;
    if (!(third_trace > 0) || !(det > kMinRelativeDeterminant * third_trace * third_trace * third_trace)) return false;
    const double c11 = xx * zz - xz * xz, c12 = xy * xz - xx * yz, c22 = xx * yy - xy * xy;
    const double inverse_det = 1 / det;
    out = {-(c00 * xw + c01 * yw + c02 * zw) * inverse_det, -(c01 * xw + c11 * yw + c12 * zw) * inverse_det,
           -(c02 * xw + c12 * yw + c22 * zw) * inverse_det};
    return out.allFinite();
  }
};

struct Placement {
  double error;
  Vec3 position;
};

// A candidate collapse of edge (keep, remove) into `keep`, valid while the two vertices'
// versions are the ones recorded (16 bits each: a version that wrapped around could let a
// stale entry through, which only reorders one collapse, as each is re-checked when made).
struct HeapEntry {
  std::uint64_t key;  // float bits of the error (monotonic for errors >= 0), then keep
  std::uint32_t remove;
  std::uint16_t keep_version, remove_version;

  std::uint32_t keep() const { return static_cast<std::uint32_t>(key); }
};

// Min-heap of collapses with four children per node: half the depth of a binary heap, and
// the children of a node share a cache line. Ties are broken by the keep vertex.
class CollapseHeap {
 public:
  bool empty() const { return entries_.empty(); }
  std::size_t size() const { return entries_.size(); }
  void clear() { entries_.clear(); }

  static std::uint64_t key(double error, std::uint32_t keep) {
    const auto error_bits = std::bit_cast<std::uint32_t>(static_cast<float>(error));
    return (std::uint64_t{error_bits} << 32) | keep;
  }

  void push(const HeapEntry& entry) {
    std::size_t i = entries_.size();
    entries_.push_back(entry);
    while (i > 0) {
      const std::size_t parent = (i - 1) / 4;
      if (entries_[parent].key <= entry.key) break;
      entries_[i] = entries_[parent];
      i = parent;
    }
    entries_[i] = entry;
  }

  HeapEntry pop() {
    const HeapEntry top = entries_.front();
    const HeapEntry last = entries_.back();
    entries_.pop_back();
    if (!entries_.empty()) sift_down(0, last);
    return top;
  }

  // Pushes without ordering, then restores the heap at once with heapify().
  void append(const HeapEntry& entry) { entries_.push_back(entry); }
  void heapify() {
    for (std::size_t i = entries_.size() / 4 + 1; i-- > 0;)
      if (i < entries_.size()) sift_down(i, entries_[i]);
  }

  // Drops the entries for which `stale` holds and restores the heap.
  template <typename Stale>
  void remove_if(Stale&& stale) {
    entries_.erase(std::remove_if(entries_.begin(), entries_.end(), stale), entries_.end());
    heapify();
  }

 private:
  void sift_down(std::size_t i, const HeapEntry& entry) {
    const std::size_t n = entries_.size();
    for (;;) {
      const std::size_t first = 4 * i + 1;
      if (first >= n) break;
      std::size_t best = first;
      const std::size_t last = std::min(first + 4, n);
      for (std::size_t c = first + 1; c < last; ++c)
        if (entries_[c].key < entries_[best].key) best = c;
      if (entry.key <= entries_[best].key) break;
      entries_[i] = entries_[best];
      i = best;
    }
    entries_[i] = entry;
  }

  std::vector<HeapEntry> entries_;
};

// Interleaved bits of the coordinates of p in [-1/2, 1/2]^3 quantised to 21 bits each.
std::uint64_t morton_code(const Vec3& p) {
  const auto spread = [](double coordinate) {
    const double unit = std::clamp(coordinate + 0.5, 0.0, 1.0);
    std::uint64_t x = static_cast<std::uint64_t>(unit * double((1u << 21) - 1));
    x = (x | (x << 32)) & 0x1f00000000ffffULL;
    x = (x | (x << 16)) & 0x1f0000ff0000ffULL;
    x = (x | (x << 8)) & 0x100f00f00f00f00fULL;
    x = (x | (x << 4)) & 0x10c30c30c30c30c3ULL;
    x = (x | (x << 2)) & 0x1249249249249249ULL;
    return x;
  };
  return spread(p.x()) | (spread(p.y()) << 1) | (spread(p.z()) << 2);
}

bool exactly_collinear(const Vec3& a, const Vec3& b, const Vec3& c) {
  using Point = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
  return CGAL::collinear(Point(a.x(), a.y(), a.z()), Point(b.x(), b.y(), b.z()), Point(c.x(), c.y(), c.z()));
}

class QuadricSimplifier {
 public:
  QuadricSimplifier(const TriangleMesh& mesh, std::size_t max_triangles)
      : input_(mesh), max_triangles_(max_triangles) {
    weld_and_normalise();
    build_incidence();
    build_quadrics();
  }

  QuadricSimplifyResult run() {
    QuadricSimplifyResult result;
    // Rule levels: 0 all rules, 1 flips allowed, 2 every collapse allowed.
    int level = 0;
    build_heap();
    std::size_t collapses_at_build = 0;
    while (alive_triangles_ > max_triangles_) {
      if (heap_.empty()) {
        if (collapses_ == collapses_at_build) {
          if (level == 2) {
            drop_smallest_triangles();
            break;
          }
          ++level;
        }
        build_heap();
        collapses_at_build = collapses_;
        continue;
      }
      if (heap_.size() > kStaleHeapFactor * alive_triangles_ + 1024)
        heap_.remove_if([this](const HeapEntry& entry) { return stale(entry); });
      const HeapEntry entry = heap_.pop();
      if (stale(entry)) continue;
      try_collapse(entry.keep(), entry.remove, level);
    }
    result.mesh = output_mesh();
    result.max_quadric_error_relative = std::sqrt(max_error_);
    result.collapses = collapses_;
    return result;
  }

 private:
  // Validates the input, merges vertices with identical coordinates, drops triangles with a
  // repeated corner and moves the vertices into a box of diagonal 1 centred at the origin.
  void weld_and_normalise() {
    const std::size_t vertex_count = input_.positions.size();
    std::vector<std::uint8_t> used(vertex_count, 0);
    for (const Triangle& triangle : input_.triangles)
      for (const VertexIndex index : triangle) {
        if (index >= vertex_count)
          throw InvalidInputError("", "triangle corner " + std::to_string(index) + " is out of range (" +
                                          std::to_string(vertex_count) + " vertices)");
        if (!used[index]) {
          if (!input_.positions[index].allFinite())
            throw InvalidInputError("", "vertex " + std::to_string(index) + " has a non-finite coordinate");
          used[index] = 1;
        }
      }
    // Representative of each used vertex: the lowest index with the same coordinates.
    std::vector<VertexIndex> sorted;
    for (std::size_t v = 0; v < vertex_count; ++v)
      if (used[v]) sorted.push_back(static_cast<VertexIndex>(v));
    const auto& p = input_.positions;
    std::sort(sorted.begin(), sorted.end(), [&p](VertexIndex a, VertexIndex b) {
      if (p[a].x() != p[b].x()) return p[a].x() < p[b].x();
      if (p[a].y() != p[b].y()) return p[a].y() < p[b].y();
      if (p[a].z() != p[b].z()) return p[a].z() < p[b].z();
      return a < b;
    });
    std::vector<VertexIndex> representative(vertex_count, 0);
    for (std::size_t i = 0; i < sorted.size();) {
      std::size_t j = i + 1;
      while (j < sorted.size() && p[sorted[j]] == p[sorted[i]]) ++j;
      for (std::size_t k = i; k < j; ++k) representative[sorted[k]] = sorted[i];
      i = j;
    }

    const BoundingBox box = bounding_box(input_);
    center_ = (box.min + box.max) / 2;
    diagonal_ = box.diagonal();
    const double scale = diagonal_ > 0 ? 1 / diagonal_ : 1.0;

    // Working vertices in Morton order of their positions, so that neighbours are near in
    // memory; triangles sorted by their first vertex.
    std::vector<std::pair<std::uint64_t, VertexIndex>> by_code;
    for (std::size_t i = 0; i < sorted.size(); ++i)
      if (representative[sorted[i]] == sorted[i])
        by_code.emplace_back(morton_code((p[sorted[i]] - center_) * scale), sorted[i]);
    std::sort(by_code.begin(), by_code.end());
    std::vector<std::uint32_t> working(vertex_count, kDeadTriangle);
    for (const auto& [code, r] : by_code) {
      working[r] = static_cast<std::uint32_t>(origin_.size());
      origin_.push_back(r);
      position_.push_back((p[r] - center_) * scale);
    }
    triangles_.reserve(input_.triangles.size());
    for (const Triangle& triangle : input_.triangles) {
      const Triangle mapped = {working[representative[triangle[0]]], working[representative[triangle[1]]],
                               working[representative[triangle[2]]]};
      if (mapped[0] != mapped[1] && mapped[1] != mapped[2] && mapped[2] != mapped[0]) triangles_.push_back(mapped);
    }
    std::stable_sort(triangles_.begin(), triangles_.end(), [](const Triangle& a, const Triangle& b) {
      return std::min({a[0], a[1], a[2]}) < std::min({b[0], b[1], b[2]});
    });
    alive_triangles_ = triangles_.size();
    const std::size_t n = position_.size();
    moved_.assign(n, 0);
    version_.assign(n, 0);
    vertex_alive_.assign(n, 1);
    border_.assign(n, 0);
    mark_.assign(n, 0);
  }

  // Incident triangles of every vertex as slices of refs_.
  void build_incidence() {
    const std::size_t n = position_.size();
    ref_start_.assign(n, 0);
    ref_count_.assign(n, 0);
    for (const Triangle& t : triangles_)
      if (t[0] != kDeadTriangle)
        for (const std::uint32_t v : t) ++ref_count_[v];
    std::uint32_t start = 0;
    for (std::size_t v = 0; v < n; ++v) {
      ref_start_[v] = start;
      start += ref_count_[v];
      ref_count_[v] = 0;
    }
    refs_.assign(start, 0);
    refs_.reserve(std::size_t{3} * start + 1024);
    for (std::size_t t = 0; t < triangles_.size(); ++t)
      if (triangles_[t][0] != kDeadTriangle)
        for (const std::uint32_t v : triangles_[t]) refs_[ref_start_[v] + ref_count_[v]++] = static_cast<std::uint32_t>(t);
    compact_at_ = refs_.capacity();
  }

  void build_quadrics() {
    quadric_.assign(position_.size(), Quadric{});
    std::vector<Vec3> unit_normal(triangles_.size(), Vec3::Zero());
    for (std::size_t t = 0; t < triangles_.size(); ++t) {
      const Triangle& tri = triangles_[t];
      const Vec3 cross = (position_[tri[1]] - position_[tri[0]]).cross(position_[tri[2]] - position_[tri[0]]);
      const double length = cross.norm();
      if (!(length > 0)) continue;
      unit_normal[t] = cross / length;
      const Quadric q = Quadric::plane(unit_normal[t], -unit_normal[t].dot(position_[tri[0]]), length / 2);
      for (const std::uint32_t v : tri) quadric_[v] += q;
    }
    // Border edges: edges (u, w) that exactly one triangle has; each is seen from its lower end.
    std::vector<std::uint32_t> count(position_.size(), 0);
    for (std::uint32_t u = 0; u < position_.size(); ++u) {
      for_each_triangle(u, [&](std::uint32_t t) {
        for (const std::uint32_t w : triangles_[t])
          if (w != u) ++count[w];
      });
      for_each_triangle(u, [&](std::uint32_t t) {
        const Triangle& tri = triangles_[t];
        for (int c = 0; c < 3; ++c) {
          const std::uint32_t a = tri[c], b = tri[(c + 1) % 3];
          if (a != u && b != u) continue;
          const std::uint32_t w = a == u ? b : a;
          if (w < u || count[w] != 1) continue;
          border_[u] = border_[w] = 1;
          const Vec3 edge = position_[b] - position_[a];
          const Vec3 normal = edge.cross(unit_normal[t]);
          const double length = normal.norm();
          if (!(length > 0)) continue;
          const Vec3 n = normal / length;
          const Quadric q = Quadric::plane(n, -n.dot(position_[a]), kBorderWeight * edge.squaredNorm());
          quadric_[u] += q;
          quadric_[w] += q;
        }
      });
      for_each_triangle(u, [&](std::uint32_t t) {
        for (const std::uint32_t w : triangles_[t]) count[w] = 0;
      });
    }
  }

  template <typename F>
  void for_each_triangle(std::uint32_t v, F&& f) const {
    const std::uint32_t* begin = refs_.data() + ref_start_[v];
    for (const std::uint32_t* it = begin; it != begin + ref_count_[v]; ++it)
      if (triangles_[*it][0] != kDeadTriangle) f(*it);
  }

  Placement placement(std::uint32_t a, std::uint32_t b) const {
    const Quadric q = quadric_[a] + quadric_[b];
    const Vec3& pa = position_[a];
    const Vec3& pb = position_[b];
    Vec3 optimum;
    if (q.minimiser(optimum)) {
      // Keep the optimum near the edge: far-off minimisers of nearly singular systems fold the mesh.
      const Vec3 midpoint = (pa + pb) / 2;
      if ((optimum - midpoint).squaredNorm() <= (pa - pb).squaredNorm()) return {q.error(optimum), optimum};
    }
    Placement best{q.error(pa), pa};
    const double error_b = q.error(pb);
    if (error_b < best.error) best = {error_b, pb};
    const Vec3 midpoint = (pa + pb) / 2;
    const double error_mid = q.error(midpoint);
    if (error_mid < best.error) best = {error_mid, midpoint};
    return best;
  }

  HeapEntry entry(std::uint32_t keep, std::uint32_t remove) const {
    return {CollapseHeap::key(placement(keep, remove).error, keep), remove, version_[keep], version_[remove]};
  }

  // A heap of every edge of the current mesh.
  void build_heap() {
    heap_.clear();
    for (std::uint32_t u = 0; u < position_.size(); ++u) {
      if (!vertex_alive_[u]) continue;
      next_stamp();
      for_each_triangle(u, [&](std::uint32_t t) {
        for (const std::uint32_t w : triangles_[t])
          if (w > u && mark_[w] != stamp_) {
            mark_[w] = stamp_;
            heap_.append(entry(u, w));
          }
      });
    }
    heap_.heapify();
  }

  // A fresh value for mark_, which no vertex holds yet.
  std::uint32_t next_stamp() {
    if (stamp_ == std::numeric_limits<std::uint32_t>::max()) {
      std::fill(mark_.begin(), mark_.end(), 0);
      stamp_ = 0;
    }
    return ++stamp_;
  }

  bool stale(const HeapEntry& entry) const {
    return version_[entry.keep()] != entry.keep_version || version_[entry.remove] != entry.remove_version;
  }

  static int corner_of(const Triangle& t, std::uint32_t v) { return t[0] == v ? 0 : t[1] == v ? 1 : t[2] == v ? 2 : -1; }

  // Collapses edge (keep, remove) into keep if the rules of `level` allow it.
  void try_collapse(std::uint32_t keep, std::uint32_t remove, int level) {
    keep_triangles_.clear();
    remove_triangles_.clear();
    for_each_triangle(keep, [&](std::uint32_t t) { keep_triangles_.push_back(t); });
    std::size_t shared = 0;
    for_each_triangle(remove, [&](std::uint32_t t) {
      remove_triangles_.push_back(t);
      if (corner_of(triangles_[t], keep) >= 0) ++shared;
    });
    if (shared == 0) return;  // not an edge any more
    if (alive_triangles_ == shared) return;  // would leave nothing
    if (level < 2 && !keeps_topology(keep, remove, shared)) return;

    const Placement target = placement(keep, remove);
    if (level < 1 && flips(keep, remove, target.position)) return;

    if (refs_.size() + keep_triangles_.size() + remove_triangles_.size() > compact_at_) compact_refs();
    for (const std::uint32_t t : remove_triangles_) {
      Triangle& tri = triangles_[t];
      if (corner_of(tri, keep) >= 0) {
        tri[0] = kDeadTriangle;
        --alive_triangles_;
      } else {
        tri[corner_of(tri, remove)] = keep;
      }
    }
    const auto start = static_cast<std::uint32_t>(refs_.size());
    for (const std::uint32_t t : keep_triangles_)
      if (triangles_[t][0] != kDeadTriangle) refs_.push_back(t);
    for (const std::uint32_t t : remove_triangles_)
      if (triangles_[t][0] != kDeadTriangle) refs_.push_back(t);
    ref_start_[keep] = start;
    ref_count_[keep] = static_cast<std::uint32_t>(refs_.size()) - start;
    ref_count_[remove] = 0;

    quadric_[keep] += quadric_[remove];
    position_[keep] = target.position;
    moved_[keep] = 1;
    border_[keep] = border_[keep] | border_[remove];
    vertex_alive_[remove] = 0;
    ++version_[keep];
    ++version_[remove];
    max_error_ = std::max(max_error_, target.error);
    ++collapses_;

    next_stamp();
    for_each_triangle(keep, [&](std::uint32_t t) {
      for (const std::uint32_t w : triangles_[t])
        if (w != keep && mark_[w] != stamp_) {
          mark_[w] = stamp_;
          heap_.push(entry(keep, w));
        }
    });
  }

  // Link condition (the vertices adjacent to both ends are exactly the corners opposite the
  // edge), no border-to-border shortcut through the interior, no duplicated triangle.
  bool keeps_topology(std::uint32_t keep, std::uint32_t remove, std::size_t shared) {
    if (border_[keep] && border_[remove] && shared != 1) return false;
    const std::uint32_t neighbour = next_stamp(), opposite = next_stamp();
    for (const std::uint32_t t : keep_triangles_)
      for (const std::uint32_t w : triangles_[t])
        if (w != keep) mark_[w] = neighbour;
    for (const std::uint32_t t : remove_triangles_) {
      const Triangle& tri = triangles_[t];
      if (corner_of(tri, keep) >= 0)
        for (const std::uint32_t w : tri)
          if (w != keep && w != remove) mark_[w] = opposite;
    }
    for (const std::uint32_t t : remove_triangles_) {
      const Triangle& tri = triangles_[t];
      if (corner_of(tri, keep) >= 0) continue;
      for (const std::uint32_t w : tri)
        if (w != remove && mark_[w] == neighbour) return false;
      // The triangle after the collapse must not exist already around keep.
      const int c = corner_of(tri, remove);
      const std::uint32_t a = tri[(c + 1) % 3], b = tri[(c + 2) % 3];
      if (mark_[a] != opposite || mark_[b] != opposite) continue;
      for (const std::uint32_t s : keep_triangles_) {
        const Triangle& other = triangles_[s];
        if (corner_of(other, a) >= 0 && corner_of(other, b) >= 0) return false;
      }
    }
    return true;
  }

  // Does moving keep and remove to `target` turn any surviving triangle's normal too far?
  bool flips(std::uint32_t keep, std::uint32_t remove, const Vec3& target) const {
    const auto turns = [&](std::uint32_t t, std::uint32_t moving) {
      const Triangle& tri = triangles_[t];
      const int c = corner_of(tri, moving);
      const Vec3& a = position_[tri[(c + 1) % 3]];
      const Vec3& b = position_[tri[(c + 2) % 3]];
      const Vec3 before = (a - position_[moving]).cross(b - position_[moving]);
      const Vec3 after = (a - target).cross(b - target);
      const double dot = before.dot(after);
      if (!(dot > 0)) return true;
      return dot * dot < kMinNormalCosine * kMinNormalCosine * before.squaredNorm() * after.squaredNorm();
    };
    for (const std::uint32_t t : keep_triangles_)
      if (corner_of(triangles_[t], remove) < 0 && turns(t, keep)) return true;
    for (const std::uint32_t t : remove_triangles_)
      if (corner_of(triangles_[t], keep) < 0 && turns(t, remove)) return true;
    return false;
  }

  void compact_refs() {
    build_incidence();
    // Leave room for the next collapses without compacting again soon.
    compact_at_ = std::max(compact_at_, 3 * refs_.size() + 1024);
    refs_.reserve(compact_at_);
  }

  // Last resort: keep the max_triangles_ largest triangles.
  void drop_smallest_triangles() {
    std::vector<std::pair<double, std::uint32_t>> by_area;
    for (std::uint32_t t = 0; t < triangles_.size(); ++t) {
      const Triangle& tri = triangles_[t];
      if (tri[0] == kDeadTriangle) continue;
      const double area = (position_[tri[1]] - position_[tri[0]]).cross(position_[tri[2]] - position_[tri[0]]).squaredNorm();
      by_area.emplace_back(-area, t);
    }
    std::sort(by_area.begin(), by_area.end());
    for (std::size_t i = max_triangles_; i < by_area.size(); ++i) {
      triangles_[by_area[i].second][0] = kDeadTriangle;
      --alive_triangles_;
    }
  }

  Vertex world_position(std::uint32_t v) const {
    if (!moved_[v]) return input_.positions[origin_[v]];
    return position_[v] * (diagonal_ > 0 ? diagonal_ : 1.0) + center_;
  }

  // Surviving triangles without exactly collinear ones or same-order duplicates, over the
  // vertices they use, numbered in order of first use.
  TriangleMesh output_mesh() const {
    std::vector<Vertex> world(position_.size());
    for (std::uint32_t v = 0; v < position_.size(); ++v)
      if (vertex_alive_[v]) world[v] = world_position(v);
    std::vector<Triangle> kept;
    for (const Triangle& tri : triangles_) {
      if (tri[0] == kDeadTriangle) continue;
      if (exactly_collinear(world[tri[0]], world[tri[1]], world[tri[2]])) continue;
      // Rotate so the smallest index comes first: equal triangles become equal arrays.
      const int first = tri[0] < tri[1] ? (tri[0] < tri[2] ? 0 : 2) : (tri[1] < tri[2] ? 1 : 2);
      kept.push_back({tri[first], tri[(first + 1) % 3], tri[(first + 2) % 3]});
    }
    std::vector<std::uint32_t> order(kept.size());
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(), [&kept](std::uint32_t a, std::uint32_t b) {
      return kept[a] != kept[b] ? kept[a] < kept[b] : a < b;
    });
    std::vector<std::uint8_t> duplicate(kept.size(), 0);
    for (std::size_t i = 1; i < order.size(); ++i)
      if (kept[order[i]] == kept[order[i - 1]]) duplicate[order[i]] = 1;

    TriangleMesh mesh;
    std::vector<std::uint32_t> output_index(position_.size(), kDeadTriangle);
    for (std::size_t t = 0; t < kept.size(); ++t) {
      if (duplicate[t]) continue;
      Triangle out;
      for (int c = 0; c < 3; ++c) {
        const std::uint32_t v = kept[t][c];
        if (output_index[v] == kDeadTriangle) {
          output_index[v] = static_cast<std::uint32_t>(mesh.positions.size());
          mesh.positions.push_back(world[v]);
        }
        out[c] = output_index[v];
      }
      mesh.triangles.push_back(out);
    }
    return mesh;
  }

  const TriangleMesh& input_;
  std::size_t max_triangles_;
  Vec3 center_ = Vec3::Zero();
  double diagonal_ = 0;

  // Per working vertex.
  std::vector<Vec3> position_;  // in the normalised frame
  std::vector<Quadric> quadric_;
  std::vector<VertexIndex> origin_;  // input vertex it started as
  std::vector<std::uint8_t> moved_, vertex_alive_, border_;
  std::vector<std::uint16_t> version_;
  std::vector<std::uint32_t> mark_;
  std::vector<std::uint32_t> ref_start_, ref_count_;
  std::uint32_t stamp_ = 0;

  std::vector<Triangle> triangles_;  // [0] == kDeadTriangle once collapsed
  std::size_t alive_triangles_ = 0;
  std::vector<std::uint32_t> refs_;
  std::size_t compact_at_ = 0;

  CollapseHeap heap_;
  std::vector<std::uint32_t> keep_triangles_, remove_triangles_;
  double max_error_ = 0;
  std::size_t collapses_ = 0;
};

}  // namespace

QuadricSimplifyResult simplify_quadric(const TriangleMesh& mesh, const QuadricSimplifyOptions& options) {
  if (options.max_triangles == 0) throw InvalidInputError("", "the triangle budget of quadric simplification is 0");
  if (mesh.triangles.empty()) throw InvalidInputError("", "the mesh has no triangles to simplify");
  return QuadricSimplifier(mesh, options.max_triangles).run();
}

}  // namespace visproxy
