#pragma once
// Simplifying a sphere set by merging pairs while keeping how often lines hit it
// (occluding-spheres paper, section 3.2-3.4).

#include <cstddef>
#include <span>
#include <string_view>
#include <vector>

#include "visproxy/mesh/sphere_set.h"
#include "visproxy/proxy/two_sphere_gssa.h"

namespace visproxy {

/// How close two spheres (radii R >= r, centres d apart) are for merging (paper, 3.2).
enum class PairDistance {
  d1,  ///< D1 = d: promotes merging small spheres
  d2,  ///< D2 = d + r - R: how far the larger must grow to hold the smaller (negative when it does)
};
std::string_view pair_distance_name(PairDistance distance);

struct MergeSpheresOptions {
  PairDistance pair_distance = PairDistance::d2;
  MergeRadius radius = MergeRadius::exact;  ///< which GSSA each merge preserves (two_sphere_gssa.h)
};

/// The work merge_spheres did: best-partner searches in the k-d tree, and entries put into
/// and taken from its priority queue. About O(n) each for n spheres.
struct MergeSpheresStatistics {
  std::size_t partner_searches = 0;
  std::size_t queue_entries = 0;
  std::size_t queue_pops = 0;
};

/// Merges the closest pair of `spheres` (by options.pair_distance) into one
/// (merge_two_spheres) until `targets[k]` spheres remain, for every k, in one pass: the
/// result's entry k is the set at targets[k] spheres, in a fixed order. Exactly targets[k]
/// spheres each.
///
/// Every sphere remembers its best partner, found with a k-d tree over the centres that
/// also bounds the radii below each node (so D2's lower bounds prune too); candidate pairs
/// wait in a priority queue and are re-examined only when one of the two has changed, and
/// only the merged sphere and the spheres whose partner was merged search again. A sphere
/// that holds the one it absorbs does not change, so the spheres that chose it keep their
/// entries. The searches and queue operations are O(n) (`statistics`, if given, receives
/// them), each search about O(log n) node visits when radii vary moderately; from a ball
/// that holds most others and empties around its centre as it absorbs them, a search is a
/// nearest-neighbour query from inside a hollow and visits up to O(n^(2/3)). Deterministic: ties go to the
/// lower index, nothing depends on addresses or thread scheduling.
///
/// Preconditions (InvalidInputError, empty file name): every target is at least 1 and at
/// most spheres.size(); radii are finite and non-negative, centres finite.
std::vector<std::vector<Sphere>> merge_spheres(std::span<const Sphere> spheres, std::span<const std::size_t> targets,
                                               const MergeSpheresOptions& options = {},
                                               MergeSpheresStatistics* statistics = nullptr);

}  // namespace visproxy
