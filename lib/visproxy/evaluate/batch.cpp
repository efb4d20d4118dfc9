#include "visproxy/evaluate/batch.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"
#include "visproxy/core/version.h"
#include "visproxy/evaluate/measure_proxies.h"
#include "visproxy/folder/proxy_folder.h"
#include "visproxy/evaluate/report.h"
#include "visproxy/folder/verdict.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/proxy/build_proxies.h"
#include "visproxy/folder/proxy_folder.h"

namespace visproxy {
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

constexpr const char* kRecordFormat = "visproxy-batch-asset";
constexpr const char* kSummaryFormat = "visproxy-batch-summary";

struct Fnv1a {
  std::uint64_t state = 1469598103934665603ull;
  void add(std::string_view bytes) {
    for (const char c : bytes) state = (state ^ static_cast<unsigned char>(c)) * 1099511628211ull;
  }
  std::string hex() const {
    char text[17];
    std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(state));
    return text;
  }
};

bool is_mesh_extension(const fs::path& path) {
  static const std::set<std::string> extensions{".obj", ".ply", ".off", ".stl", ".gltf", ".glb", ".fbx", ".dae", ".3ds"};
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return std::tolower(c); });
  return extensions.count(extension) > 0;
}

// The first line of an error message: records and summaries hold one line per failure.
std::string one_line(std::string text) {
  const auto end = text.find('\n');
  if (end != std::string::npos) text.resize(end);
  return text;
}

json read_record(const fs::path& path) {
  try {
    json record = json::parse(read_file(path));
    if (record.is_object() && record.value("format", "") == kRecordFormat) return record;
  } catch (const json::exception&) {
  }
  return nullptr;  // not a record (edited by hand, or not ours): treated as absent
}

json base_record(const fs::path& mesh, const std::string& name, const BatchOptions& options) {
  return {{"format", kRecordFormat},
          {"format_version", 1},
          {"asset", mesh.generic_string()},
          {"folder", name},
          {"status", "failed"},
          {"error", nullptr},
          {"warnings", json::array()},
          {"triangles", nullptr},
          {"proxies", 0},
          {"claims_holding", 0},
          {"seconds", 0.0},
          {"options", batch_options_json(options)},
          {"visproxy_version", version()}};
}

double value_at(const json& object, std::initializer_list<const char*> path) {
  const json* node = &object;
  for (const char* key : path) {
    if (!node->is_object() || !node->contains(key)) return std::nan("");
    node = &(*node)[key];
  }
  return node->is_number() ? node->get<double>() : std::nan("");
}

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (const char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

std::string number_text(double value, const char* pattern = "%.6g") {
  if (std::isnan(value)) return "";
  char text[32];
  std::snprintf(text, sizeof text, pattern, value);
  return text;
}

}  // namespace

json batch_options_json(const BatchOptions& options) {
  return {{"proxies", options.proxies},
          {"seed", options.seed},
          {"rays", options.rays},
          {"timed_rays", options.timed_rays},
          {"hausdorff_samples", options.hausdorff_samples},
          {"gssa_lines", options.gssa_lines}};
}

std::vector<fs::path> read_asset_list(const fs::path& list) {
  std::vector<fs::path> assets;
  std::error_code error;
  if (fs::is_directory(list, error)) {
    for (fs::recursive_directory_iterator it(list, error), end; !error && it != end; it.increment(error))
      if (it->is_regular_file(error) && is_mesh_extension(it->path())) assets.push_back(it->path());
    if (error) throw IOError(list, "cannot list the folder: " + error.message());
    std::sort(assets.begin(), assets.end());
  } else {
    std::istringstream lines(read_file(list));
    std::string line;
    while (std::getline(lines, line)) {
      const auto first = line.find_first_not_of(" \t\r");
      if (first == std::string::npos || line[first] == '#') continue;
      const auto last = line.find_last_not_of(" \t\r");
      const fs::path path = line.substr(first, last - first + 1);
      assets.push_back(path.is_absolute() ? path : list.parent_path() / path);
    }
  }
  if (assets.empty())
    throw InvalidInputError(list, fs::is_directory(list, error) ? "the folder holds no mesh file (.obj .ply .off .stl .gltf .glb .fbx .dae .3ds)"
                                                                : "the list names no mesh (one path per line)");
  return assets;
}

std::vector<fs::path> shard_assets(const std::vector<fs::path>& assets, std::size_t index, std::size_t count) {
  if (count == 0 || index >= count)
    throw InvalidInputError("", "shard " + std::to_string(index) + "/" + std::to_string(count) +
                                    ": needs 0 <= I < N");
  std::vector<fs::path> shard;
  for (std::size_t i = index; i < assets.size(); i += count) shard.push_back(assets[i]);
  return shard;
}

std::pair<std::size_t, std::size_t> parse_shard(const std::string& text) {
  const auto slash = text.find('/');
  auto digits = [](const std::string& part) {
    return !part.empty() && part.size() <= 9 && std::all_of(part.begin(), part.end(), [](unsigned char c) { return std::isdigit(c); });
  };
  if (slash != std::string::npos && digits(text.substr(0, slash)) && digits(text.substr(slash + 1))) {
    const std::size_t index = std::stoul(text.substr(0, slash)), count = std::stoul(text.substr(slash + 1));
    if (count > 0 && index < count) return {index, count};
  }
  throw InvalidInputError("", "--shard " + text + ": must be I/N with 0 <= I < N (e.g. 0/4 .. 3/4)");
}

std::string asset_folder_name(const fs::path& mesh, const BatchOptions& options) {
  Fnv1a hash;
  try {
    hash.add(read_file(mesh));
  } catch (const Error&) {
    hash.add("unreadable:" + mesh.generic_string());
  }
  hash.add(std::string(1, '\0') + batch_options_json(options).dump() + '\0' + version());
  std::string stem = mesh.stem().string();
  for (char& c : stem)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-')) c = '-';
  if (stem.empty()) stem = "mesh";
  return stem + "-" + hash.hex();
}

namespace {

// The record of the complete folder ROOT/NAME, or null (missing, or not a valid record).
json complete_record(const fs::path& root, const std::string& name) {
  std::error_code error;
  return fs::exists(root / name / "asset.json", error) ? read_record(root / name / "asset.json") : json(nullptr);
}

}  // namespace

json find_asset_record(const fs::path& root, const std::string& name) {
  if (json record = complete_record(root, name); !record.is_null()) return record;
  std::error_code error;
  if (fs::exists(root / (name + ".failed.json"), error)) return read_record(root / (name + ".failed.json"));
  return nullptr;
}

json record_failure(const fs::path& mesh, const fs::path& root, const std::string& name, const BatchOptions& options,
                    const std::string& error) {
  if (json record = complete_record(root, name); !record.is_null()) return record;
  json record = base_record(mesh, name, options);
  record["folder"] = nullptr;
  record["error"] = one_line(error);
  fs::create_directories(root);
  write_file_atomically(root / (name + ".failed.json"), record.dump(2) + "\n");
  return record;
}

json process_asset(const fs::path& mesh_path, const fs::path& root, const BatchOptions& options, bool retry_failed) {
  const auto start = std::chrono::steady_clock::now();
  std::error_code error;
  fs::create_directories(root, error);
  if (error) throw IOError(root, "cannot create the batch folder: " + error.message());
  const std::string name = asset_folder_name(mesh_path, options);
  const fs::path done = root / name;
  const fs::path failed = root / (name + ".failed.json");
  if (json record = find_asset_record(root, name); !record.is_null()) {
    if (record.value("status", "") != "failed" || !retry_failed) {
      record["resumed"] = true;
      return record;
    }
  }
  json record = base_record(mesh_path, name, options);
  const fs::path partial = root / ".partial" / (name + "." + std::to_string(::getpid()));
  fs::remove_all(partial, error);
  try {
    fs::create_directories(partial);
    const std::vector<ProxySpec> specs = options.proxies.empty() ? default_proxy_specs() : parse_proxy_specs(options.proxies);
    auto warn = [&record](const std::string& warning) { record["warnings"].push_back(warning); };
    const TriangleMesh mesh = read_mesh(mesh_path, {.weld = Weld::automatic, .on_warning = warn});
    record["triangles"] = mesh.triangles.size();
    BuildOptions build{.per_component = false,
                       .hausdorff_samples = options.hausdorff_samples,
                       .seed = options.seed,
                       .on_start = {},
                       .tets = InnerTetrahedra::normals,
                       .gssa_lines = options.gssa_lines,
                       .default_set = options.proxies.empty(),
                       .on_skip = [&warn](std::string_view proxy, std::string_view reason) {
                         warn("skipped " + std::string(proxy) + ": " + std::string(reason));
                       }};
    json manifest = build_proxy_folder(partial, mesh, mesh_path, Weld::automatic, specs, build).manifest;
    std::size_t holding = 0;
    for (json& entry : manifest["proxies"]) {
      const ProxyGeometry geometry = read_proxy_geometry(partial, entry);
      entry["verify"] = verify_proxy(mesh, manifest, entry, geometry,
                                     {.hausdorff_samples = options.hausdorff_samples, .seed = options.seed});
      holding += entry["verify"]["holds"].get<bool>() ? 1 : 0;
    }
    write_manifest(partial, manifest);
    manifest = measure_proxies(mesh, partial, std::move(manifest),
                               {.rays = options.rays, .seed = options.seed, .scene = {}, .timing = {.rays = options.timed_rays},
                                .on_start = {}, .on_warning = warn});
    write_manifest(partial, manifest);
    write_report(partial, manifest, mesh);
    record["proxies"] = manifest["proxies"].size();
    record["claims_holding"] = holding;
    record["status"] = holding == manifest["proxies"].size() ? "ok" : "claims_failed";
    record["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    write_file_atomically(partial / "asset.json", record.dump(2) + "\n");
    // Into place whole. Another worker may have finished the same asset meanwhile (the
    // same bytes listed twice): its folder is as good as this one.
    // A folder in place without a valid record is not finished (edited, or not ours): replaced.
    if (fs::exists(done, error) && complete_record(root, name).is_null()) fs::remove_all(done, error);
    fs::rename(partial, done, error);
    if (error) {
      fs::remove_all(partial, error);
      if (json other = complete_record(root, name); !other.is_null())
        return other;
      throw IOError(done, "cannot move the finished proxy folder into place");
    }
    fs::remove(failed, error);
  } catch (const std::exception& e) {
    // Bad input (Error), and also a library's failure on this one asset (an exhausted
    // memory, a CGAL precondition): the asset fails, the batch goes on.
    fs::remove_all(partial, error);
    record["folder"] = nullptr;
    record["status"] = "failed";
    record["error"] = one_line(dynamic_cast<const Error*>(&e) ? std::string(e.what()) : mesh_path.string() + ": internal error: " + e.what());
    record["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    write_file_atomically(failed, record.dump(2) + "\n");
  }
  record["resumed"] = false;
  return record;
}

json batch_merge(const fs::path& root) {
  std::error_code error;
  if (!fs::is_directory(root, error)) throw IOError(root, "not a batch folder");
  std::vector<json> records;
  for (const fs::directory_entry& item : fs::directory_iterator(root, error)) {
    const fs::path path = item.path();
    const std::string file = path.filename().string();
    if (file.empty() || file[0] == '.') continue;
    json record;
    if (item.is_directory(error) && fs::exists(path / "asset.json", error)) record = read_record(path / "asset.json");
    else if (file.size() > 12 && file.ends_with(".failed.json") && !fs::exists(root / file.substr(0, file.size() - 12) / "asset.json", error))
      record = read_record(path);
    if (!record.is_null()) records.push_back(std::move(record));
  }
  std::sort(records.begin(), records.end(), [](const json& a, const json& b) {
    const std::string x = a.value("asset", ""), y = b.value("asset", "");
    return x != y ? x < y : a.dump() < b.dump();
  });
  json rows = json::array();
  std::size_t ok = 0, claims_failed = 0, failed = 0, proxies = 0;
  for (const json& record : records) {
    const std::string status = record.value("status", "failed");
    ok += status == "ok", claims_failed += status == "claims_failed", failed += status == "failed";
    if (status == "failed") continue;
    const fs::path folder = root / record["folder"].get<std::string>();
    const nlohmann::json manifest = read_manifest(folder);
    // The predicted efficiencies of the asset's report, by proxy.
    // (A folder from before recommendations, or one whose file was damaged, has none.)
    std::map<std::string, json> predicted;
    if (fs::exists(folder / "recommendation.json", error)) {
      json recommendation;
      try {
        recommendation = json::parse(read_file(folder / "recommendation.json"));
      } catch (const json::exception&) {
      }
      if (recommendation.is_object() && recommendation.contains("proxies") && recommendation["proxies"].is_array())
        for (const json& p : recommendation["proxies"])
          if (p.is_object() && p.contains("name") && p["name"].is_string()) predicted[p["name"].get<std::string>()] = p;
    }
    auto efficiency = [&](const json& entry, const char* use) {
      const auto found = predicted.find(entry["name"].get<std::string>());
      return found == predicted.end() ? std::nan("") : value_at(found->second, {use, "efficiency"});
    };
    for (const json& entry : manifest["proxies"]) {
      ++proxies;
      const json* verify = entry.contains("verify") ? &entry["verify"] : nullptr;
      rows.push_back({{"asset", record["asset"]},
                      {"folder", record["folder"]},
                      {"triangles", record["triangles"]},
                      {"proxy", entry["name"]},
                      {"kind", entry["kind"]},
                      {"primitives", entry["primitives"]},
                      {"claim", verify ? (*verify)["claim"] : json(nullptr)},
                      {"holds", verify ? (*verify)["holds"] : json(nullptr)},
                      {"f_hit", value_at(entry, {"measure", "f_hit", "value"})},
                      {"f_miss", value_at(entry, {"measure", "f_miss", "value"})},
                      {"gssa_ratio", value_at(entry, {"measure", "gssa_ratio", "value"})},
                      {"variance", value_at(entry, {"measure", "variance", "optimal"})},
                      {"cost_ratio", value_at(entry, {"measure", "cost_ns_per_ray", "proxy_over_mesh"})},
                      {"build_seconds", entry.value("build_seconds", std::nan(""))},
                      {"efficiency_control_variate", efficiency(entry, "control_variate")},
                      {"efficiency_eq8", efficiency(entry, "eq8")},
                      {"efficiency_bounds", efficiency(entry, "bounds")}});
    }
  }
  // NaN is not JSON: unmeasured figures are null.
  for (json& row : rows)
    for (auto& [key, value] : row.items())
      if (value.is_number_float() && std::isnan(value.get<double>())) value = nullptr;
  json summary{{"format", kSummaryFormat},
               {"format_version", 1},
               {"folder", root.generic_string()},
               {"assets", records.size()},
               {"ok", ok},
               {"claims_failed", claims_failed},
               {"failed", failed},
               {"proxies", proxies},
               {"timed_fields", {"seconds", "build_seconds", "cost_ratio", "efficiency_control_variate", "efficiency_eq8",
                                 "efficiency_bounds"}},
               {"records", records},
               {"rows", rows},
               {"visproxy_version", version()}};

  const std::vector<std::string> columns{"asset", "folder", "triangles", "proxy", "kind", "primitives", "claim", "holds",
                                         "f_hit", "f_miss", "gssa_ratio", "variance", "cost_ratio", "build_seconds",
                                         "efficiency_control_variate", "efficiency_eq8", "efficiency_bounds"};
  auto cell_text = [](const json& value) -> std::string {
    if (value.is_null()) return "";
    if (value.is_string()) return value.get<std::string>();
    if (value.is_boolean()) return value.get<bool>() ? "yes" : "no";
    if (value.is_number_float()) return number_text(value.get<double>());
    return value.dump();
  };
  std::string csv;
  for (const std::string& column : columns) csv += (csv.empty() ? "" : ",") + column;
  csv += ",status,error\n";
  for (const json& row : rows) {
    for (std::size_t c = 0; c < columns.size(); ++c) csv += (c ? "," : "") + csv_field(cell_text(row[columns[c]]));
    csv += ",ok,\n";
  }
  for (const json& record : records)
    if (record.value("status", "") == "failed") {
      csv += csv_field(record.value("asset", "")) + std::string(columns.size() - 1, ',') + ",failed," +
             csv_field(record["error"].is_string() ? record["error"].get<std::string>() : "") + "\n";
    }

  std::vector<std::vector<HtmlCell>> table;
  for (const json& row : rows) {
    std::vector<HtmlCell> cells;
    for (const std::string& column : columns) {
      const json& value = row[column];
      HtmlCell cell;
      cell.text = cell_text(value);
      if (value.is_number()) cell.sort_value = value.get<double>(), cell.number = true;
      if (column == "holds" && value.is_boolean() && !value.get<bool>()) cell.text = "FAILS", cell.css_class = "fails";
      if (column == "asset") cell.link = row["folder"].get<std::string>() + "/report.html";
      cells.push_back(std::move(cell));
    }
    table.push_back(std::move(cells));
  }
  std::string before = "<p>" + std::to_string(records.size()) + " assets in " + escape_html(root.generic_string()) + ": " +
                       std::to_string(ok) + " with every claim holding, " + std::to_string(claims_failed) +
                       " with a claim failing, " + std::to_string(failed) + " failed. One row per asset and proxy (" +
                       std::to_string(proxies) + "); the asset links to its own report.</p>\n";
  std::string after;
  if (failed > 0) {
    after += "<h2>Failed assets</h2>\n<table>\n<thead><tr><th>asset</th><th>error</th></tr></thead>\n<tbody>\n";
    for (const json& record : records)
      if (record.value("status", "") == "failed")
        after += "<tr><td>" + escape_html(record.value("asset", "")) + "</td><td>" +
                 escape_html(record["error"].is_string() ? record["error"].get<std::string>() : "") + "</td></tr>\n";
    after += "</tbody>\n</table>\n";
  }
  after += "<p class=\"notes\">f_hit: of the isotropic lines the mesh blocks, the fraction the proxy blocks; f_miss: of the "
           "free lines, the fraction the proxy lets through; GSSA ratio: proxy-blocked over mesh-blocked lines; variance: "
           "the stochastic estimator's per ray at its optimal probabilities; cost ratio: proxy time per ray over the "
           "mesh's on one core; build seconds: wall time; efficiency: how many times cheaper than tracing the mesh alone "
           "each use of the proxy is predicted to be at equal error (its report's recommendation; bounds only for proved "
           "claims). Written by visproxy " +
           std::string(version()) + " from the asset records in this folder.</p>\n";
  const std::string html = sortable_table_page("visproxy batch: " + root.generic_string(), before, columns, table, after);

  write_file_atomically(root / "summary.json", summary.dump(2) + "\n");
  write_file_atomically(root / "summary.csv", csv);
  write_file_atomically(root / "summary.html", html);
  return summary;
}

}  // namespace visproxy
