#pragma once
// A procedural forest: a few species of tree (trunk, branches and leaves, from tens of
// thousands to about a million triangles each), instanced thousands of times with seeded
// transforms over a rolling terrain. The paper's scene where proxies pay most (291 M
// instanced primitives), and where adaptive probes fail.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct TreeOptions {
  std::uint64_t seed = 1;
  std::size_t triangles = 100'000;  ///< about this many: the leaves make up the difference
  int branch_levels = 3;            ///< generations of branches above the trunk
  int children = 4;                 ///< branches from each branch
  int sides = 6;                    ///< polygon of each branch's cross-section
  /// Leaves as broad quads (foliage), or as long thin needles in tufts (a hairball-like
  /// crown of many crossing slivers).
  bool needles = false;
};

/// One tree, about 1 unit tall, standing on the origin with +y up: a trunk and
/// `branch_levels` generations of tapered, slightly bending branches (open tubes), and
/// leaves, two triangles each, spread over the outer branches until the mesh has about
/// `triangles` triangles. Open surfaces (no inside). Deterministic for a seed.
TriangleMesh make_tree(const TreeOptions& options);

struct ForestOptions {
  std::size_t trees = 10'000;
  std::size_t species = 4;
  std::uint64_t seed = 1;
  /// The species' sizes run from the first to the second, evenly in log scale; every
  /// other species has needles.
  std::size_t fewest_triangles = 30'000, most_triangles = 1'000'000;
  double spacing = 1.2;  ///< mean distance between neighbouring trees (world units; trees are about 1 tall)
  int terrain_cells = 200;  ///< grid of the terrain, cells a side
};

struct TreePlacement {
  std::size_t species = 0;
  Eigen::Affine3d transform = Eigen::Affine3d::Identity();  ///< tree to world: scale, turn about y, move onto the ground
};

struct Forest {
  std::vector<TriangleMesh> species;  ///< the tree meshes
  TriangleMesh terrain;               ///< a height field, +y up, centred on the origin
  double extent = 0;                  ///< the terrain's side, world units
  std::vector<TreePlacement> trees;
  /// Triangles the renderer sees through instancing: the trees' and the terrain's.
  std::size_t instanced_triangles() const;
};

/// The paper's proxies for each tree: a box and clustering (its Table 5 forest), a bounded
/// hull, a conservative outer mesh and a sphere set.
inline const std::vector<std::string> kForestProxies = {"aabb", "cluster:0.03", "hull:32", "outer:512", "spheres:100"};

/// The species, the terrain and the placements: one tree per cell of a jittered grid over
/// the terrain (so trees do not overlap), its species, scale (0.8 to 1.25) and turn about y
/// drawn from the seed, set on the ground at its trunk. Deterministic for a seed.
Forest make_forest(const ForestOptions& options);

/// The files a forest's scene names, relative to the scene file.
struct ForestFiles {
  std::vector<std::string> species;          ///< a mesh file per species
  std::vector<std::string> proxy_folders;    ///< a `visproxy build` folder per species ("": none)
  std::string terrain;                       ///< the terrain's mesh file
};

/// The scene (data/schemas/scene.schema.json): the terrain and every tree as instances
/// (transform matrices), each tree naming `proxies` (the first is the one stochastic
/// visibility uses), a square light high above the forest's middle, and a camera low over
/// one edge looking across it, `width` x `height`.
std::string forest_scene_json(const Forest& forest, const ForestFiles& files, const std::vector<std::string>& proxies,
                              int width, int height, std::uint64_t seed);

}  // namespace visproxy
