#include "visproxy/scene/forest.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <nlohmann/json.hpp>

#include "visproxy/core/random.h"

namespace visproxy {
namespace {

struct Branch {
  Vertex start, direction;
  double length = 1, radius = 0.03;
  int level = 0;
};

// A tapered tube of `segments` rings along a slowly bending path; appends the points along
// its axis (one per ring) to `axis`.
void add_tube(TriangleMesh& mesh, const Branch& branch, int sides, int segments, Random& random, std::vector<Vertex>& axis) {
  Vertex point = branch.start, direction = branch.direction.normalized();
  Vertex normal = direction.unitOrthogonal();
  const auto first = static_cast<VertexIndex>(mesh.positions.size());
  for (int step = 0; step <= segments; ++step) {
    const double t = static_cast<double>(step) / segments;
    const double radius = branch.radius * (1 - 0.7 * t);
    const Vertex binormal = direction.cross(normal);
    for (int side = 0; side < sides; ++side) {
      const double angle = 2 * std::numbers::pi * side / sides;
      mesh.positions.push_back(point + radius * (std::cos(angle) * normal + std::sin(angle) * binormal));
    }
    axis.push_back(point);
    direction = (direction + 0.12 * random.unit_vector() + Vertex(0, 0.04, 0)).normalized();  // bends, a little upwards
    point += branch.length / segments * direction;
    normal = (normal - normal.dot(direction) * direction).normalized();
    if (!normal.allFinite()) normal = direction.unitOrthogonal();
  }
  const auto n = static_cast<VertexIndex>(sides);
  for (int step = 0; step < segments; ++step)
    for (VertexIndex side = 0; side < n; ++side) {
      const VertexIndex a = first + static_cast<VertexIndex>(step) * n + side;
      const VertexIndex b = first + static_cast<VertexIndex>(step) * n + (side + 1) % n;
      mesh.triangles.push_back({a, b, b + n});
      mesh.triangles.push_back({a, b + n, a + n});
    }
}

// A leaf: a quad (two triangles) at `at`, turned at random; needles are long and thin.
void add_leaf(TriangleMesh& mesh, const Vertex& at, double size, bool needle, Random& random) {
  const Vertex along = random.unit_vector();
  const Vertex across = along.cross(random.unit_vector()).normalized();
  const double length = needle ? 3 * size : size, width = needle ? 0.08 * size : 0.6 * size;
  const auto first = static_cast<VertexIndex>(mesh.positions.size());
  mesh.positions.push_back(at - 0.5 * width * across);
  mesh.positions.push_back(at + 0.5 * width * across);
  mesh.positions.push_back(at + length * along + 0.5 * width * across);
  mesh.positions.push_back(at + length * along - 0.5 * width * across);
  mesh.triangles.push_back({first, first + 1, first + 2});
  mesh.triangles.push_back({first, first + 2, first + 3});
}

}  // namespace

TriangleMesh make_tree(const TreeOptions& options) {
  Random random(options.seed);
  TriangleMesh mesh;
  std::vector<Branch> branches{{Vertex::Zero(), Vertex(0, 1, 0), 0.45, 0.035, 0}};
  std::vector<Vertex> twig_points;  // points along the outermost branches, where leaves grow
  const int segments_of[] = {10, 6, 4, 3, 3, 3};
  for (std::size_t b = 0; b < branches.size(); ++b) {
    const Branch branch = branches[b];
    std::vector<Vertex> axis;
    add_tube(mesh, branch, options.sides, segments_of[std::min(branch.level, 5)], random, axis);
    if (branch.level == options.branch_levels) {
      twig_points.insert(twig_points.end(), axis.begin() + static_cast<std::ptrdiff_t>(axis.size() / 3), axis.end());
      continue;
    }
    for (int c = 0; c < options.children; ++c) {
      // Children start in the upper part of their parent and lean out at 35-65 degrees.
      const double at = 0.35 + 0.6 * random.uniform();
      const Vertex start = axis[std::min(axis.size() - 1, static_cast<std::size_t>(at * static_cast<double>(axis.size() - 1)))];
      const Vertex out = (random.unit_vector() - random.unit_vector().dot(branch.direction) * branch.direction).normalized();
      const double lean = (35 + 30 * random.uniform()) * std::numbers::pi / 180;
      Vertex direction = std::cos(lean) * branch.direction.normalized() + std::sin(lean) * out;
      if (!direction.allFinite()) direction = branch.direction;
      branches.push_back({start, direction.normalized(), branch.length * (0.55 + 0.15 * random.uniform()),
                          branch.radius * 0.6, branch.level + 1});
    }
  }
  // Leaves along the twigs until the budget is spent, each a little off its twig.
  const std::size_t wood = mesh.triangles.size();
  const std::size_t leaves = options.triangles > wood + 2 ? (options.triangles - wood) / 2 : 1;
  const double size = 0.035 * std::pow(100'000.0 / static_cast<double>(std::max<std::size_t>(leaves, 1000)), 0.25);
  for (std::size_t k = 0; k < leaves; ++k) {
    const Vertex& base = twig_points[random.below(twig_points.size())];
    add_leaf(mesh, base + 0.06 * std::cbrt(random.uniform()) * random.unit_vector(), size, options.needles, random);
  }
  return mesh;
}

std::size_t Forest::instanced_triangles() const {
  std::size_t total = terrain.triangles.size();
  for (const TreePlacement& tree : trees) total += species[tree.species].triangles.size();
  return total;
}

Forest make_forest(const ForestOptions& options) {
  Forest forest;
  Random random(options.seed);
  const std::size_t kinds = std::max<std::size_t>(options.species, 1);
  for (std::size_t k = 0; k < kinds; ++k) {
    const double t = kinds == 1 ? 0.0 : static_cast<double>(k) / static_cast<double>(kinds - 1);
    const double size = std::exp((1 - t) * std::log(static_cast<double>(options.fewest_triangles)) +
                                 t * std::log(static_cast<double>(std::max(options.most_triangles, options.fewest_triangles))));
    forest.species.push_back(make_tree({.seed = options.seed * 1000 + k + 1,
                                        .triangles = static_cast<std::size_t>(size),
                                        .branch_levels = 3,
                                        .children = 4 + static_cast<int>(k % 2),
                                        .sides = 6,
                                        .needles = k % 2 == 1}));
  }

  // The terrain: smooth seeded waves, a few tree heights high over the whole extent.
  const std::size_t side = static_cast<std::size_t>(std::ceil(std::sqrt(static_cast<double>(std::max<std::size_t>(options.trees, 1)))));
  forest.extent = static_cast<double>(side) * options.spacing;
  const int cells = std::max(options.terrain_cells, 2);
  std::vector<Vertex> waves;
  std::vector<double> phases;
  for (int w = 0; w < 6; ++w) {
    const double angle = 2 * std::numbers::pi * random.uniform();
    const double frequency = 2 * std::numbers::pi / (forest.extent * (0.25 + 0.5 * random.uniform()));
    waves.emplace_back(frequency * std::cos(angle), 0, frequency * std::sin(angle));
    phases.push_back(2 * std::numbers::pi * random.uniform());
  }
  const double amplitude = std::min(0.03 * forest.extent, 6.0);
  auto height = [&](double x, double z) {
    double sum = 0;
    for (std::size_t w = 0; w < waves.size(); ++w) sum += std::sin(waves[w].x() * x + waves[w].z() * z + phases[w]);
    return amplitude * sum / static_cast<double>(waves.size());
  };
  const double half = 0.5 * forest.extent;
  for (int j = 0; j <= cells; ++j)
    for (int i = 0; i <= cells; ++i) {
      const double x = -half + forest.extent * i / cells, z = -half + forest.extent * j / cells;
      forest.terrain.positions.emplace_back(x, height(x, z), z);
    }
  const auto row = static_cast<VertexIndex>(cells + 1);
  for (VertexIndex j = 0; j < static_cast<VertexIndex>(cells); ++j)
    for (VertexIndex i = 0; i < static_cast<VertexIndex>(cells); ++i) {
      const VertexIndex a = j * row + i, b = a + 1, c = a + row, d = c + 1;
      forest.terrain.triangles.push_back({a, c, b});  // counter-clockwise seen from above
      forest.terrain.triangles.push_back({b, c, d});
    }

  // One tree per cell of a jittered grid, on the terrain's surface (the triangle under the
  // trunk, so the tree stands on what the renderer sees).
  auto ground = [&](double x, double z) {
    const double u = (x + half) / forest.extent * cells, v = (z + half) / forest.extent * cells;
    const int i = std::clamp(static_cast<int>(u), 0, cells - 1), j = std::clamp(static_cast<int>(v), 0, cells - 1);
    const double fu = u - i, fv = v - j;
    const auto at = [&](int a, int b) { return forest.terrain.positions[static_cast<std::size_t>(b * (cells + 1) + a)].y(); };
    return fu + fv <= 1 ? at(i, j) + fu * (at(i + 1, j) - at(i, j)) + fv * (at(i, j + 1) - at(i, j))
                        : at(i + 1, j + 1) + (1 - fu) * (at(i, j + 1) - at(i + 1, j + 1)) + (1 - fv) * (at(i + 1, j) - at(i + 1, j + 1));
  };
  for (std::size_t t = 0; t < options.trees; ++t) {
    const double x = -half + options.spacing * (static_cast<double>(t % side) + 0.2 + 0.6 * random.uniform());
    const double z = -half + options.spacing * (static_cast<double>(t / side) + 0.2 + 0.6 * random.uniform());
    TreePlacement tree;
    tree.species = static_cast<std::size_t>(random.below(kinds));
    const double scale = 0.8 + 0.45 * random.uniform();
    const double turn = 2 * std::numbers::pi * random.uniform();
    // Sunk by a hundredth of its height, so the trunk's open base is below the ground.
    tree.transform = Eigen::Translation3d(x, ground(x, z) - 0.01 * scale, z) * Eigen::AngleAxisd(turn, Vertex::UnitY()) *
                     Eigen::Scaling(scale);
    forest.trees.push_back(tree);
  }
  return forest;
}

std::string forest_scene_json(const Forest& forest, const ForestFiles& files, const std::vector<std::string>& proxies,
                              int width, int height, std::uint64_t seed) {
  nlohmann::json meshes = nlohmann::json::object();
  for (std::size_t k = 0; k < forest.species.size(); ++k) {
    nlohmann::json mesh = {{"file", files.species[k]}};
    if (k < files.proxy_folders.size() && !files.proxy_folders[k].empty()) mesh["proxy_folder"] = files.proxy_folders[k];
    meshes["tree" + std::to_string(k)] = mesh;
  }
  meshes["terrain"] = {{"file", files.terrain}};
  nlohmann::json instances = nlohmann::json::array();
  instances.push_back({{"mesh", "terrain"}, {"albedo", {0.35, 0.3, 0.2}}});
  for (const TreePlacement& tree : forest.trees) {
    std::vector<double> matrix;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) matrix.push_back(tree.transform.matrix()(r, c));
    instances.push_back({{"mesh", "tree" + std::to_string(tree.species)},
                         {"albedo", {0.25, 0.45, 0.2}},
                         {"transform", {{"matrix", matrix}}},
                         {"proxies", proxies}});
  }
  const double e = forest.extent, half = 0.5 * e;
  const nlohmann::json scene = {
      {"format", "visproxy-scene"},
      {"format_version", 1},
      {"description", "A procedural forest (seed " + std::to_string(seed) + "): " + std::to_string(forest.trees.size()) +
                          " trees of " + std::to_string(forest.species.size()) + " species on a terrain " +
                          std::to_string(e) + " units across, " + std::to_string(forest.instanced_triangles()) +
                          " instanced triangles, under a square light high above"},
      {"meshes", meshes},
      {"instances", instances},
      {"lights",
       {{{"type", "parallelogram"},
         {"corner", {-0.1 * e, 0.8 * e, -0.1 * e}},
         {"edge1", {0.2 * e, 0.0, 0.0}},
         {"edge2", {0.0, 0.0, 0.2 * e}},
         {"radiance", {50.0, 50.0, 50.0}}}}},
      {"camera",
       {{"from", {0.0, 2.5, -half - 2}},
        {"at", {0.0, 0.3, -half + 12}},
        {"up", {0.0, 1.0, 0.0}},
        {"fov_degrees", 50},
        {"width", width},
        {"height", height}}}};
  return scene.dump(1) + "\n";
}

}  // namespace visproxy
