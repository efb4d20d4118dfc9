// visproxy build MESH -o DIR [--proxy SPEC]... [--per-component] [--weld MODE] [--seed S]
//                            [--tets tetgen|normals] [--gssa-lines N] [--memory-limit GIB]
//                            [--time-limit SECONDS]

#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <mutex>
#include <thread>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <new>
#include <optional>
#include <string>
#include <vector>

#include "commands.h"
#include "progress.h"
#include "visproxy/evaluate/proxy_flags.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/proxy/build_proxies.h"
#include "visproxy/folder/asset_folder.h"
#include "visproxy/folder/proxy_folder.h"

namespace visproxy::cli {
namespace {

// Once `seconds` have passed, prints one line naming the file and every step in progress
// (reading, builders, measures: several when builders run at once) and ends the process
// with exit code 3, unless finish() came first. Nothing is written before finish(), so
// nothing partial is left.
class Watchdog {
 public:
  Watchdog(double seconds, std::filesystem::path file) : seconds_(seconds), file_(std::move(file)) {
    if (seconds_ > 0) thread_ = std::thread([this] { watch(); });
  }
  ~Watchdog() {
    finish();
    if (thread_.joinable()) thread_.join();
  }
  /// The step `key` (a spec's text, or "" for reading) is now `what`.
  void step(const std::string& key, std::string what) {
    const std::lock_guard lock(mutex_);
    steps_[key] = std::move(what);
  }
  void done(const std::string& key) {
    const std::lock_guard lock(mutex_);
    steps_.erase(key);
  }
  void finish() {
    {
      const std::lock_guard lock(mutex_);
      done_ = true;
    }
    changed_.notify_all();
  }

 private:
  void watch() {
    std::unique_lock lock(mutex_);
    if (changed_.wait_for(lock, std::chrono::duration<double>(seconds_), [this] { return done_; })) return;
    std::string steps;
    for (const auto& [key, what] : steps_) steps += (steps.empty() ? "" : "; ") + what;
    if (steps.empty()) steps = "out of time";
    std::fprintf(stderr, "visproxy: %s: %s (--time-limit %g s)\n", file_.string().c_str(), steps.c_str(), seconds_);
    std::fflush(stderr);
    std::_Exit(3);
  }
  double seconds_;
  std::filesystem::path file_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::map<std::string, std::string> steps_{{"", "out of time while reading it"}};
  bool done_ = false;
  std::thread thread_;
};

struct BuildCommandOptions {
  ProgressMode progress = ProgressMode::automatic;
  std::filesystem::path mesh;
  std::filesystem::path folder;
  std::vector<std::string> proxies;
  bool per_component = false;
  bool per_mesh = false;
  Weld weld = Weld::automatic;
  std::uint64_t seed = 1;
  std::size_t hausdorff_samples = 20000;
  double memory_limit_gib = 0;
  double time_limit = 0;
  std::size_t builders_at_once = 0;
  InnerTetrahedra tets = InnerTetrahedra::normals;
  std::size_t gssa_lines = 100000;
};

void print_table(const BuildCommandOptions& options, const ManifestMesh& mesh, const std::vector<BuiltProxy>& proxies,
                 double total_seconds) {
  std::printf("visproxy build: %zu proxies of %s (%zu vertices, %zu triangles, %zu component%s, diagonal %.6g)\n",
              proxies.size(), options.mesh.string().c_str(), mesh.vertices, mesh.triangles, mesh.components,
              mesh.components == 1 ? "" : "s", mesh.bounds.diagonal());
  std::printf("%-28s %-8s %10s %-9s %9s %12s  %s\n", "name", "kind", "primitives", "type", "build s",
              "Hausdorff %", "file");
  bool any_spheres = false;
  for (const BuiltProxy& proxy : proxies) {
    const double hausdorff_percent = 100.0 * proxy.error.at("hausdorff_relative").get<double>();
    const bool spheres = proxy.primitive_type == PrimitiveType::sphere;
    any_spheres = any_spheres || spheres;
    std::string gssa;
    if (spheres) {
      const auto& ratio = proxy.result.at("gssa_ratio");
      char upper[32] = "inf";  // null: unbounded
      if (!ratio.at("upper").is_null()) std::snprintf(upper, sizeof upper, "%.3f", ratio.at("upper").get<double>());
      char text[96];
      std::snprintf(text, sizeof text, "  GSSA ratio %.3f [%.3f, %s]", ratio.at("value").get<double>(),
                    ratio.at("lower").get<double>(), upper);
      gssa = text;
    }
    std::printf("%-28s %-8s %10zu %-9s %9.3f %12.4f  %s%s\n", proxy.name.c_str(),
                std::string(kind_name(proxy.spec.kind())).c_str(), proxy.primitives,
                std::string(primitive_type_name(proxy.primitive_type)).c_str(), proxy.build_seconds, hausdorff_percent,
                (options.folder / (proxy.name + (spheres ? ".json" : ".ply"))).string().c_str(), gssa.c_str());
  }
  std::printf("Hausdorff %%: sampled two-sided Hausdorff distance between proxy and mesh, in %% of the bounding-box\n"
              "diagonal (%zu samples per surface, seed %llu). Build s: wall seconds of each builder, %zu built at "
              "once. Manifest: %s (%.2f s in all)\n",
              options.hausdorff_samples, static_cast<unsigned long long>(options.seed),
              builders_at_once(options.builders_at_once, mesh.triangles),
              (options.folder / "manifest.json").string().c_str(), total_seconds);
  if (any_spheres)
    std::printf("GSSA ratio: isotropic lines hitting the spheres / lines hitting the mesh (%zu lines, seed %llu, 95 %% "
                "interval)\n",
                options.gssa_lines, static_cast<unsigned long long>(options.seed));
}

// --per-mesh: every part of the asset into its own folder, one line per part.
void build_per_mesh(const BuildCommandOptions& options, const std::vector<ProxySpec>& specs) {
  const auto start = std::chrono::steady_clock::now();
  BuildOptions build{.per_component = options.per_component,
                     .hausdorff_samples = options.hausdorff_samples,
                     .seed = options.seed,
                     .on_start = {},
                     .tets = options.tets,
                     .gssa_lines = options.gssa_lines,
                     .default_set = options.proxies.empty(),
                     .on_skip = {}};
  build.builders_at_once = options.builders_at_once;
  std::optional<Progress> progress;
  const nlohmann::json asset = build_asset_folder(
      options.folder, options.mesh, options.weld, specs, build, [&](std::string_view part, std::size_t, std::size_t n) {
        if (!progress) progress.emplace("visproxy build", n, options.progress);
        progress->step("building the proxies of " + std::string(part));
      });
  progress.reset();
  std::printf("visproxy build --per-mesh: %zu meshes of %s, each built once\n", asset["parts"].size(), options.mesh.string().c_str());
  std::printf("%-32s %10s %10s %8s  %s\n", "mesh", "triangles", "instances", "proxies", "folder / problem");
  std::size_t problems = 0;
  for (const nlohmann::json& part : asset["parts"]) {
    const bool built = part["problem"].is_null();
    problems += built ? 0 : 1;
    std::printf("%-32s %10zu %10zu %8zu  %s\n", part["name"].get<std::string>().c_str(), part["triangles"].get<std::size_t>(),
                part["instances"].size(), part["proxies"].size(),
                built ? (options.folder / part["name"].get<std::string>()).string().c_str() : part["problem"].get<std::string>().c_str());
    if (!built) std::cerr << "visproxy build: " << part["name"].get<std::string>() << " not built: " << part["problem"].get<std::string>() << "\n";
  }
  std::printf("%zu of %zu meshes built, %.2f s in all. Listed in %s\n", asset["parts"].size() - problems, asset["parts"].size(),
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
              (options.folder / "asset.json").string().c_str());
}

}  // namespace

void add_build_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<BuildCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "build",
      "Build visibility proxies of a mesh: one binary PLY and one OBJ per proxy (sphere proxies: a JSON sphere set "
      "and a PLY of their icospheres) in DIR, listed in DIR/manifest.json "
      "(schema: data/schemas/manifest.schema.json) with kind, parameters, primitive count, build time and error.");
  command->add_option("mesh", options->mesh, "Mesh file (.obj, .ply, .off, .stl, or through Assimp .gltf, .glb, .fbx, .dae, .3ds, ...)")->required();
  command->add_option("-o,--output", options->folder, "Output folder (created if missing)")->required();
  command->add_option("--proxy", options->proxies,
                      "Proxy to build (repeatable):\n" + proxy_spec_help() +
                          "Default: aabb obb hull hull:32 wrap outer:512 quadric:512 cluster:0.03 inside:40 spheres:100 "
                          "(left out, with a note: inside:40 when the mesh is not closed, and any proxy of at least 4096 "
                          "primitives that is more than 10 % of the mesh's triangles)");
  add_progress_option(command, options->progress);
  command->add_flag("--per-component", options->per_component,
                    "Build one proxy per connected component (N applies to each) and join them in one file");
  CLI::Option* per_mesh = command->add_flag(
      "--per-mesh", options->per_mesh,
      "A multi-mesh asset (glTF, FBX, ...): build the proxies of each of its meshes once, in its own coordinates, into "
      "DIR/MESH/ (a proxy folder whose mesh is ASSET:MESH), and list the meshes with the nodes that show them in "
      "DIR/asset.json (schema: data/schemas/asset.schema.json); 'export' puts each proxy under those nodes");
  as_choice<Weld>(command->add_option(
      "--weld", options->weld,
      "Merge vertices with identical coordinates: auto (STL and Assimp's formats only), never, always [default: auto]"));
  command->add_option("--seed", options->seed, "Seed of every random choice (error samples, box search) [default: 1]");
  command
      ->add_option("--hausdorff-samples", options->hausdorff_samples,
                   "Area-uniform samples per surface for the Hausdorff error [default: 20000]")
      ->check(CLI::Range(std::size_t{100}, std::size_t{100'000'000}));
  as_choice<InnerTetrahedra>(
      command->add_option("--tets", options->tets,
                          "How spheres:N finds the tetrahedra inside the mesh: normals (Delaunay of surface samples, "
                          "inner tetrahedra by the normal criterion; any mesh) or tetgen (TetGen's constrained "
                          "tetrahedralization; watertight meshes) [default: normals]"));
  command
      ->add_option("--gssa-lines", options->gssa_lines,
                   "Isotropic lines for the GSSA ratio of sphere proxies [default: 100000]")
      ->check(CLI::Range(std::size_t{1000}, std::size_t{100'000'000}));

  command
      ->add_option("--builders-at-once", options->builders_at_once,
                   "Proxies built and measured at once, each on its own worker; the proxies are the same bit for bit, "
                   "the build seconds grow as builders share the cores, and so does the peak memory [default: the "
                   "machine's threads for meshes up to 2^20 triangles, 1 above]")
      ->check(CLI::Range(std::size_t{1}, std::size_t{256}));
  command
      ->add_option("--memory-limit", options->memory_limit_gib,
                   "Stop with exit code 3 and a line naming the builder or measure that ran out, rather than use more "
                   "than this many GiB of data memory (the process's RLIMIT_DATA) [default: no limit]")
      ->check(CLI::Range(0.001, 1.0e6));

  command
      ->add_option("--time-limit", options->time_limit,
                   "Stop with exit code 3 and a line naming the builder or measure in progress once this many seconds "
                   "have passed, writing nothing [default: no limit]")
      ->check(CLI::Range(0.001, 1.0e9))
      ->excludes(per_mesh);

  command->callback([options, &exit_code] {
    const auto start = std::chrono::steady_clock::now();
    if (options->memory_limit_gib > 0) {
      const auto bytes = static_cast<rlim_t>(options->memory_limit_gib * 1024 * 1024 * 1024);
      const rlimit limit{bytes, bytes};
      if (::setrlimit(RLIMIT_DATA, &limit) != 0) throw CLI::ValidationError("--memory-limit", "cannot be set on this system");
    }
    // Specs are checked before anything is read or built.
    const std::vector<ProxySpec> specs =
        options->proxies.empty() ? default_proxy_specs() : parse_proxy_specs(options->proxies);
    if (options->per_mesh) {
      build_per_mesh(*options, specs);
      exit_code = kSuccess;
      return;
    }
    Watchdog watchdog(options->time_limit, options->mesh);
    const TriangleMesh mesh = [&] {
      try {
        return read_mesh(options->mesh, {.weld = options->weld, .on_warning = print_warning});
      } catch (const std::bad_alloc&) {
        throw OutOfMemoryError(options->mesh, "out of memory while reading it");
      }
    }();
    BuildOptions build{.per_component = options->per_component,
                       .hausdorff_samples = options->hausdorff_samples,
                       .seed = options->seed,
                       .on_start = {},
                       .tets = options->tets,
                       .gssa_lines = options->gssa_lines,
                       .default_set = options->proxies.empty(),
                       .on_skip = [](std::string_view name, std::string_view reason) {
                         std::cerr << "visproxy build: skipping " << name << ": " << reason << "\n";
                       }};
    watchdog.done("");
    build.builders_at_once = options->builders_at_once;
    std::optional<Progress> progress(std::in_place, "visproxy build", specs.size(), options->progress);
    build.on_start = [&](std::string_view name) {
      progress->step(std::string("building ") + std::string(name));
      for (const ProxySpec& spec : specs)
        if (spec.name() == name) watchdog.step(spec.text, spec.text + ": out of time while building it");
    };
    build.on_measure = [&](std::string_view spec) {
      watchdog.step(std::string(spec), std::string(spec) + ": out of time while measuring its error");
    };
    build.on_step_done = [&](std::string_view spec) { watchdog.done(std::string(spec)); };
    const BuiltFolder built =
        build_proxy_folder(options->folder, mesh, options->mesh, options->weld, specs, build, [&] { watchdog.finish(); });
    progress.reset();  // clears the terminal's progress line before the table
    print_table(*options, built.mesh, built.proxies,
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    for (const ProxyFlag& flag : proxy_flags(built.manifest)) std::printf("check: %s\n", flag.text.c_str());
    exit_code = kSuccess;
  });
}

}  // namespace visproxy::cli
