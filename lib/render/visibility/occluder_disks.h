#pragma once
// Occluder disks (occluding-spheres paper §2): from a shading point x, a ball (O, R) at
// distance t = |O - x| hides the cone of directions within gamma of O - x, cos gamma =
// sqrt(t^2 - R^2) / t; a segment to y at distance z is occluded when the angle delta
// between y - x and O - x has cos delta > cos gamma, and t < z. Per shading point each
// ball costs one direction and one cosine; each segment then costs a dot product and two
// comparisons per ball.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "render/render_world.h"
#include "render/renderer.h"

namespace visproxy {

/// The balls of a set as occluder disks from one point, in structure-of-arrays form
/// (single precision, padded to a multiple of kDiskBlock with balls that hide nothing).
class OccluderDisks {
 public:
  static constexpr std::size_t kDiskBlock = 16;

  /// Starts over for the point `x` with unit normal `n`. Balls entirely behind the tangent
  /// plane (n . (O - x) <= -R) cannot hide a segment that leaves towards n and are left out.
  void reset(const Vertex& x, const Vertex& n);
  /// Adds the balls of `spheres`; `self_heuristic` skips those with t < 2R (the shading
  /// point's own object, §4.2). A ball holding x (t <= R) hides every segment longer than t.
  void add(const std::vector<Sphere>& spheres, bool self_heuristic);
  /// Pads the arrays; call after the last add() and before occludes().
  void finish();

  /// Whether the segment from x to `end` is occluded by a disk; adds the disks compared to
  /// `tests`.
  bool occludes(const Vertex& end, std::uint64_t& tests) const;
  std::size_t size() const { return count_; }

 private:
  Vertex x_ = Vertex::Zero(), n_ = Vertex::UnitZ();
  std::size_t count_ = 0;
  std::vector<float> ux_, uy_, uz_, cos_, t_;
};

/// Whether any of the n disks (n a multiple of OccluderDisks::kDiskBlock) hides unit
/// direction d at distance z: d . u_j > cos_j and t_j < z. Vectorised across disks,
/// blocks of 16 at a time, with AVX2 where the processor has it.
bool any_disk_occludes(const float* ux, const float* uy, const float* uz, const float* cos_gamma, const float* t, std::size_t n,
                       float dx, float dy, float dz, float z);
/// The same, one disk at a time with an early exit and no vectorisation: the baseline the
/// benchmark compares with.
bool any_disk_occludes_scalar(const float* ux, const float* uy, const float* uz, const float* cos_gamma, const float* t,
                              std::size_t n, float dx, float dy, float dz, float z);

/// The definition evaluated in double for one ball, for tests: cos delta > cos gamma and t < z,
/// with a ball holding x hiding every segment longer than t.
bool disk_occludes_reference(const Vertex& x, const Sphere& ball, const Vertex& end);

}  // namespace visproxy
