#pragma once
// `visproxy batch`: an asset library processed one mesh at a time (build, verify, measure,
// report), each into its own proxy folder, resumable, with failures recorded and not fatal,
// split into deterministic shards for any job runner (GNU parallel, Slurm, Dask).
//
// Layout of a batch folder ROOT:
//   ROOT/STEM-KEY/          a complete proxy folder (manifest.json, proxies, report.html)
//                           and asset.json, the asset's record; renamed into place whole
//   ROOT/STEM-KEY.failed.json  the record of an asset that failed, with its one-line error
//   ROOT/.partial/          folders being written (a crash leaves them here, never in place)
//   ROOT/logs/STEM-KEY.log  the CLI's worker process's stderr for the asset
//   ROOT/summary.json, summary.csv, summary.html  written by batch_merge
// KEY is a 64-bit FNV-1a hash (16 hexadecimal digits) of the mesh file's bytes, the batch
// options and visproxy's version, so a changed mesh, option or version gets a new folder.

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace visproxy {

struct BatchOptions {
  std::vector<std::string> proxies;  ///< proxy specs; empty: the default set (inside:40 only for closed meshes)
  std::uint64_t seed = 1;            ///< seeds every random choice of build, verify and measure
  std::size_t rays = 200'000;        ///< isotropic lines for measure
  std::size_t timed_rays = 50'000;   ///< of them, timed on one core for the cost per ray
  std::size_t hausdorff_samples = 20'000;
  std::size_t gssa_lines = 100'000;
};

/// The options as the key and every record state them.
nlohmann::json batch_options_json(const BatchOptions& options);

/// The meshes of LIST: a text file with one path per line (relative paths are taken from
/// the file's folder; blank lines and lines starting with '#' are skipped), or a folder,
/// searched recursively for files with a mesh extension (.obj .ply .off .stl .gltf .glb
/// .fbx .dae .3ds), sorted. Throws IOError naming LIST when it cannot be read, and
/// InvalidInputError when it names no mesh.
std::vector<std::filesystem::path> read_asset_list(const std::filesystem::path& list);

/// The assets of shard `index` of `count` (0 <= index < count): those at positions
/// index, index + count, index + 2 count, ... of the list. Every asset is in exactly one
/// shard. Throws InvalidInputError for an index out of range.
std::vector<std::filesystem::path> shard_assets(const std::vector<std::filesystem::path>& assets, std::size_t index,
                                                std::size_t count);

/// "I/N" as given to --shard: both integers, 0 <= I < N. Throws InvalidInputError otherwise.
std::pair<std::size_t, std::size_t> parse_shard(const std::string& text);

/// The asset's folder name STEM-KEY (STEM: the file name without extension, characters
/// other than letters, digits, '.', '_' and '-' replaced by '-'). A file that cannot be read
/// gets the key of its path instead of its bytes.
std::string asset_folder_name(const std::filesystem::path& mesh, const BatchOptions& options);

/// Processes one asset into ROOT (created if missing) and returns its record:
///   {"asset", "folder", "status": "ok" | "claims_failed" | "failed", "error", "proxies",
///    "claims_holding", "triangles", "seconds", "resumed", "options", "visproxy_version"}
/// A complete folder (ROOT/NAME/asset.json) is not processed again ("resumed": true); nor
/// is a recorded failure unless `retry_failed`. Work happens in ROOT/.partial and is renamed
/// into place only when complete; an error (bad mesh, builder failure) is caught and
/// recorded in ROOT/NAME.failed.json, with "error" the exception's one line.
/// "claims_failed": the folder is complete but some proxy's claim does not hold.
nlohmann::json process_asset(const std::filesystem::path& mesh, const std::filesystem::path& root,
                             const BatchOptions& options, bool retry_failed = false);

/// The record of a failure found outside process_asset (a crashed worker) of the asset
/// `mesh`, whose folder name is `name` (asset_folder_name): written to
/// ROOT/NAME.failed.json unless a complete folder exists, whose record is returned then.
nlohmann::json record_failure(const std::filesystem::path& mesh, const std::filesystem::path& root,
                              const std::string& name, const BatchOptions& options, const std::string& error);

/// The record of the asset whose folder name is `name` (asset_folder_name) already in
/// ROOT, complete or failed, or null. (The name is taken, not the mesh, so that a caller
/// hashes the mesh's bytes once.)
nlohmann::json find_asset_record(const std::filesystem::path& root, const std::string& name);

/// One summary of every record in ROOT (all shards): ROOT/summary.json (the records, and
/// one row per asset and proxy: kind, primitives, verdict, f_hit, f_miss, GSSA ratio,
/// variance, cost ratio, build seconds), summary.csv (those rows) and summary.html (a
/// sortable table linking each asset's report, the failures with their errors). Rows are
/// sorted by asset path and proxy; fields that measure time are named in "timed_fields"
/// (everything else is the same for the same assets and options, however sharded).
/// Returns the summary.
nlohmann::json batch_merge(const std::filesystem::path& root);

}  // namespace visproxy
