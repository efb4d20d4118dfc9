#include "visproxy/asset/export_proxies.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstring>
#include <optional>
#include <set>

#include "visproxy/asset/gltf_document.h"
#include "visproxy/core/files.h"
#include "visproxy/core/version.h"
#include "visproxy/folder/asset_folder.h"
#include "visproxy/folder/verdict.h"

namespace visproxy {
namespace {

using json = nlohmann::json;

std::string lower_extension(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension;
}

// The shortest decimal that reads back as `value` in double: for a float's value, float
// readers get the same float too (the decimal is within 2^-53 of it).
std::string decimal(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

// One proxy folder's share of the export: the whole asset's folder, or one part's.
struct Group {
  std::string prefix = {};            // names its objects: PREFIX.PROXY
  std::filesystem::path folder = {};  // its proxy folder
  std::filesystem::path mesh_path = {};
  json manifest = {};
  TriangleMesh mesh = {};    // the source mesh (the part's, in its own coordinates)
  json instances = nullptr;  // the part's instances (null for the whole asset, placed in its world)
  std::vector<json> entries = {};
  std::size_t first = 0;  // its proxies' index in ExportResult::proxies
};

json extras_of(const ExportedProxy& proxy, const json& entry, const std::filesystem::path& source,
               const TriangleMesh& mesh) {
  const FloatProxy& g = proxy.geometry;
  json object = {{"shadow_only", true},
                 {"proxy", proxy.name},
                 {"spec", entry.value("spec", std::string())},
                 {"kind", kind_name(g.kind)},
                 {"claim", kind_claim(g.kind)},
                 {"proved", g.kind != ProxyKind::general},
                 {"primitive_type", entry.value("primitive_type", std::string("triangle"))},
                 {"source", source.filename().string()},
                 {"mesh_hash", content_hash(mesh)},
                 {"proxy_hash", content_hash(g.mesh())},
                 {"moved", g.moved},
                 {"generator", std::string("visproxy ") + version()}};
  if (!proxy.part.empty()) object["part"] = proxy.part;
  if (entry.value("primitive_type", std::string()) == "sphere")
    object["drawn_as"] = "icospheres with their vertices on the spheres";
  if (g.kind != ProxyKind::general) object["margin"] = g.verify.value("margin", json());
  if (!g.note.empty()) object["note"] = g.note;
  return {{"visproxy", object}};
}

std::string obj_object(const std::string& name, const TriangleMesh& mesh, std::size_t& base, const json& comment) {
  std::string out;
  if (!comment.is_null()) out += "# visproxy " + comment.dump() + "\n";
  out += "o " + name + "\n";
  for (const Vertex& p : mesh.positions)
    out += "v " + decimal(p.x()) + " " + decimal(p.y()) + " " + decimal(p.z()) + "\n";
  for (const Triangle& t : mesh.triangles)
    out += "f " + std::to_string(base + t[0] + 1) + " " + std::to_string(base + t[1] + 1) + " " +
           std::to_string(base + t[2] + 1) + "\n";
  base += mesh.positions.size();
  return out;
}

std::string ply_bytes(const FloatProxy& proxy, const json& comment) {
  std::string out = "ply\nformat binary_little_endian 1.0\ncomment visproxy " + comment.dump() + "\nelement vertex " +
                    std::to_string(proxy.positions.size() / 3) +
                    "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
                    std::to_string(proxy.indices.size() / 3) +
                    "\nproperty list uchar uint vertex_indices\nend_header\n";
  const std::size_t header = out.size();
  out.resize(header + proxy.positions.size() * 4);
  std::memcpy(out.data() + header, proxy.positions.data(), proxy.positions.size() * 4);  // little-endian hosts only
  for (std::size_t i = 0; i < proxy.indices.size(); i += 3) {
    out.push_back(3);
    const std::size_t at = out.size();
    out.resize(at + 12);
    std::memcpy(out.data() + at, proxy.indices.data() + i, 12);
  }
  return out;
}

bool gltf_source(const std::filesystem::path& path) {
  const std::string extension = lower_extension(path);
  return extension == ".gltf" || extension == ".glb";
}

std::pair<std::vector<float>, std::vector<std::uint32_t>> float_mesh(const TriangleMesh& mesh) {
  std::vector<float> positions;
  positions.reserve(3 * mesh.positions.size());
  for (const Vertex& p : mesh.positions)
    for (int axis = 0; axis < 3; ++axis) positions.push_back(static_cast<float>(p[axis]));
  std::vector<std::uint32_t> indices;
  indices.reserve(3 * mesh.triangles.size());
  for (const Triangle& t : mesh.triangles) indices.insert(indices.end(), t.begin(), t.end());
  return {std::move(positions), std::move(indices)};
}

// The glTF node Assimp's node at `path` (child indices from its root) was made from: its
// root is the default scene's one root node, or stands above several. Checked by name.
std::size_t gltf_node_at(const json& document, const json& instance, const std::filesystem::path& source) {
  const std::string node_name = instance.at("node").get<std::string>();
  const auto fail = [&]() -> std::size_t {
    throw InvalidInputError(source, "its node hierarchy is not the one the proxy folder records (node " +
                                        json(node_name).dump() + "): build the folder again from this file");
  };
  const json& scenes = document.value("scenes", json::array());
  const std::size_t scene = document.value("scene", std::size_t{0});
  if (scene >= scenes.size()) return fail();
  const json& roots = scenes[scene].value("nodes", json::array());
  const json& nodes = document.value("nodes", json::array());
  const std::vector<std::uint32_t> path = instance.at("path").get<std::vector<std::uint32_t>>();
  std::size_t step = 0;
  std::size_t node = 0;
  if (roots.size() == 1) {
    node = roots[0].get<std::size_t>();
  } else {
    if (path.empty() || path[0] >= roots.size()) return fail();
    node = roots[path[0]].get<std::size_t>();
    step = 1;
  }
  for (; step < path.size(); ++step) {
    if (node >= nodes.size()) return fail();
    const json& children = nodes[node].value("children", json::array());
    if (path[step] >= children.size()) return fail();
    node = children[path[step]].get<std::size_t>();
  }
  if (node >= nodes.size()) return fail();
  if (nodes[node].contains("name") && nodes[node]["name"] != node_name) return fail();
  return node;
}

json gltf_matrix(const Eigen::Affine3d& transform) {
  if (transform.matrix() == Eigen::Matrix4d::Identity()) return nullptr;
  json matrix = json::array();
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) matrix.push_back(static_cast<float>(transform.matrix()(r, c)));
  return matrix;
}

}  // namespace

ExportFormat export_format(const std::filesystem::path& path) {
  const std::string extension = lower_extension(path);
  if (extension == ".glb") return ExportFormat::glb;
  if (extension == ".gltf") return ExportFormat::gltf;
  if (extension == ".obj") return ExportFormat::obj;
  if (extension == ".ply") return ExportFormat::ply;
  throw InvalidInputError(path, "unknown export format '" + extension + "' (one of .glb, .gltf, .obj, .ply)");
}

ExportResult export_proxies(const std::filesystem::path& folder, const std::filesystem::path& out,
                            const ExportOptions& options) {
  ExportResult result;
  result.path = out;
  result.format = export_format(out);

  // The proxy folders: the folder itself, or each built part of an asset folder (its mesh
  // read from the asset, which is read once).
  std::vector<Group> groups;
  const bool per_part = is_asset_folder(folder);
  if (per_part) {
    result.source = options.source.empty()
                        ? std::filesystem::path(read_asset_manifest(folder).at("source").get<std::string>())
                        : options.source;
  } else {
    groups.push_back({.prefix = {}, .folder = folder, .manifest = read_manifest(folder)});
    result.source = options.source.empty()
                        ? std::filesystem::path(groups[0].manifest.at("mesh").at("path").get<std::string>())
                        : options.source;
    groups[0].mesh_path = result.source;
    groups[0].prefix = result.source.stem().string();
  }
  if (!std::filesystem::exists(result.source))
    throw InvalidInputError(
        folder / (per_part ? "asset.json" : "manifest.json"),
        "the mesh it was built from, " + result.source.string() + ", does not exist here (name it with --mesh)");
  if (per_part)
    for (BuiltPart& part : read_built_parts(folder, result.source).parts)
      groups.push_back({.prefix = part.name,
                        .folder = part.folder,
                        .mesh_path = part.mesh_path,
                        .manifest = std::move(part.manifest),
                        .mesh = std::move(part.mesh),
                        .instances = part.listing.at("instances")});

  // The proxies asked for, in each manifest's order; a name no folder lists is an error.
  std::set<std::string> known;
  for (const Group& group : groups)
    for (const json& entry : group.manifest.at("proxies")) known.insert(entry.at("name").get<std::string>());
  for (const std::string& name : options.proxies)
    if (known.count(name) == 0)
      throw InvalidInputError(folder / "manifest.json", "lists no proxy named '" + name + "'");
  std::size_t count = 0;
  for (Group& group : groups) {
    for (const json& entry : group.manifest.at("proxies"))
      if (options.proxies.empty() || std::find(options.proxies.begin(), options.proxies.end(),
                                               entry.at("name").get<std::string>()) != options.proxies.end())
        group.entries.push_back(entry);
    count += group.entries.size();
  }
  if (count == 0) throw InvalidInputError(folder / "manifest.json", "lists no proxies to export");
  if (result.format == ExportFormat::ply && count != 1)
    throw InvalidInputError(out, "a PLY file holds one mesh: choose one of the folder's " + std::to_string(count) +
                                     " proxies (--proxy NAME)");

  for (Group& group : groups) {
    if (group.entries.empty()) continue;
    if (!per_part) group.mesh = read_manifest_mesh(group.mesh_path, group.manifest, options.on_warning);
    group.first = result.proxies.size();
    for (const json& entry : group.entries) {
      const std::string name = entry.at("name").get<std::string>();
      if (options.on_proxy) options.on_proxy(group.instances.is_null() ? name : group.prefix + "." + name);
      const ProxyGeometry geometry = read_proxy_geometry(group.folder, entry);
      result.proxies.push_back(
          {.name = name,
           .part = group.instances.is_null() ? std::string() : group.prefix,
           .node = group.prefix + "." + name,
           .geometry = round_proxy_to_float(group.mesh, group.manifest, entry, geometry, group.folder)});
    }
  }

  std::string bytes;
  switch (result.format) {
    case ExportFormat::glb:
    case ExportFormat::gltf: {
      const bool keep_source = gltf_source(result.source);
      GltfDocument document =
          keep_source ? GltfDocument::read(result.source) : GltfDocument::empty(std::string("visproxy ") + version());
      if (keep_source) document.move_uris(result.source.parent_path(), out.parent_path());
      for (const Group& group : groups) {
        if (group.entries.empty()) continue;
        // The nodes the proxies hang under: the source's own (a glTF source), or new ones
        // holding the source mesh as read; none for a whole asset placed in its world.
        std::vector<std::optional<std::size_t>> parents;
        if (keep_source) {
          if (group.instances.is_null())
            parents.push_back(std::nullopt);
          else
            for (const json& instance : group.instances)
              parents.push_back(gltf_node_at(document.json(), instance, result.source));
        } else {
          const auto [positions, indices] = float_mesh(group.mesh);
          const std::size_t mesh_index = document.add_mesh(group.prefix, positions, indices);
          if (group.instances.is_null()) {
            document.add_node(group.prefix, mesh_index, std::nullopt, json());
            parents.push_back(std::nullopt);
          } else {
            for (const json& instance : group.instances)
              parents.push_back(document.add_node(instance.at("node").get<std::string>(), mesh_index, std::nullopt,
                                                  json(), gltf_matrix(instance_transform(instance))));
          }
        }
        for (std::size_t i = 0; i < group.entries.size(); ++i) {
          const ExportedProxy& proxy = result.proxies[group.first + i];
          const std::size_t mesh_index =
              document.add_mesh(proxy.node, proxy.geometry.positions, proxy.geometry.indices);
          const json extras = extras_of(proxy, group.entries[i], result.source, group.mesh);
          for (const std::optional<std::size_t>& parent : parents)
            document.add_node(proxy.node, mesh_index, parent, extras);
        }
      }
      bytes = result.format == ExportFormat::glb ? document.glb() : document.gltf();
      break;
    }
    case ExportFormat::obj: {
      bytes = "# " + out.filename().string() + ": " + result.source.filename().string() + " and " +
              std::to_string(result.proxies.size()) + " visproxy proxies (shadow casters only), written by visproxy " +
              version() +
              (groups.size() > 1 || !groups[0].instances.is_null() ? "; each part in its own coordinates" : "") + "\n";
      std::size_t base = 0;
      for (const Group& group : groups) {
        if (group.entries.empty()) continue;
        bytes += obj_object(group.prefix, group.mesh, base, json());
        for (std::size_t i = 0; i < group.entries.size(); ++i) {
          const ExportedProxy& proxy = result.proxies[group.first + i];
          bytes += obj_object(proxy.node, proxy.geometry.mesh(), base,
                              extras_of(proxy, group.entries[i], result.source, group.mesh)["visproxy"]);
        }
      }
      break;
    }
    case ExportFormat::ply:
      for (const Group& group : groups)
        if (!group.entries.empty())
          bytes = ply_bytes(
              result.proxies[group.first].geometry,
              extras_of(result.proxies[group.first], group.entries[0], result.source, group.mesh)["visproxy"]);
      break;
  }
  std::error_code error;  // a folder that cannot be made: write_file_atomically names the problem
  if (!out.parent_path().empty()) std::filesystem::create_directories(out.parent_path(), error);
  write_file_atomically(out, bytes);
  return result;
}

}  // namespace visproxy
