// The `spheres` visibility strategy: each instance's sphere-set proxy as occluder disks,
// instances without one (and, with --self-shadow exact, the own instance) traced exactly.

#include "visproxy/render/visibility/occluder_disks.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>

#include "visproxy/render/visibility/visibility.h"

namespace visproxy {

namespace {

// |w| in double, rounded to single precision: the same arithmetic in every form of the test.
float segment_length(const Vertex& w) { return static_cast<float>(std::sqrt(w.x() * w.x() + w.y() * w.y() + w.z() * w.z())); }

// Whether the segment w = (wx, wy, wz) of length z lies in a group's bound's cone (one with
// cos >= -1), in the single-precision arithmetic every scalar form of the test shares.
bool in_cone(const DiskGroup& group, float wx, float wy, float wz, float z) {
  return wx * group.ux + wy * group.uy + wz * group.uz > group.cos * z;
}

}  // namespace

void OccluderDisks::reset(const Vertex& x, const Vertex& n) {
  x_ = x, n_ = n;
  const Vertex helper = std::abs(n.x()) > 0.9 ? Vertex(0, 1, 0) : Vertex(1, 0, 0);
  tangent_ = n.cross(helper).normalized();
  bitangent_ = n.cross(tangent_);
  count_ = 0;
  disks_.clear();
  groups_.clear();
  grid_ = false;
}

namespace {

// The disks of `count` balls from x (unit normal n), stored in single precision at ux[i],
// ... t[i]. In double: v = O - x, |v|^2 and |v|^2 - R^2 (no cancellation in single
// precision), rounded to single; in single, 8 lanes at a time: t = |v| and its reciprocal,
// u = v / t and cos gamma = sqrt(|v|^2 - R^2) / t, each within 3 units of 2^-24 (the error
// OccluderDisks::kDiskTestError counts). A ball behind the tangent plane, or one the
// self-shadowing heuristic (when `heuristic`) skips, becomes a disk that hides nothing
// (cos gamma 2, as padding), so that the balls keep their places and both loops vectorise
// across balls with selects rather than branches. Returns the balls kept and, in `used`,
// one past the last.
__attribute__((target_clones("avx2", "default"))) std::size_t ball_disks(const Sphere* balls, std::size_t count, const Vertex& x,
                                                                        const Vertex& n, bool heuristic, float* __restrict ux,
                                                                        float* __restrict uy, float* __restrict uz,
                                                                        float* __restrict cos_gamma, float* __restrict t_out,
                                                                        std::size_t& used) {
  const double x0 = x.x(), x1 = x.y(), x2 = x.z(), n0 = n.x(), n1 = n.y(), n2 = n.z();
  const std::int64_t skip_close = heuristic ? -1 : 0;
  static_assert(sizeof(Sphere) == 4 * sizeof(double));
  const double* const b = balls[0].center.data();  // centre and radius: four packed doubles per ball
  // v, |v|^2 (negative for a ball left out) and |v|^2 - R^2 go into the output arrays first.
  for (std::size_t i = 0; i < count; ++i) {
    const double r = b[4 * i + 3];
    const double v0 = b[4 * i] - x0, v1 = b[4 * i + 1] - x1, v2 = b[4 * i + 2] - x2;
    const double along = n0 * v0 + n1 * v1 + n2 * v2;
    const double squared = v0 * v0 + v1 * v1 + v2 * v2;
    const std::int64_t behind = along <= -r ? -1 : 0;  // behind the tangent plane
    const std::int64_t close = squared < 4 * r * r ? -1 : 0;  // t < 2R
    const bool keep = (behind | (close & skip_close)) == 0;
    ux[i] = static_cast<float>(v0), uy[i] = static_cast<float>(v1), uz[i] = static_cast<float>(v2);
    t_out[i] = static_cast<float>(keep ? squared : -1.0);
    cos_gamma[i] = static_cast<float>(squared - r * r);
  }
  std::int32_t kept = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const float squared = t_out[i], rest = cos_gamma[i];
    const bool k = squared >= 0;
    const float t = std::sqrt(k ? squared : 0.0f), inverse = 1 / t;
    const bool outside = rest > 0;  // else x inside the ball: every direction
    const float a = outside ? ux[i] * inverse : 0.0f, c = outside ? uy[i] * inverse : 0.0f, d = outside ? uz[i] * inverse : 1.0f;
    const float cosine = outside ? std::sqrt(rest) * inverse : -2.0f;
    ux[i] = k ? a : 0.0f, uy[i] = k ? c : 0.0f, uz[i] = k ? d : 1.0f;
    cos_gamma[i] = k ? cosine : 2.0f;
    t_out[i] = k ? t : 0.0f;
    kept += k ? 1 : 0;
  }
  used = count;
  while (used > 0 && cos_gamma[used - 1] == 2.0f) --used;
  return static_cast<std::size_t>(kept);
}

}  // namespace

void OccluderDisks::add_balls(const Sphere* first, const Sphere* last, bool self_heuristic, const DiskGroup* cone) {
  DiskGroup group;
  const std::size_t base = disks_.ux.size();
  group.begin = static_cast<std::uint32_t>(base);
  const std::size_t count = static_cast<std::size_t>(last - first);
  const std::size_t room = (count + kDiskBlock - 1) / kDiskBlock * kDiskBlock;
  disks_.resize(base + room);
  std::size_t used = 0;
  const std::size_t kept = ball_disks(first, count, x_, n_, self_heuristic, disks_.ux.data() + base, disks_.uy.data() + base,
                                      disks_.uz.data() + base, disks_.cos.data() + base, disks_.t.data() + base, used);
  if (kept == 0) {
    disks_.resize(base);
    return;
  }
  // Up to the last ball kept, then padding to a whole block.
  disks_.resize(base + used);
  disks_.pad_to(kDiskBlock);
  group.count = static_cast<std::uint32_t>(used);
  count_ += kept;
  if (cone) group.ux = cone->ux, group.uy = cone->uy, group.uz = cone->uz, group.cos = cone->cos;
  groups_.push_back(group);
}

namespace {

// The cones of `count` clusters' bounds from x, as OccluderDisks::bound_cone() describes
// them: into ux[i], ..., cos[i] (cos -2: every direction). Selects rather than branches, so
// that the loop vectorises across clusters; bound_cone() is this for one cluster, so that
// every form of the test gets the same cones.
//
// A direction the float test passes for a held ball of half-angle g lies within
// g + spread of the ball's axis, spread = acos(cos g - e) - g, so within G + spread of the
// bound's (G its half-angle: the ball's cone lies in the bound's). The bound's own float
// test passes every direction whose exact cosine exceeds its stored cosine by e: the
// stored cosine is cos(G + spread) - e, rounded down. Angles are added through their
// cosines and sines, with g at its least (the least radius at the farthest distance).
__attribute__((target_clones("avx2", "default"))) void bound_cones(const double* __restrict cx, const double* __restrict cy,
                                                                  const double* __restrict cz, const double* __restrict cr,
                                                                  const double* __restrict cl, std::size_t count, const Vertex& x,
                                                                  float* __restrict ux, float* __restrict uy, float* __restrict uz,
                                                                  float* __restrict cos) {
  constexpr double e = OccluderDisks::kDiskTestError;
  const double x0 = x.x(), x1 = x.y(), x2 = x.z();
  for (std::size_t i = 0; i < count; ++i) {
    const double radius = cr[i];
    const double v0 = cx[i] - x0, v1 = cy[i] - x1, v2 = cz[i] - x2;
    const double t = std::sqrt(v0 * v0 + v1 * v1 + v2 * v2), inverse = 1 / t;
    const double sin_bound = radius * inverse, cos_bound = std::sqrt(std::max(0.0, (t - radius) * (t + radius))) * inverse;
    const double sin_least = std::min(std::max(cl[i] / (t + radius), 0.0), sin_bound);
    const double cos_least = std::sqrt(std::max(0.0, 1 - sin_least * sin_least));
    const double cos_reach = cos_least - e;  // cos(g + spread)
    const double sin_reach = std::sqrt(std::max(0.0, 1 - cos_reach * cos_reach));
    const double cos_rest = cos_bound * cos_least + sin_bound * sin_least;  // cos(G - g)
    const double sin_rest = std::max(0.0, sin_bound * cos_least - cos_bound * sin_least);
    // cos(G + spread) = cos((G - g) + (g + spread)); 2^-40 more for the double arithmetic.
    const double cos_cone = cos_rest * cos_reach - sin_rest * sin_reach - e - 0x1.0p-40;
    // Every direction where x lies in the bound (or on it) or the cone reaches all round.
    const bool some = t > radius && cos_cone > -1;
    // Stored rounded down: where rounding went up, the next float below (for 0: -2^-149).
    const float stored = static_cast<float>(cos_cone);
    const std::int32_t bits = std::bit_cast<std::int32_t>(stored);
    const std::int32_t down = stored == 0 ? std::int32_t{-0x7FFFFFFF} : bits - 1 + ((bits >> 31) & 2);
    const float below = static_cast<double>(stored) > cos_cone ? std::bit_cast<float>(down) : stored;
    ux[i] = some ? static_cast<float>(v0 * inverse) : 0.0f;
    uy[i] = some ? static_cast<float>(v1 * inverse) : 0.0f;
    uz[i] = some ? static_cast<float>(v2 * inverse) : 1.0f;
    cos[i] = some ? below : -2.0f;
  }
}

}  // namespace

DiskGroup OccluderDisks::bound_cone(const Sphere& bound, double least_radius) const {
  DiskGroup group;
  visproxy::bound_cones(&bound.center.x(), &bound.center.y(), &bound.center.z(), &bound.radius, &least_radius, 1, x_, &group.ux,
                        &group.uy, &group.uz, &group.cos);
  return group;
}

void OccluderDisks::bound_cones(const ClusterBounds& bounds, BoundCones& cones) const {
  const std::size_t count = bounds.size();
  cones.ux.resize(count), cones.uy.resize(count), cones.uz.resize(count), cones.cos.resize(count);
  visproxy::bound_cones(bounds.x.data(), bounds.y.data(), bounds.z.data(), bounds.radius.data(), bounds.least.data(), count, x_,
                        cones.ux.data(), cones.uy.data(), cones.uz.data(), cones.cos.data());
}

void OccluderDisks::add(const std::vector<Sphere>& spheres, bool self_heuristic) {
  add_balls(spheres.data(), spheres.data() + spheres.size(), self_heuristic, nullptr);
}

void OccluderDisks::add(const std::vector<Sphere>& spheres, const std::vector<SphereCluster>& clusters, bool self_heuristic) {
  thread_local ClusterBounds bounds;
  thread_local BoundCones cones;
  bounds.clear();
  for (const SphereCluster& cluster : clusters) bounds.push(cluster);
  bound_cones(bounds, cones);
  add(spheres, clusters, self_heuristic, cones, 0);
}

void OccluderDisks::add(const std::vector<Sphere>& spheres, const std::vector<SphereCluster>& clusters, bool self_heuristic,
                        const BoundCones& cones, std::size_t offset) {
  const std::size_t count = clusters.size();
  const auto cone = [&](std::size_t c) {
    DiskGroup group;
    group.ux = cones.ux[offset + c], group.uy = cones.uy[offset + c], group.uz = cones.uz[offset + c], group.cos = cones.cos[offset + c];
    return group;
  };
  for (std::size_t c = 0; c < count; ++c) {
    const SphereCluster& cluster = clusters[c];
    // Every ball of a bound behind the tangent plane is behind it too.
    if (behind(cluster.bound)) {
      c += cluster.children;
      continue;
    }
    if (cluster.children == 0) {
      const DiskGroup own = cone(c);
      add_balls(spheres.data() + cluster.begin, spheres.data() + cluster.end, self_heuristic, &own);
      continue;
    }
    // A head: its cone, then the groups of the clusters it heads that keep a ball.
    const std::size_t head = groups_.size();
    groups_.push_back(cone(c));
    for (std::size_t k = 0; k < cluster.children; ++k) {
      const SphereCluster& child = clusters[c + 1 + k];
      const DiskGroup own = cone(c + 1 + k);
      add_balls(spheres.data() + child.begin, spheres.data() + child.end, self_heuristic, &own);
    }
    c += cluster.children;
    groups_[head].span = static_cast<std::uint32_t>(groups_.size() - head - 1);
    if (groups_[head].span == 0) groups_.pop_back();
  }
}

namespace {

// The cell of a projected point (p in [-1, 1]^2 for directions in front of the plane).
int grid_cell(double px, double py) {
  constexpr int side = OccluderDisks::kGridSide;
  const int cx = std::clamp(static_cast<int>((px + 1) * 0.5 * side), 0, side - 1);
  const int cy = std::clamp(static_cast<int>((py + 1) * 0.5 * side), 0, side - 1);
  return cy * side + cx;
}

}  // namespace

void OccluderDisks::finish(bool grid) {
  grid_ = grid && count_ > 0;
  if (grid_) {
    // Stereographic projection from -n: a direction d maps to (d.t, d.b) / (1 + d.n), the
    // front hemisphere into the unit disc, and a cap of axis u and half-angle gamma to the
    // disc whose diameter joins the images of the cap's two points on u's meridian, at
    // signed radii tan((theta -+ gamma) / 2) (theta: u's angle from n). Caps that hold -n
    // (theta + gamma >= pi) or x (cos gamma < -1) reach every cell. Each cap goes into
    // the cells its disc's bounding square meets, grown by a rounding margin; the cells'
    // lists are laid out one after another by a counting sort.
    constexpr int side = kGridSide, cells = side * side;
    thread_local std::vector<std::array<std::int16_t, 4>> rectangles;  // x0, x1, y0, y1 per disk; x0 < 0: every cell
    const std::size_t entries_in = disks_.ux.size();
    rectangles.resize(entries_in);
    cell_start_.assign(cells + 1, 0);
    for (std::size_t j = 0; j < entries_in; ++j) {
      std::array<std::int16_t, 4>& r = rectangles[j];
      r = {0, side - 1, 0, side - 1};
      const double cos_gamma = disks_.cos[j];
      if (cos_gamma > 1) {
        r = {1, 0, 1, 0};  // padding: no cell
        continue;
      }
      if (cos_gamma < -1) continue;  // x inside the ball
      const Vertex u(disks_.ux[j], disks_.uy[j], disks_.uz[j]);
      const double sin_gamma = std::sqrt(std::max(0.0, 1 - cos_gamma * cos_gamma));
      const double cos_theta = std::clamp(u.dot(n_), -1.0, 1.0), sin_theta = std::sqrt(std::max(0.0, 1 - cos_theta * cos_theta));
      const double cos_far = cos_theta * cos_gamma - sin_theta * sin_gamma, sin_far = sin_theta * cos_gamma + cos_theta * sin_gamma;
      if (cos_far <= -1 + 1e-6 || (sin_far <= 0 && cos_far < 0)) continue;  // theta + gamma >= pi: the cap holds -n
      const double cos_near = cos_theta * cos_gamma + sin_theta * sin_gamma, sin_near = sin_theta * cos_gamma - cos_theta * sin_gamma;
      const double r_far = sin_far / (1 + cos_far), r_near = sin_near / (1 + cos_near);  // tan of half the angles
      const double azimuth_x = u.dot(tangent_), azimuth_y = u.dot(bitangent_);
      const double length = std::sqrt(azimuth_x * azimuth_x + azimuth_y * azimuth_y);
      const double ax = length > 0 ? azimuth_x / length : 1, ay = length > 0 ? azimuth_y / length : 0;
      // The margin covers the single-precision comparison: d . u > cos gamma in floats can hold
      // up to about 2e-7 / sin gamma radians outside the cap (the projection at most doubles it).
      const double centre = 0.5 * (r_far + r_near);
      const double radius = 0.5 * std::abs(r_far - r_near) + 1e-4 * (1 + std::abs(centre)) + 1e-6 / std::max(sin_gamma, 1e-4);
      const double cx = centre * ax, cy = centre * ay;
      if (cx - radius > 1 || cx + radius < -1 || cy - radius > 1 || cy + radius < -1) {
        r = {1, 0, 1, 0};  // misses the front: no cell
        continue;
      }
      auto cell = [](double v) { return static_cast<std::int16_t>(std::clamp(static_cast<int>(std::floor((v + 1) * 0.5 * side)), 0, side - 1)); };
      r = {cell(cx - radius), cell(cx + radius), cell(cy - radius), cell(cy + radius)};
    }
    for (std::size_t j = 0; j < entries_in; ++j) {
      const auto& r = rectangles[j];
      for (int y = r[2]; y <= r[3]; ++y)
        for (int x = r[0]; x <= r[1]; ++x) ++cell_start_[static_cast<std::size_t>(y * side + x) + 1];
    }
    for (int c = 0; c < cells; ++c) cell_start_[static_cast<std::size_t>(c) + 1] += cell_start_[static_cast<std::size_t>(c)];
    const std::size_t entries = cell_start_.back();
    cells_.ux.resize(entries), cells_.uy.resize(entries), cells_.uz.resize(entries), cells_.cos.resize(entries), cells_.t.resize(entries);
    thread_local std::vector<std::size_t> next;
    next.assign(cell_start_.begin(), cell_start_.end() - 1);
    for (std::size_t j = 0; j < entries_in; ++j) {
      const auto& r = rectangles[j];
      for (int y = r[2]; y <= r[3]; ++y)
        for (int x = r[0]; x <= r[1]; ++x) {
          const std::size_t slot = next[static_cast<std::size_t>(y * side + x)]++;
          cells_.ux[slot] = disks_.ux[j], cells_.uy[slot] = disks_.uy[j], cells_.uz[slot] = disks_.uz[j];
          cells_.cos[slot] = disks_.cos[j], cells_.t[slot] = disks_.t[j];
        }
    }
  }
}

bool OccluderDisks::occludes(const Vertex& end, std::uint64_t& tests) const {
  if (count_ == 0) return false;
  return occludes_groups(end, 0, groups_.size(), tests);
}

bool OccluderDisks::occludes_groups(const Vertex& end, std::size_t first, std::size_t last, std::uint64_t& tests) const {
  if (first >= last) return false;
  const Vertex w = end - x_;
  const float zf = segment_length(w);
  if (!(zf > 0)) return false;
  const float dx = static_cast<float>(w.x()), dy = static_cast<float>(w.y()), dz = static_cast<float>(w.z());
  for (std::size_t g = first; g < last; ++g) {
    const DiskGroup& group = groups_[g];
    if (group.cos >= -1) {
      ++tests;
      if (!in_cone(group, dx, dy, dz, zf)) {
        g += group.span;
        continue;
      }
    }
    if (group.span > 0) continue;
    if (group_disks_occlude(g, dx, dy, dz, zf, tests)) return true;
  }
  return false;
}

bool OccluderDisks::group_disks_occlude(std::size_t g, float wx, float wy, float wz, float z, std::uint64_t& tests) const {
  const DiskGroup& group = groups_[g];
  tests += group.count;
  const std::size_t b = group.begin, n = (group.count + kDiskBlock - 1) / kDiskBlock * kDiskBlock;
  return any_disk_occludes(disks_.ux.data() + b, disks_.uy.data() + b, disks_.uz.data() + b, disks_.cos.data() + b, disks_.t.data() + b, n,
                           wx, wy, wz, z);
}

__attribute__((target_clones("avx2", "default"))) bool any_disk_occludes(const float* ux, const float* uy, const float* uz,
                                                                        const float* cos_gamma, const float* t, std::size_t n,
                                                                        float wx, float wy, float wz, float z) {
  constexpr std::size_t block = OccluderDisks::kDiskBlock;
  for (std::size_t base = 0; base < n; base += block) {
    int hidden = 0;
    for (std::size_t j = base; j < base + block; ++j)
      hidden |= static_cast<int>(wx * ux[j] + wy * uy[j] + wz * uz[j] > cos_gamma[j] * z) & static_cast<int>(t[j] < z);
    if (hidden != 0) return true;
  }
  return false;
}

namespace {

// w = end - x in single precision and z = |w| rounded from double, for m segments: the
// inputs of the disk comparisons. Vectorised across segments.
__attribute__((target_clones("avx2", "default"))) void segments_to_floats(const Vertex* __restrict ends, std::size_t m, const Vertex& x,
                                                                         float* __restrict wx, float* __restrict wy, float* __restrict wz,
                                                                         float* __restrict z) {
  const double x0 = x.x(), x1 = x.y(), x2 = x.z();
  const double* const e = ends[0].data();  // Vertex is three packed doubles
  static_assert(sizeof(Vertex) == 3 * sizeof(double));
  for (std::size_t k = 0; k < m; ++k) {
    const double w0 = e[3 * k] - x0, w1 = e[3 * k + 1] - x1, w2 = e[3 * k + 2] - x2;
    wx[k] = static_cast<float>(w0), wy[k] = static_cast<float>(w1), wz[k] = static_cast<float>(w2);
    z[k] = static_cast<float>(std::sqrt(w0 * w0 + w1 * w1 + w2 * w2));
  }
}

}  // namespace

void OccluderDisks::occludes(std::span<const Vertex> ends, std::span<std::uint8_t> hidden, std::uint64_t& tests) const {
  if (count_ == 0) {
    std::fill(hidden.begin(), hidden.end(), std::uint8_t{0});
    return;
  }
  thread_local std::vector<float> wx, wy, wz, z;
  thread_local std::vector<std::int32_t> any;
  thread_local std::vector<std::uint32_t> order, cell_of;
  thread_local std::vector<std::size_t> starts;
  const std::size_t m = ends.size();
  if (m == 0) return;
  if (!grid_) {
    // Padded to whole chunks of kChunk segments with segments of length 0, which nothing hides.
    const std::size_t padded = (m + kChunk - 1) / kChunk * kChunk;
    wx.resize(padded), wy.resize(padded), wz.resize(padded), z.resize(padded), any.assign(padded, 0);
    float *const px = wx.data(), *const py = wy.data(), *const pz = wz.data(), *const pd = z.data();
    std::int32_t* const pa = any.data();
    segments_to_floats(ends.data(), m, x_, px, py, pz, pd);
    for (std::size_t k = m; k < padded; ++k) px[k] = py[k] = pz[k] = pd[k] = 0;
    tests += disk_groups_hide_chunks(groups_.data(), groups_.size(), disks_.ux.data(), disks_.uy.data(), disks_.uz.data(), disks_.cos.data(),
                                     disks_.t.data(), px, py, pz, pd, m, pa);
    std::uint8_t* const out = hidden.data();
    for (std::size_t k = 0; k < m; ++k) out[k] = pd[k] > 0 && pa[k] != 0 ? 1 : 0;
    return;
  }
  // The grid: segments sorted by the cell of their direction (counting sort), then each
  // cell's disks against each cell's segments, disk by disk across the segments. Segments
  // that do not leave in front of the tangent plane take every disk.
  constexpr std::size_t cells = static_cast<std::size_t>(kGridSide) * kGridSide;
  wx.resize(m), wy.resize(m), wz.resize(m), z.resize(m), any.assign(m, 0);
  cell_of.resize(m), order.resize(m);
  starts.assign(cells + 2, 0);
  for (std::size_t k = 0; k < m; ++k) {
    const Vertex w = ends[k] - x_;
    // Only directions in front of the tangent plane project into the unit disc, where the
    // margin holds; the others are compared with every disk.
    const double length = w.norm(), along = w.dot(n_), up = length + along;
    cell_of[k] = along > 0 ? static_cast<std::uint32_t>(grid_cell(w.dot(tangent_) / up, w.dot(bitangent_) / up))
                           : static_cast<std::uint32_t>(cells);
    ++starts[cell_of[k] + 1];
  }
  for (std::size_t c = 0; c <= cells; ++c) starts[c + 1] += starts[c];
  {
    thread_local std::vector<std::size_t> next;
    next.assign(starts.begin(), starts.end() - 1);
    for (std::size_t k = 0; k < m; ++k) {
      const std::size_t slot = next[cell_of[k]]++;
      order[slot] = static_cast<std::uint32_t>(k);
      const Vertex w = ends[k] - x_;
      wx[slot] = static_cast<float>(w.x()), wy[slot] = static_cast<float>(w.y()), wz[slot] = static_cast<float>(w.z());
      z[slot] = segment_length(w);
    }
  }
  for (std::size_t c = 0; c <= cells; ++c) {
    const std::size_t begin = starts[c], count = starts[c + 1] - begin;
    if (count == 0) continue;
    const Soa& source = c < cells ? cells_ : disks_;
    const std::size_t first = c < cells ? cell_start_[c] : 0, disks = c < cells ? cell_start_[c + 1] - first : disks_.ux.size();
    tests += disks * count;
    disks_hide_segments(source.ux.data() + first, source.uy.data() + first, source.uz.data() + first, source.cos.data() + first,
                        source.t.data() + first, disks, wx.data() + begin, wy.data() + begin, wz.data() + begin, z.data() + begin, count,
                        any.data() + begin);
  }
  for (std::size_t slot = 0; slot < m; ++slot) hidden[order[slot]] = z[slot] > 0 && any[slot] != 0 ? 1 : 0;
}

__attribute__((target_clones("avx2", "default"))) void disks_hide_segments(const float* __restrict ux, const float* __restrict uy,
                                                                          const float* __restrict uz,
                                                                          const float* __restrict cos_gamma, const float* __restrict t,
                                                                          std::size_t n, const float* __restrict wx,
                                                                          const float* __restrict wy, const float* __restrict wz,
                                                                          const float* __restrict z, std::size_t m,
                                                                          std::int32_t* __restrict hidden) {
  for (std::size_t j = 0; j < n; ++j) {
    const float a = ux[j], b = uy[j], c = uz[j], cg = cos_gamma[j], tj = t[j];
    // Selects rather than a short-circuit, so that the loop vectorises.
    for (std::size_t k = 0; k < m; ++k) {
      const float dot = wx[k] * a + wy[k] * b + wz[k] * c;
      const std::int32_t in_cone = dot > cg * z[k] ? -1 : 0;
      const std::int32_t before = tj < z[k] ? -1 : 0;
      hidden[k] = hidden[k] | (in_cone & before);
    }
  }
}

namespace {

using Floats = float __attribute__((vector_size(4 * kChunk)));
using Ints = std::int32_t __attribute__((vector_size(4 * kChunk)));
static_assert(sizeof(Floats) / sizeof(float) == kChunk);

// Whether any lane of a comparison's result (each lane 0 or -1) is set: the lanes ORed as
// 64-bit words, which compiles to a vector test rather than a lane-by-lane extraction.
inline bool any_lane(Ints v) {
  std::uint64_t words[sizeof(Ints) / 8];
  std::memcpy(words, &v, sizeof words);
  std::uint64_t all = 0;
  for (std::uint64_t w : words) all |= w;
  return all != 0;
}

}  // namespace

__attribute__((target_clones("avx2", "default"))) std::uint64_t disk_groups_hide_chunks(
    const DiskGroup* groups, std::size_t group_count, const float* __restrict ux, const float* __restrict uy, const float* __restrict uz,
    const float* __restrict cos_gamma, const float* __restrict t, const float* __restrict wx, const float* __restrict wy,
    const float* __restrict wz, const float* __restrict z, std::size_t m, std::int32_t* __restrict hidden) {
  std::uint64_t tests = 0;
  for (std::size_t base = 0; base < m; base += kChunk) {
    const std::uint64_t lanes = std::min(kChunk, m - base);
    Floats x, y, w, d;
    std::memcpy(&x, wx + base, sizeof x), std::memcpy(&y, wy + base, sizeof y), std::memcpy(&w, wz + base, sizeof w);
    std::memcpy(&d, z + base, sizeof d);
    Ints any;
    std::memcpy(&any, hidden + base, sizeof any);
    for (std::size_t g = 0; g < group_count; ++g) {
      const DiskGroup& group = groups[g];
      if (group.cos >= -1) {
        tests += lanes;
        const Ints in_cone = x * group.ux + y * group.uy + w * group.uz > group.cos * d;
        if (!any_lane(in_cone & ~any)) {
          g += group.span;
          continue;
        }
      }
      if (group.span > 0) continue;
      tests += lanes * group.count;
      for (std::size_t j = group.begin, end = group.begin + group.count; j < end; ++j)
        any |= (x * ux[j] + y * uy[j] + w * uz[j] > cos_gamma[j] * d) & (t[j] < d);
      if (!any_lane(~any)) break;
    }
    std::memcpy(hidden + base, &any, sizeof any);
  }
  return tests;
}

__attribute__((optimize("no-tree-vectorize"))) bool any_disk_occludes_scalar(const float* ux, const float* uy, const float* uz,
                                                                             const float* cos_gamma, const float* t, std::size_t n,
                                                                             float wx, float wy, float wz, float z) {
  for (std::size_t j = 0; j < n; ++j)
    if (t[j] < z && wx * ux[j] + wy * uy[j] + wz * uz[j] > cos_gamma[j] * z) return true;
  return false;
}

bool disk_occludes_reference(const Vertex& x, const Sphere& ball, const Vertex& end) {
  const Vertex v = ball.center - x, w = end - x;
  const double t = v.norm(), z = w.norm();
  if (!(t < z)) return false;
  if (t <= ball.radius) return true;
  const double cos_gamma = std::sqrt(t * t - ball.radius * ball.radius) / t;
  return v.dot(w) / (t * z) > cos_gamma;
}

DiskPartition prepare_occluder_disks(OccluderDisks& disks, const RenderWorld& world, std::size_t instances, const SurfaceHit& hit,
                                     const Vertex& position, bool trace_own, bool own_heuristic, std::size_t grid_from,
                                     bool clusters, const ClusterBounds* bounds) {
  DiskPartition partition;
  disks.reset(position, hit.normal);
  thread_local BoundCones cones;
  if (clusters && bounds) disks.bound_cones(*bounds, cones);
  std::size_t offset = 0;  // the instance's first cluster in `bounds`
  const unsigned own_bit = hit.instance >= 0 ? instance_bit(static_cast<std::size_t>(hit.instance)) : 0u;
  bool own_traced = false, shared = false;  // the own instance traced; another traced instance has its bit
  for (std::size_t i = 0; i < instances; ++i) {
    const bool is_own = static_cast<int>(i) == hit.instance;
    const std::vector<Sphere>& balls = world.occluder_spheres(i);
    const std::size_t first = offset;
    offset += world.occluder_clusters(i).size();
    if (balls.empty() || (is_own && trace_own)) {
      // Traced exactly.
      partition.traced |= instance_bit(i);
      own_traced = own_traced || is_own;
      shared = shared || (!is_own && instance_bit(i) == own_bit);
      continue;
    }
    if (clusters && bounds)
      disks.add(balls, world.occluder_clusters(i), is_own && own_heuristic, cones, first);
    else if (clusters)
      disks.add(balls, world.occluder_clusters(i), is_own && own_heuristic);
    else
      disks.add(balls, is_own && own_heuristic);
    partition.disks |= instance_bit(i);
  }
  if (own_traced && !shared && hit.own_mesh_behind) partition.own_alone = own_bit;
  disks.finish(disks.size() >= grid_from);
  return partition;
}

OccluderDiskIndex::OccluderDiskIndex(const RenderWorld& world, std::size_t instances, std::size_t lazy_from)
    : world_(&world), instances_(instances), has_spheres_(instances, 0) {
  std::size_t with = 0;
  for (std::size_t i = 0; i < instances; ++i) {
    const std::vector<Sphere>& balls = world.occluder_spheres(i);
    const std::size_t bit = static_cast<std::size_t>(std::countr_zero(instance_bit(i)));
    if (balls.empty()) {
      ++without_spheres_[bit], without_bits_ |= instance_bit(i);
      continue;
    }
    has_spheres_[i] = 1, ++with;
    ++with_spheres_[bit], with_bits_ |= instance_bit(i);
  }
  lazy_ = with >= lazy_from;
  if (!lazy_) {
    // Points make every cluster's cone at once (prepare_occluder_disks).
    for (std::size_t i = 0; i < instances; ++i)
      for (const SphereCluster& cluster : world.occluder_clusters(i)) bounds_.push(cluster);
    return;
  }
  std::vector<BoundingBox> boxes;
  for (std::size_t i = 0; i < instances; ++i) {
    const std::vector<Sphere>& balls = world.occluder_spheres(i);
    const std::vector<SphereCluster>& clusters = world.occluder_clusters(i);
    for (std::size_t c = 0; c < clusters.size(); ++c) {
      if (clusters[c].children > 0) continue;
      BoundingBox box;
      for (std::uint32_t k = clusters[c].begin; k < clusters[c].end; ++k) {
        box.extend(balls[k].center - Vertex::Constant(balls[k].radius));
        box.extend(balls[k].center + Vertex::Constant(balls[k].radius));
      }
      runs_.push_back({static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(c)});
      boxes.push_back(box);
    }
  }
  tree_ = BoxTree(boxes, {});
}

DiskPartition PointDisks::begin(const OccluderDiskIndex& index, const SurfaceHit& hit, const Vertex& position, bool trace_own,
                                bool own_heuristic, std::size_t grid_from, bool clusters) {
  index_ = &index;
  if (!index.lazy())
    return prepare_occluder_disks(disks_, *index.world_, index.instances_, hit, position, trace_own, own_heuristic, grid_from,
                                  clusters, &index.bounds_);
  // As prepare_occluder_disks() sets the bits, from the counts per bit: only the own
  // instance's bit can differ from the scene's.
  disks_.reset(position, hit.normal);
  disks_.finish(false);
  x_ = position, own_ = hit.instance, own_heuristic_ = own_heuristic, clusters_ = clusters;
  DiskPartition partition{.traced = index.without_bits_, .disks = index.with_bits_};
  skip_own_ = false;
  if (own_ >= 0) {
    const auto own = static_cast<std::size_t>(own_);
    const unsigned bit = instance_bit(own);
    std::uint32_t without = index.without_spheres_[static_cast<std::size_t>(std::countr_zero(bit))];
    std::uint32_t with = index.with_spheres_[static_cast<std::size_t>(std::countr_zero(bit))];
    bool own_traced = false;
    std::uint32_t others_traced = without;  // traced instances on the own bit besides the own one
    if (!index.has_spheres_[own]) {
      own_traced = true, --others_traced;
    } else if (trace_own) {
      --with, skip_own_ = true;
      own_traced = true;
    }
    partition.traced = (partition.traced & ~bit) | (without > 0 || own_traced ? bit : 0u);
    if (own_traced && others_traced == 0 && hit.own_mesh_behind) partition.own_alone = bit;
    partition.disks = (partition.disks & ~bit) | (with > 0 ? bit : 0u);
  }
  if (seen_.size() != index.runs_.size())
    seen_.assign(index.runs_.size(), 0), group_.resize(index.runs_.size()), cone_.resize(index.runs_.size()), stamp_ = 0;
  if (++stamp_ == 0) std::fill(seen_.begin(), seen_.end(), 0), stamp_ = 1;  // after 2^32 points
  return partition;
}

namespace {
constexpr std::uint32_t kNoGroup = ~std::uint32_t{0}, kNotMade = kNoGroup - 1;
}  // namespace

bool PointDisks::occludes(const Vertex& end, std::uint64_t& tests, std::uint64_t* clusters) {
  if (!index_->lazy()) return disks_.occludes(end, tests);
  const Vertex w = end - x_;
  const double margin = std::ldexp(w.norm(), -8);
  // The slab test of the segment from x lengthened by 2^-8 against the boxes grown by the
  // margin, with the reciprocals of its direction made once.
  const Vertex d = (1 + std::ldexp(1.0, -8)) * w;
  const Vertex inverse(1 / d.x(), 1 / d.y(), 1 / d.z());
  const RenderWorld& world = *index_->world_;
  // The segment as occludes_groups() compares it with a group's cone.
  const float zf = segment_length(w);
  if (!(zf > 0)) return false;
  const float dx = static_cast<float>(w.x()), dy = static_cast<float>(w.y()), dz = static_cast<float>(w.z());
  return index_->tree_.any_along(
      w, [&](const BoundingBox& box, const Sphere&) {
        double t0 = 0, t1 = 1;
        for (int a = 0; a < 3; ++a) {
          const double low = box.min[a] - margin, high = box.max[a] + margin;
          if (d[a] == 0) {
            if (x_[a] < low || x_[a] > high) return false;
            continue;
          }
          double near = (low - x_[a]) * inverse[a], far = (high - x_[a]) * inverse[a];
          if (inverse[a] < 0) std::swap(near, far);
          t0 = std::max(t0, near), t1 = std::min(t1, far);
          if (t0 > t1) return false;
        }
        return true;
      },
      [&](std::uint32_t r) {
        const OccluderDiskIndex::Run run = index_->runs_[r];
        const bool own = static_cast<int>(run.instance) == own_;
        if (own && skip_own_) return false;
        if (clusters) ++*clusters;
        const SphereCluster& cluster = world.occluder_clusters(run.instance)[run.cluster];
        if (seen_[r] != stamp_) {
          seen_[r] = stamp_;
          if (clusters_) {
            group_[r] = disks_.behind(cluster.bound) ? kNoGroup : kNotMade;
            cone_[r] = disks_.bound_cone(cluster.bound, cluster.least_radius);
          } else {
            group_[r] = kNotMade, cone_[r] = DiskGroup{};
          }
        }
        if (group_[r] == kNoGroup) return false;
        const DiskGroup& cone = cone_[r];
        if (cone.cos >= -1) {
          ++tests;
          if (!in_cone(cone, dx, dy, dz, zf)) return false;
        }
        if (group_[r] == kNotMade) {
          const std::vector<Sphere>& balls = world.occluder_spheres(run.instance);
          const std::size_t first = disks_.groups();
          disks_.add_run(balls.data() + cluster.begin, balls.data() + cluster.end, own && own_heuristic_, clusters_ ? &cone : nullptr);
          group_[r] = disks_.groups() > first ? static_cast<std::uint32_t>(first) : kNoGroup;
        }
        return group_[r] != kNoGroup && disks_.group_disks_occlude(group_[r], dx, dy, dz, zf, tests);
      });
}

void PointDisks::occludes(std::span<const Vertex> ends, std::span<std::uint8_t> hidden, std::uint64_t& tests,
                          std::uint64_t* clusters) {
  if (!index_->lazy()) return disks_.occludes(ends, hidden, tests);
  for (std::size_t k = 0; k < ends.size(); ++k) hidden[k] = occludes(ends[k], tests, clusters) ? 1 : 0;
}

DiskPartition begin_point_disks(PointDisks& disks, ExactConnections& traced, const OccluderDiskIndex& index, const RenderWorld& world,
                                const RenderOptions& options, const SurfaceHit& hit, const Vertex& position, bool trace_own) {
  const DiskPartition partition = disks.begin(index, hit, position, trace_own, options.self_shadow == SelfShadow::heuristic,
                                              options.disk_grid_from, options.disk_clusters);
  traced.begin(world, position, partition.traced);
  traced.skip_own_where_clear(hit, partition.own_alone);
  return partition;
}

namespace {

class OccluderDiskVisibility;

class OccluderDiskPoint final : public PointVisibility {
 public:
  explicit OccluderDiskPoint(const OccluderDiskVisibility& shared) : shared_(shared) {}
  void begin(const ShadingPoint& point) override;
  double to_light(const Vertex& end) override { return connection(end); }
  double connection(const Vertex& end) override;
  void connections(std::span<const Vertex> ends, std::span<const unsigned> end_shells, std::span<double> out) override;

 private:
  const OccluderDiskVisibility& shared_;
  ShadingPoint point_;
  PointDisks disks_;
  ExactConnections traced_;  // the instances traced exactly
  bool any_traced_ = false;
  std::vector<Vertex> rest_;
  std::vector<std::size_t> rest_index_;
  std::vector<std::uint8_t> blocked_;
  std::vector<unsigned> lanes_;
  std::vector<std::uint8_t> hidden_;
};

class OccluderDiskVisibility final : public Visibility {
 public:
  explicit OccluderDiskVisibility(const VisibilityContext& context)
      : context_(context), index_(context.world, context.scene.instances.size(), context.options.disk_lazy_from) {}
  std::unique_ptr<PointVisibility> point_visibility() override { return std::make_unique<OccluderDiskPoint>(*this); }

 private:
  friend class OccluderDiskPoint;
  VisibilityContext context_;
  OccluderDiskIndex index_;
};

void OccluderDiskPoint::begin(const ShadingPoint& point) {
  point_ = point;
  const RenderOptions& options = shared_.context_.options;
  const DiskPartition partition = begin_point_disks(disks_, traced_, shared_.index_, shared_.context_.world, options, *point.hit,
                                                    point.position, options.self_shadow == SelfShadow::exact);
  any_traced_ = partition.traced != 0;
}

double OccluderDiskPoint::connection(const Vertex& end) {
  RenderStats& stats = *point_.stats;
  ++stats.proxy_tests;
  if (disks_.occludes(end, stats.disks.tests, &stats.disks.clusters)) return 0;
  const unsigned lane = traced_.lane(end);
  if (lane == 0) return 1;
  ++stats.exact_tests;
  return shared_.context_.world.mesh_blocks(point_.position, end, {.skip = -1, .only = -1, .bits = lane}) ? 0 : 1;
}

void OccluderDiskPoint::connections(std::span<const Vertex> ends, std::span<const unsigned> end_shells, std::span<double> out) {
  RenderStats& stats = *point_.stats;
  rest_.clear(), rest_index_.clear(), lanes_.clear();
  stats.proxy_tests += ends.size();
  const RenderWorld& world = shared_.context_.world;
  hidden_.resize(ends.size());
  disks_.occludes(ends, hidden_, stats.disks.tests, &stats.disks.clusters);
  const std::uint8_t* const hidden = hidden_.data();
  for (std::size_t i = 0; i < ends.size(); ++i) out[i] = hidden[i] ? 0 : 1;
  if (!any_traced_) return;
  for (std::size_t i = 0; i < ends.size(); ++i) {
    if (hidden[i]) continue;
    const unsigned lane = traced_.lane(ends[i], end_shells.empty() ? nullptr : &end_shells[i]);
    if (lane == 0) continue;
    rest_.push_back(ends[i]), rest_index_.push_back(i), lanes_.push_back(lane);
  }
  if (rest_.empty()) return;
  stats.exact_tests += rest_.size();
  blocked_.resize(rest_.size());
  if (shared_.context_.options.group_connections) {
    world.mesh_blocks(point_.position, rest_, blocked_, {}, lanes_);
  } else {
    for (std::size_t k = 0; k < rest_.size(); ++k)
      blocked_[k] = world.mesh_blocks(point_.position, rest_[k], {.skip = -1, .only = -1, .bits = lanes_[k]});
  }
  for (std::size_t k = 0; k < rest_.size(); ++k)
    if (blocked_[k]) out[rest_index_[k]] = 0;
}

}  // namespace

std::unique_ptr<Visibility> make_occluder_disk_visibility(const VisibilityContext& context) {
  return std::make_unique<OccluderDiskVisibility>(context);
}

}  // namespace visproxy
