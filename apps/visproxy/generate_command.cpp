// visproxy generate hairball --triangles N -o DIR [--seed S] [--proxy SPEC]...
// visproxy generate room -o SCENE.json [--proxy SPEC]... [--width W] [--height H]
// visproxy generate forest -o DIR [--trees N] [--species K] [--seed S] [--proxy SPEC]... [--tree-triangles MIN,MAX]

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "commands.h"
#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"
#include "visproxy/folder/proxy_folder.h"
#include "visproxy/folder/verdict.h"
#include "visproxy/mesh/write_mesh.h"
#include "visproxy/proxy/build_proxies.h"
#include "visproxy/folder/proxy_folder.h"
#include "visproxy/scene/forest.h"
#include "visproxy/scene/hairball.h"
#include "visproxy/scene/room.h"

namespace visproxy::cli {
namespace {

struct GenerateOptions {
  std::size_t triangles = 2'000'000;
  std::filesystem::path folder;
  std::uint64_t seed = 1;
  std::vector<std::string> proxies{"hull:32", "hull", "cluster:0.02"};
  int width = 320, height = 240;
};

// The hairball above a floor, lit from above: the scene file written beside the mesh.
std::string hairball_scene(const GenerateOptions& o) {
  std::string proxies;
  for (const std::string& spec : o.proxies) proxies += (proxies.empty() ? "\"" : ", \"") + spec + "\"";
  return "{\n"
         "  \"format\": \"visproxy-scene\",\n"
         "  \"format_version\": 1,\n"
         "  \"description\": \"A procedural hairball of " + std::to_string(o.triangles) + " triangles (seed " +
         std::to_string(o.seed) + ") over a floor, lit by a square light above: highly complex geometry with no clean inside.\",\n"
         "  \"meshes\": {\n"
         "    \"floor\": {\"positions\": [[-4, 0, -4], [4, 0, -4], [4, 0, 4], [-4, 0, 4]], \"triangles\": [[0, 2, 1], [0, 3, 2]]},\n"
         "    \"hairball\": {\"file\": \"hairball.ply\", \"proxy_folder\": \"proxies\"}\n"
         "  },\n"
         "  \"instances\": [\n"
         "    {\"mesh\": \"floor\", \"albedo\": [0.7, 0.7, 0.7]},\n"
         "    {\"mesh\": \"hairball\", \"albedo\": [0.8, 0.55, 0.3], \"transform\": {\"translate\": [0, 1.15, 0]}, \"proxies\": [" +
         proxies + "]}\n"
         "  ],\n"
         "  \"lights\": [\n"
         "    {\"type\": \"parallelogram\", \"corner\": [-0.75, 3.5, -0.75], \"edge1\": [1.5, 0, 0], \"edge2\": [0, 0, 1.5], \"radiance\": [6, 6, 6]}\n"
         "  ],\n"
         "  \"camera\": {\"from\": [0, 1.6, 4.6], \"at\": [0, 0.9, 0], \"up\": [0, 1, 0], \"fov_degrees\": 45, \"width\": " +
         std::to_string(o.width) + ", \"height\": " + std::to_string(o.height) + "}\n"
         "}\n";
}

// Verifies every outside and inside proxy of a folder just written and records the verdicts,
// so that renders of the scene use the proofs without making them again.
void record_verdicts(const std::filesystem::path& folder, nlohmann::json manifest, const TriangleMesh& mesh) {
  for (nlohmann::json& entry : manifest["proxies"]) {
    if (entry_kind(entry) == ProxyKind::general) continue;
    entry["verify"] = verify_proxy(mesh, manifest, entry, read_proxy_geometry(folder, entry));
  }
  write_manifest(folder, manifest);
}

struct ForestCommandOptions {
  std::filesystem::path folder;
  ForestOptions forest;
  std::vector<std::string> proxies = kForestProxies;
  std::vector<std::size_t> sizes;
  int width = 640, height = 360;
};

}  // namespace

void add_generate_command(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<GenerateOptions>();
  CLI::App* generate = app.add_subcommand("generate", "Write procedural test scenes");
  generate->require_subcommand(1);
  CLI::App* hairball = generate->add_subcommand(
      "hairball",
      "A hairball of thin random tubes: writes DIR/hairball.ply, the scene DIR/hairball.json (floor, light, camera) and "
      "its proxies in DIR/proxies (a 'visproxy build' folder the scene points to, its claims verified and recorded).");
  hairball->add_option("--triangles", o->triangles, "About this many triangles [default: 2000000]")
      ->check(CLI::Range(std::size_t{480}, std::size_t{200'000'000}));
  hairball->add_option("-o,--output", o->folder, "Output folder (created if missing)")->required();
  hairball->add_option("--seed", o->seed, "Seed of the tubes and of the proxy builds [default: 1]");
  hairball->add_option("--proxy", o->proxies, "Proxies to build and name in the scene [default: hull:32 hull cluster:0.02]");
  hairball->add_option("--width", o->width, "Image width of the scene's camera [default: 320]")->check(CLI::Range(1, 16384));
  hairball->add_option("--height", o->height, "Image height [default: 240]")->check(CLI::Range(1, 16384));
  hairball->callback([o, &exit_code] {
    const auto start = std::chrono::steady_clock::now();
    const std::vector<ProxySpec> specs = parse_proxy_specs(o->proxies);
    const TriangleMesh mesh = make_hairball({.triangles = o->triangles, .seed = o->seed});
    std::error_code error;
    std::filesystem::create_directories(o->folder, error);
    if (error) throw IOError(o->folder, "cannot create the output folder: " + error.message());
    const std::filesystem::path mesh_path = o->folder / "hairball.ply";
    const BuildOptions build{.per_component = false, .hausdorff_samples = 20000, .seed = o->seed, .on_start = {}};
    const BuiltFolder built = build_proxy_folder(o->folder / "proxies", mesh, mesh_path, Weld::automatic, specs, build);
    write_mesh(mesh_path, mesh);
    record_verdicts(o->folder / "proxies", built.manifest, mesh);
    write_file_atomically(o->folder / "hairball.json", hairball_scene(*o));
    std::printf("visproxy generate hairball: %zu triangles (seed %llu) in %s, scene %s, %zu proxies in %s (%.1f s)\n",
                mesh.triangles.size(), static_cast<unsigned long long>(o->seed), mesh_path.string().c_str(),
                (o->folder / "hairball.json").string().c_str(), built.proxies.size(), (o->folder / "proxies").string().c_str(),
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    exit_code = kSuccess;
  });

  auto forest = std::make_shared<ForestCommandOptions>();
  CLI::App* forest_command = generate->add_subcommand(
      "forest",
      "A forest of instanced procedural trees on a rolling terrain: writes DIR/tree-K.ply for each species (trunk, "
      "branches and leaves or needles), DIR/terrain.ply, each species' proxies in DIR/proxies-K (a 'visproxy build' "
      "folder: aabb, cluster:0.03, hull:32, outer:512 and spheres:100 unless --proxy, each outside and inside claim "
      "verified and recorded), and the scene DIR/forest.json, which places the trees with seeded transforms and names "
      "their proxies.");
  forest_command->add_option("-o,--output", forest->folder, "Output folder (created if missing)")->required();
  forest_command->add_option("--trees", forest->forest.trees, "Trees in the scene [default: 10000]")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1'000'000}));
  forest_command->add_option("--species", forest->forest.species, "Distinct tree meshes [default: 4]")
      ->check(CLI::Range(std::size_t{1}, std::size_t{64}));
  forest_command->add_option("--seed", forest->forest.seed, "Seed of the trees, the terrain, the placements and the proxy builds [default: 1]");
  forest_command->add_option("--proxy", forest->proxies, "Proxies to build for every species and name in the scene [default: the paper's five]");
  forest_command->add_option("--tree-triangles", forest->sizes, "Triangles of the smallest and the largest species [default: 30000,1000000]")
      ->expected(2)->delimiter(',')->check(CLI::Range(std::size_t{4000}, std::size_t{50'000'000}));
  forest_command->add_option("--width", forest->width, "Image width of the scene's camera [default: 640]")->check(CLI::Range(1, 16384));
  forest_command->add_option("--height", forest->height, "Image height [default: 360]")->check(CLI::Range(1, 16384));
  forest_command->callback([forest, &exit_code] {
    const auto start = std::chrono::steady_clock::now();
    const std::vector<ProxySpec> specs = parse_proxy_specs(forest->proxies);
    if (forest->sizes.size() == 2) forest->forest.fewest_triangles = forest->sizes[0], forest->forest.most_triangles = forest->sizes[1];
    if (forest->forest.fewest_triangles > forest->forest.most_triangles)
      throw InvalidInputError("", "--tree-triangles: the smallest species cannot be larger than the largest");
    const Forest made = make_forest(forest->forest);
    std::error_code error;
    std::filesystem::create_directories(forest->folder, error);
    if (error) throw IOError(forest->folder, "cannot create the output folder: " + error.message());
    ForestFiles files;
    for (std::size_t k = 0; k < made.species.size(); ++k) {
      const TriangleMesh& tree = made.species[k];
      const std::string name = "tree-" + std::to_string(k) + ".ply", proxies = "proxies-" + std::to_string(k);
      const std::filesystem::path mesh_path = forest->folder / name;
      std::fprintf(stderr, "visproxy generate forest: species %zu of %zu, %zu triangles: building %zu proxies ...\n", k + 1,
                   made.species.size(), tree.triangles.size(), specs.size());
      const BuildOptions build{.per_component = false, .hausdorff_samples = 20000, .seed = forest->forest.seed, .on_start = {}};
      const BuiltFolder built = build_proxy_folder(forest->folder / proxies, tree, mesh_path, Weld::automatic, specs, build);
      write_mesh(mesh_path, tree);
      record_verdicts(forest->folder / proxies, built.manifest, tree);
      files.species.push_back(name);
      files.proxy_folders.push_back(proxies);
    }
    files.terrain = "terrain.ply";
    write_mesh(forest->folder / files.terrain, made.terrain);
    write_file_atomically(forest->folder / "forest.json",
                          forest_scene_json(made, files, forest->proxies, forest->width, forest->height, forest->forest.seed));
    std::size_t tree_triangles = 0;
    for (const TriangleMesh& tree : made.species) tree_triangles += tree.triangles.size();
    std::printf("visproxy generate forest: %zu trees of %zu species (%zu triangles in all, seed %llu) on a terrain %.1f units across: "
                "%zu instanced triangles; scene %s, proxies in %s/proxies-K (%.1f s)\n",
                made.trees.size(), made.species.size(), tree_triangles, static_cast<unsigned long long>(forest->forest.seed),
                made.extent, made.instanced_triangles(), (forest->folder / "forest.json").string().c_str(),
                forest->folder.string().c_str(), std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    exit_code = kSuccess;
  });

  auto room = std::make_shared<RoomOptions>();
  auto room_path = std::make_shared<std::filesystem::path>();
  CLI::App* room_command = generate->add_subcommand(
      "room",
      "A room with a table and four chairs under one ceiling light (closed furniture meshes of disjoint boxes, so that "
      "inside proxies exist): writes the scene file, meshes inline, naming the proxies each piece of furniture uses "
      "(built into the proxy cache on first render).");
  room_command->add_option("-o,--output", *room_path, "Scene file to write (.json)")->required();
  room_command->add_option("--proxy", room->proxies, "Proxies every piece of furniture names [default: hull inner:128,grid=128]");
  room_command->add_option("--width", room->width, "Image width of the scene's camera [default: 640]")->check(CLI::Range(1, 16384));
  room_command->add_option("--height", room->height, "Image height [default: 480]")->check(CLI::Range(1, 16384));
  room_command->callback([room, room_path, &exit_code] {
    parse_proxy_specs(room->proxies);  // a bad spec fails before anything is written
    if (room_path->has_parent_path()) {
      std::error_code error;
      std::filesystem::create_directories(room_path->parent_path(), error);
      if (error) throw IOError(room_path->parent_path(), "cannot create the output folder: " + error.message());
    }
    write_file_atomically(*room_path, room_scene_json(*room));
    std::printf("visproxy generate room: table and 4 chairs (%zu and %zu triangles) in a closed room, one ceiling light, %dx%d camera, "
                "proxies %s: %s\n",
                make_table().triangles.size(), make_chair().triangles.size(), room->width, room->height,
                [&] {
                  std::string all;
                  for (const std::string& spec : room->proxies) all += (all.empty() ? "" : " ") + spec;
                  return all;
                }().c_str(),
                room_path->string().c_str());
    exit_code = kSuccess;
  });
}

}  // namespace visproxy::cli
