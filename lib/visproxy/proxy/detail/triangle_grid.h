#pragma once
// Private to lib/visproxy/proxy/detail: a uniform grid over the current triangles of a
// conservative decimation, for its self-intersection test. Triangles are never removed
// from it: dead ones are skipped on query. Boxes that span more than kMaxCells cells go to
// a list that every query visits instead.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy::detail {

class TriangleGrid {
 public:
  void reset(double cell_size) {
    cell_size_ = cell_size;
    cells_.clear();
    large_.clear();
  }

  void insert(std::uint32_t triangle, const BoundingBox& box) {
    const CellRange range = cells_of(box);
    if (range.count() > kMaxCells) {
      large_.push_back(triangle);
      return;
    }
    for (std::int64_t z = range.lo[2]; z <= range.hi[2]; ++z)
      for (std::int64_t y = range.lo[1]; y <= range.hi[1]; ++y)
        for (std::int64_t x = range.lo[0]; x <= range.hi[0]; ++x) cells_[key(x, y, z)].push_back(triangle);
  }

  /// Calls f(triangle) for every triangle that may overlap `box` (with repeats: the caller
  /// deduplicates) until f returns false.
  template <typename F>
  void for_triangles_near(const BoundingBox& box, F f) const {
    for (const std::uint32_t t : large_)
      if (!f(t)) return;
    const CellRange range = cells_of(box);
    if (range.count() > kMaxCells) {
      for (const auto& cell : cells_)
        for (const std::uint32_t t : cell.second)
          if (!f(t)) return;
      return;
    }
    for (std::int64_t z = range.lo[2]; z <= range.hi[2]; ++z)
      for (std::int64_t y = range.lo[1]; y <= range.hi[1]; ++y)
        for (std::int64_t x = range.lo[0]; x <= range.hi[0]; ++x) {
          const auto it = cells_.find(key(x, y, z));
          if (it == cells_.end()) continue;
          for (const std::uint32_t t : it->second)
            if (!f(t)) return;
        }
  }

 private:
  static constexpr std::int64_t kMaxCells = 512;

  struct CellRange {
    std::array<std::int64_t, 3> lo;
    std::array<std::int64_t, 3> hi;
    std::int64_t count() const {
      std::int64_t n = 1;
      for (std::size_t k = 0; k < 3; ++k) n *= std::min<std::int64_t>(hi[k] - lo[k] + 1, kMaxCells + 1);
      return n;
    }
  };

  CellRange cells_of(const BoundingBox& box) const {
    CellRange range{};
    for (int k = 0; k < 3; ++k) {
      // Clamped so that far-out coordinates cannot overflow; keys wrap around, which only
      // adds candidates.
      constexpr double limit = 0x1.0p40;
      const auto k_index = static_cast<std::size_t>(k);
      range.lo[k_index] = static_cast<std::int64_t>(std::clamp(std::floor(box.min[k] / cell_size_), -limit, limit));
      range.hi[k_index] = static_cast<std::int64_t>(std::clamp(std::floor(box.max[k] / cell_size_), -limit, limit));
    }
    return range;
  }
  static std::uint64_t key(std::int64_t x, std::int64_t y, std::int64_t z) {
    constexpr std::uint64_t mask = (1u << 21) - 1;
    return (static_cast<std::uint64_t>(x) & mask) | ((static_cast<std::uint64_t>(y) & mask) << 21) |
           ((static_cast<std::uint64_t>(z) & mask) << 42);
  }

  double cell_size_ = 1;
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> cells_;
  std::vector<std::uint32_t> large_;
};

// ---------------------------------------------------------------------------------------

}  // namespace visproxy::detail
