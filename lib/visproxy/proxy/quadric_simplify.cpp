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
// Collapses are made in passes, cheapest first, as in meshoptimizer's simplifier: a pass
// rates every edge, sorts the rates, and collapses edges in that order up to half of the
// triangles still over budget and up to 1.5 times the error of the collapse at the pass's
// goal. A collapse locks its two vertices for the rest of the pass (their neighbours only
// lose dead triangles, and their rates do not change), so a pass needs no incremental
// update: incidence is rebuilt between passes over flat arrays, and only the edges at the
// survivors of the last pass are rated again. This is far kinder to the cache than a
// global heap: on bunny00 to 512 triangles, a lazy-deletion heap of edges took about 2.5x
// as long, for a sampled Hausdorff error of 0.010-0.017 of the diagonal (depending on
// tie-breaking) against 0.009-0.010 here, although the greedy order is now exact only
// within a pass.

#include "visproxy/proxy/quadric_simplify.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/proxy/detail/output_mesh.h"
#include "visproxy/proxy/detail/plane_quadric.h"

namespace visproxy {
namespace {

using Vec3 = Eigen::Vector3d;

// Border planes weigh this much per squared edge length (a triangle's plane weighs its area).
constexpr double kBorderWeight = 10.0;
// The quadric's 3x3 part is solved for the optimal position only if det(A) / (trace(A)/3)^3
// exceeds this (PlaneQuadric::minimiser).
constexpr double kMinRelativeDeterminant = 1e-3;
// A collapse is a flip if a moved triangle's normal turns by this much or more (cosine).
constexpr double kMinNormalCosine = 0.0;
// A pass stops at collapses whose error exceeds this many times that of its goal collapse.
constexpr double kPassErrorSlack = 1.5;
// Marks a dead triangle (in its first corner) and a vertex not numbered yet.
constexpr std::uint32_t kDeadTriangle = std::numeric_limits<std::uint32_t>::max();
constexpr std::uint32_t kUnnumbered = std::numeric_limits<std::uint32_t>::max();

using Quadric = detail::PlaneQuadric;

struct Placement {
  double error;
  Vec3 position;
};

// A candidate collapse of edge (u, w), rated by the float bits of its error (which order
// like the errors, as errors are >= 0).
struct Candidate {
  std::uint32_t error_bits;
  std::uint32_t u, w;

  double error() const { return static_cast<double>(std::bit_cast<float>(error_bits)); }
};

std::uint32_t error_bits(double error) { return std::bit_cast<std::uint32_t>(static_cast<float>(error)); }

// Sorts by error with a stable LSD radix sort (11 bits per round), so ties keep the order
// in which the edges were listed.
void sort_candidates(std::vector<Candidate>& candidates, std::vector<Candidate>& scratch) {
  scratch.resize(candidates.size());
  for (int shift = 0; shift < 32; shift += 11) {
    std::size_t count[2049] = {};
    for (const Candidate& c : candidates) ++count[((c.error_bits >> shift) & 2047) + 1];
    for (std::size_t i = 1; i < 2049; ++i) count[i] += count[i - 1];
    for (const Candidate& c : candidates) scratch[count[(c.error_bits >> shift) & 2047]++] = c;
    candidates.swap(scratch);
  }
}

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

// Asks for every cache line of `object` (a hint: it reads nothing and cannot fault).
// Prefetches have no effect the compiler can see, so a call to a function made only of them
// may be dropped as useless (GCC 12 does): these functions must be inlined.
template <typename T>
[[gnu::always_inline]] inline void prefetch_object(const T& object) {
  const char* first = reinterpret_cast<const char*>(&object);
  for (std::size_t byte = 0; byte < sizeof(T); byte += 64) __builtin_prefetch(first + byte);
  __builtin_prefetch(first + sizeof(T) - 1);
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
    // Rule levels: 0 all rules, 1 flips allowed, 2 every collapse allowed. A pass that
    // collapses nothing is repeated without its error limit, then at the next level.
    int level = 0;
    bool limited = true;
    while (alive_triangles_ > max_triangles_) {
      if (run_pass(level, limited) > 0) {
        limited = true;
      } else if (limited) {
        limited = false;
      } else if (level < 2) {
        ++level;
        limited = true;
      } else {
        drop_smallest_triangles();
      }
    }
    QuadricSimplifyResult result;
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
    const auto& p = input_.positions;
    const BoundingBox box = bounding_box(input_);
    center_ = (box.min + box.max) / 2;
    diagonal_ = box.diagonal();
    const double scale = diagonal_ > 0 ? 1 / diagonal_ : 1.0;

    // Used vertices in Morton order of their positions (so that neighbours are near in
    // memory), then by index. Equal coordinates have equal codes: each run of equal
    // coordinates within a code becomes one working vertex, the input vertex of lowest index.
    std::vector<std::pair<std::uint64_t, VertexIndex>> by_code;
    for (std::size_t v = 0; v < vertex_count; ++v)
      if (used[v]) by_code.emplace_back(morton_code((p[v] - center_) * scale), static_cast<VertexIndex>(v));
    std::sort(by_code.begin(), by_code.end());
    std::vector<std::uint32_t> working(vertex_count, kUnnumbered);
    for (std::size_t i = 0; i < by_code.size(); ++i) {
      const VertexIndex v = by_code[i].second;
      for (std::size_t j = i; j-- > 0 && by_code[j].first == by_code[i].first;)
        if (p[by_code[j].second] == p[v]) {
          working[v] = working[by_code[j].second];
          break;
        }
      if (working[v] != kUnnumbered) continue;
      working[v] = static_cast<std::uint32_t>(origin_.size());
      origin_.push_back(v);
      position_.push_back((p[v] - center_) * scale);
    }

    // Triangles without repeated corners, grouped by their lowest corner (counting sort).
    const std::size_t n = position_.size();
    std::vector<std::uint32_t> first(n + 1, 0);
    std::vector<Triangle> mapped;
    mapped.reserve(input_.triangles.size());
    for (const Triangle& triangle : input_.triangles) {
      const Triangle t = {working[triangle[0]], working[triangle[1]], working[triangle[2]]};
      if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) continue;
      mapped.push_back(t);
      ++first[std::min({t[0], t[1], t[2]}) + 1];
    }
    for (std::size_t v = 0; v < n; ++v) first[v + 1] += first[v];
    triangles_.resize(mapped.size());
    for (const Triangle& t : mapped) triangles_[first[std::min({t[0], t[1], t[2]})]++] = t;
    alive_triangles_ = triangles_.size();
    moved_.assign(n, 0);
    lock_.assign(n, 0);
    border_.assign(n, 0);
    mark_.assign(n, 0);
  }

  // Drops dead triangles and lists the incident triangles of every vertex as slices of refs_.
  void build_incidence() {
    triangles_.erase(std::remove_if(triangles_.begin(), triangles_.end(),
                                    [](const Triangle& t) { return t[0] == kDeadTriangle; }),
                     triangles_.end());
    const std::size_t n = position_.size();
    ref_start_.assign(n + 1, 0);
    for (const Triangle& t : triangles_)
      for (const std::uint32_t v : t) ++ref_start_[v + 1];
    for (std::size_t v = 0; v < n; ++v) ref_start_[v + 1] += ref_start_[v];
    refs_.resize(ref_start_[n]);
    for (std::size_t t = 0; t < triangles_.size(); ++t)
      for (const std::uint32_t v : triangles_[t]) refs_[ref_start_[v]++] = static_cast<std::uint32_t>(t);
    for (std::size_t v = n; v > 0; --v) ref_start_[v] = ref_start_[v - 1];
    ref_start_[0] = 0;
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
    std::vector<std::uint32_t> count(position_.size(), 0), counted_for(position_.size(), kUnnumbered);
    for (std::uint32_t u = 0; u < position_.size(); ++u) {
      for_each_triangle(u, [&](std::uint32_t t) {
        for (const std::uint32_t w : triangles_[t]) {
          if (counted_for[w] != u) counted_for[w] = u, count[w] = 0;
          ++count[w];
        }
      });
      for_each_triangle(u, [&](std::uint32_t t) {
        const Triangle& tri = triangles_[t];
        const int c = corner_of(tri, u);
        for (const int side : {1, 2}) {
          const std::uint32_t w = tri[(c + side) % 3];
          if (w < u || count[w] != 1) continue;
          border_[u] = border_[w] = 1;
          // The edge in the triangle's direction, u -> w or w -> u.
          const std::uint32_t a = side == 1 ? u : w, b = side == 1 ? w : u;
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
    }
  }

  // Calls f for the triangles of v as the incidence lists have them (from the pass's start).
  template <typename F>
  void for_each_triangle(std::uint32_t v, F&& f) const {
    for (std::uint32_t i = ref_start_[v]; i < ref_start_[v + 1]; ++i)
      if (triangles_[refs_[i]][0] != kDeadTriangle) f(refs_[i]);
  }

  Placement placement(std::uint32_t a, std::uint32_t b) const {
    const Quadric q = quadric_[a] + quadric_[b];
    const double inverse_weight = q.weight > 0 ? 1 / q.weight : 0.0;
    const Vec3& pa = position_[a];
    const Vec3& pb = position_[b];
    const Vec3 midpoint = (pa + pb) / 2;
    Vec3 optimum;
    // Keep the optimum near the edge: far-off minimisers of nearly singular systems fold the mesh.
    if (q.minimiser(optimum, kMinRelativeDeterminant) && (optimum - midpoint).squaredNorm() <= (pa - pb).squaredNorm()) {
      // At the minimiser x of x^T A x + 2 b.x + c, A x = -b, so the sum is b.x + c.
      const double sum = q.xw * optimum.x() + q.yw * optimum.y() + q.zw * optimum.z() + q.ww;
      return {std::max(0.0, sum) * inverse_weight, optimum};
    }
    double best = q.sum(pa);
    Vec3 position = pa;
    if (const double sum_b = q.sum(pb); sum_b < best) best = sum_b, position = pb;
    if (const double sum_mid = q.sum(midpoint); sum_mid < best) best = sum_mid, position = midpoint;
    return {std::max(0.0, best) * inverse_weight, position};
  }

  // One pass: rates every edge, then collapses in order of rate. Returns the collapses made.
  std::size_t run_pass(int level, bool limited) {
    build_incidence();
    rate_edges();

    // Goal: half of the triangles over budget, about two per collapse.
    const std::size_t goal = std::max<std::size_t>(1, (alive_triangles_ - max_triangles_ + 1) / 2);
    double error_limit = std::numeric_limits<double>::infinity();
    if (limited) {
      const std::size_t goal_collapse = std::min(candidates_.size() - 1, goal / 2);
      error_limit = kPassErrorSlack * candidates_[goal_collapse].error();
    }
    // A collapse locks its two vertices, whose incidence lists are stale until the next
    // pass; the lists of their neighbours only lose dead triangles, which are skipped.
    ++pass_;
    survivors_.clear();
    std::size_t removed = 0, collapses = 0;
    for (std::size_t index = 0; index < candidates_.size(); ++index) {
      prefetch_ahead(index);
      const Candidate& candidate = candidates_[index];
      const std::uint32_t u = candidate.u, w = candidate.w;
      if (lock_[u] == pass_ || lock_[w] == pass_) continue;
      const std::size_t before = alive_triangles_;
      if (!try_collapse(u, w, level, error_limit)) {
        if (candidate.error() > error_limit) break;
        continue;
      }
      removed += before - alive_triangles_;
      survivors_.push_back(u);
      ++collapses;
      if (alive_triangles_ <= max_triangles_ || removed >= goal) break;
    }
    return collapses;
  }

  // The candidates are tried in order of error, so their vertices lie anywhere in memory,
  // and on meshes of millions of triangles a try waits on chains of cache misses (incidence,
  // then triangles, then their corners). Before trying candidate `index`, this asks for what
  // later tries will read, a chain's next link per step: the vertex data six candidates
  // ahead, the incidence slices three ahead, the triangles two ahead and their corners' positions
  // one ahead. It only reads, so the result does not change; quadric:512 on a 4.8 M-triangle
  // mesh spends about a third less time trying collapses.
  [[gnu::always_inline]] void prefetch_ahead(std::size_t index) const {  // see prefetch_object
    const std::size_t count = candidates_.size();
    if (index + 6 < count) {
      for (const std::uint32_t v : {candidates_[index + 6].u, candidates_[index + 6].w}) {
        __builtin_prefetch(&lock_[v]);
        __builtin_prefetch(&ref_start_[v]);
        __builtin_prefetch(&position_[v]);
        prefetch_object(quadric_[v]);
      }
    }
    if (index + 3 < count)
      for (const std::uint32_t v : {candidates_[index + 3].u, candidates_[index + 3].w})
        __builtin_prefetch(refs_.data() + ref_start_[v]);  // may be one past the end: a hint only
    if (index + 2 < count)
      for (const std::uint32_t v : {candidates_[index + 2].u, candidates_[index + 2].w})
        for (std::uint32_t i = ref_start_[v]; i < ref_start_[v + 1]; ++i) __builtin_prefetch(&triangles_[refs_[i]]);
    if (index + 1 < count) {
      const Candidate& next = candidates_[index + 1];
      if (lock_[next.u] == pass_ || lock_[next.w] == pass_) return;  // will be skipped
      for (const std::uint32_t v : {next.u, next.w})
        for (std::uint32_t i = ref_start_[v]; i < ref_start_[v + 1]; ++i) {
          const Triangle& triangle = triangles_[refs_[i]];
          if (triangle[0] != kDeadTriangle)
            for (const std::uint32_t corner : triangle) __builtin_prefetch(&position_[corner]);
        }
    }
  }

  // Sorted candidates for every edge. Only edges at a vertex that survived a collapse of the
  // last pass are rated anew: the others join the same two vertices, with the same quadrics
  // and positions, as before (an edge between vertices no collapse touched keeps a triangle,
  // as only triangles with both ends of a collapsed edge die), so their rates still hold.
  void rate_edges() {
    if (!rated_) {
      rated_ = true;
      candidates_.clear();
      for (std::uint32_t u = 0; u < position_.size(); ++u) {
        const std::uint32_t stamp = next_stamp();
        for_each_triangle(u, [&](std::uint32_t t) {
          for (const std::uint32_t w : triangles_[t])
            if (w > u && mark_[w] != stamp) {
              mark_[w] = stamp;
              candidates_.push_back({0, u, w});
            }
        });
      }
      rate_in_parallel(candidates_);
      sort_candidates(candidates_, scratch_);
      return;
    }
    // lock_[v] == pass_ marks the vertices of the last pass's collapses: the survivors, and
    // the removed vertices, which have no triangles left.
    std::erase_if(candidates_, [this](const Candidate& c) { return lock_[c.u] == pass_ || lock_[c.w] == pass_; });
    fresh_.clear();
    std::sort(survivors_.begin(), survivors_.end());  // memory order
    for (const std::uint32_t u : survivors_) {
      const std::uint32_t stamp = next_stamp();
      for_each_triangle(u, [&](std::uint32_t t) {
        for (const std::uint32_t w : triangles_[t])
          // An edge between two survivors is rated from the lower one.
          if (w != u && mark_[w] != stamp && !(lock_[w] == pass_ && w < u)) {
            mark_[w] = stamp;
            fresh_.push_back({0, u, w});
          }
      });
    }
    rate_in_parallel(fresh_);
    sort_candidates(fresh_, scratch_);
    scratch_.resize(candidates_.size() + fresh_.size());
    std::merge(candidates_.begin(), candidates_.end(), fresh_.begin(), fresh_.end(), scratch_.begin(),
               [](const Candidate& a, const Candidate& b) { return a.error_bits < b.error_bits; });
    candidates_.swap(scratch_);
  }

  // Each listed edge's error (placement is const: the edges are rated independently, and
  // the list keeps its order, so the result does not depend on the number of threads).
  void rate_in_parallel(std::vector<Candidate>& edges) const {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, edges.size(), 4096), [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        if (i + 8 < range.end())
          for (const std::uint32_t v : {edges[i + 8].u, edges[i + 8].w}) {
            __builtin_prefetch(&position_[v]);
            prefetch_object(quadric_[v]);
          }
        edges[i].error_bits = error_bits(placement(edges[i].u, edges[i].w).error);
      }
    });
  }

  // A fresh value for mark_, which no vertex holds yet.
  std::uint32_t next_stamp() {
    if (stamp_ == std::numeric_limits<std::uint32_t>::max()) {
      std::fill(mark_.begin(), mark_.end(), 0);
      stamp_ = 0;
    }
    return ++stamp_;
  }

  static int corner_of(const Triangle& t, std::uint32_t v) { return t[0] == v ? 0 : t[1] == v ? 1 : t[2] == v ? 2 : -1; }

  // Collapses edge (keep, remove) into keep if the rules of `level` allow it and its error
  // is within the limit; then locks every vertex around it for the rest of the pass.
  bool try_collapse(std::uint32_t keep, std::uint32_t remove, int level, double error_limit) {
    keep_triangles_.clear();
    remove_triangles_.clear();
    for_each_triangle(keep, [&](std::uint32_t t) { keep_triangles_.push_back(t); });
    std::size_t shared = 0;
    for_each_triangle(remove, [&](std::uint32_t t) {
      remove_triangles_.push_back(t);
      if (corner_of(triangles_[t], keep) >= 0) ++shared;
    });
    if (alive_triangles_ == shared) return false;  // would leave nothing
    if (level < 2 && !keeps_topology(keep, remove, shared)) return false;
    const Placement target = placement(keep, remove);
    if (!(target.error <= error_limit)) return false;
    if (level < 1 && flips(keep, remove, target.position)) return false;

    lock_[keep] = lock_[remove] = pass_;
    for (const std::uint32_t t : remove_triangles_) {
      Triangle& tri = triangles_[t];
      if (corner_of(tri, keep) >= 0) {
        tri[0] = kDeadTriangle;
        --alive_triangles_;
      } else {
        tri[corner_of(tri, remove)] = keep;
      }
    }
    quadric_[keep] += quadric_[remove];
    position_[keep] = target.position;
    moved_[keep] = 1;
    border_[keep] = border_[keep] | border_[remove];
    max_error_ = std::max(max_error_, target.error);
    ++collapses_;
    return true;
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

  // Surviving triangles, cleaned as every simplifier's (detail::clean_output_mesh).
  TriangleMesh output_mesh() const {
    std::vector<Vertex> world(position_.size());
    for (std::uint32_t v = 0; v < position_.size(); ++v) world[v] = world_position(v);
    std::vector<Triangle> alive;
    for (const Triangle& tri : triangles_)
      if (tri[0] != kDeadTriangle) alive.push_back(tri);
    return detail::clean_output_mesh(world, alive);
  }

  const TriangleMesh& input_;
  std::size_t max_triangles_;
  Vec3 center_ = Vec3::Zero();
  double diagonal_ = 0;

  // Per working vertex.
  std::vector<Vec3> position_;  // in the normalised frame
  std::vector<Quadric> quadric_;
  std::vector<VertexIndex> origin_;  // input vertex it started as
  std::vector<std::uint8_t> moved_, border_;
  std::vector<std::uint32_t> mark_, lock_;
  std::vector<std::uint32_t> ref_start_;  // #V + 1 offsets into refs_
  std::uint32_t stamp_ = 0;

  std::vector<Triangle> triangles_;  // [0] == kDeadTriangle once collapsed
  std::size_t alive_triangles_ = 0;
  std::vector<std::uint32_t> refs_;
  std::uint32_t pass_ = 0;
  std::vector<Candidate> candidates_, fresh_, scratch_;  // of the current pass
  std::vector<std::uint32_t> survivors_;  // of the last pass's collapses
  bool rated_ = false;
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
