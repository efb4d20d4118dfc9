#include "visproxy/folder/verdict.h"

#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/mesh_topology.h"
#include "visproxy/proxy/surface_distance.h"
#include "visproxy/verify/containment.h"
#include "visproxy/verify/sphere_containment.h"

namespace visproxy {
namespace {

using nlohmann::json;

std::string point_text(const Vertex& p) {
  char buffer[96];
  std::snprintf(buffer, sizeof buffer, "(%.9g, %.9g, %.9g)", p.x(), p.y(), p.z());
  return buffer;
}

// The container holds the contents (both triangle meshes). `names` say which is which in
// the counterexample ("mesh vertex 12 ... is outside the proxy"). With `solid`, the
// contents' solid must lie in the container's (an inside proxy made of triangles).
json check_mesh_containment(const TriangleMesh& container, const TriangleMesh& contents, bool solid,
                            const char* contents_name, const char* container_name) {
  const Containment containment = check_containment(container, contents, {.check_surface = true, .contents_solid = solid});
  json result = {{"checked",
                  {{"vertices", containment.vertices_checked},
                   {"vertices_on_surface", containment.vertices_on_boundary},
                   {"triangles_touching", containment.triangles_touching},
                   {"triangles_in_convex_parts", containment.triangles_in_convex_parts},
                   {"convex_container", containment.convex_container}}}};
  result["holds"] = containment.contained();
  auto open_edge = [](const EdgeBalance& edges) {
    return "edge " + std::to_string(edges.first_low) + "-" + std::to_string(edges.first_high) + " is used " +
           std::to_string(edges.first_forward) + " times from " + std::to_string(edges.first_low) + " and " +
           std::to_string(edges.first_backward) + " times from " + std::to_string(edges.first_high) + " (" +
           std::to_string(edges.unbalanced_edges) + " such edges)";
  };
  std::string counterexample;
  result["margin"] = 0.0;
  if (!containment.container_edges.balanced()) {
    counterexample = std::string("the ") + container_name + " is not closed, so it bounds no solid: its " +
                     open_edge(containment.container_edges);
    result["margin"] = nullptr;
  } else if (!containment.contents_edges.balanced()) {
    counterexample = std::string("the ") + contents_name + " is not closed, so it bounds no solid: its " +
                     open_edge(containment.contents_edges);
    result["margin"] = nullptr;
  } else if (containment.first_vertex_outside) {
    const Vertex& p = contents.positions[*containment.first_vertex_outside];
    counterexample = std::string(contents_name) + " vertex " + std::to_string(*containment.first_vertex_outside) + " " +
                     point_text(p) + " is outside the " + container_name;
    const std::vector<Vertex> outside{p};
    result["margin"] = -closest_distance_to_surface(container, outside).distance;
  } else if (containment.first_unproved) {
    counterexample = std::string(contents_name) + " triangle " + std::to_string(containment.first_unproved->second) +
                     " meets " + container_name + " triangle " + std::to_string(containment.first_unproved->first) +
                     (solid ? "" : " and lies in no convex part of the " + std::string(container_name));
  } else if (containment.first_container_vertex_inside) {
    counterexample = std::string(container_name) + " vertex " + std::to_string(*containment.first_container_vertex_inside) +
                     " " + point_text(container.positions[*containment.first_container_vertex_inside]) +
                     " lies inside the " + contents_name + ", so the " + contents_name + "'s solid holds part of the " +
                     container_name + "'s surface";
  } else if (containment.vertices_on_boundary > 0) {
    result["margin"] = 0.0;  // a contents vertex lies exactly on the container's surface
  } else {
    result["margin"] = closest_distance_to_surface(container, used_positions(contents)).distance;
  }
  result["counterexample"] = counterexample.empty() ? json(nullptr) : json(counterexample);
  return result;
}

json check_sphere_containment(const TriangleMesh& mesh, const std::vector<Sphere>& spheres) {
  const SphereContainment containment = check_spheres_inside(mesh, spheres);
  json result = {{"checked", {{"spheres", containment.spheres_checked}}},
                 {"holds", containment.contained()},
                 {"margin", containment.min_margin_world}};
  if (containment.first_outside) {
    const Sphere& sphere = spheres[*containment.first_outside];
    char radius[32];
    std::snprintf(radius, sizeof radius, "%.9g", sphere.radius);
    result["counterexample"] = "sphere " + std::to_string(*containment.first_outside) + " (centre " +
                               point_text(sphere.center) + ", radius " + radius + ") is not inside the mesh";
  } else {
    result["counterexample"] = nullptr;
  }
  return result;
}

// Why the mesh bounds no solid, or nothing: closed means every edge used as often in
// each direction (self-intersections and non-manifold edges are fine).
std::string closed_mesh_problem(const TriangleMesh& mesh) {
  const EdgeBalance edges = check_edge_balance(mesh);
  if (edges.balanced()) return {};
  const MeshTopology topology = analyze_topology(mesh);
  if (topology.boundary_edges > 0)
    return "the mesh has " + std::to_string(topology.boundary_edges) + " boundary edges, so it has no inside";
  return "the mesh is not closed: " + std::to_string(edges.unbalanced_edges) +
         " edges are not used as often in one direction as in the other (inconsistent orientation), so its inside is not defined";
}

}  // namespace

json verify_proxy(const TriangleMesh& mesh, const json& manifest, const json& entry, const ProxyGeometry& proxy,
                  const VerifyOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const ProxyKind kind = entry_kind(entry);
  json result;
  switch (kind) {
    case ProxyKind::outside: {
      if (proxy.type == PrimitiveType::sphere) {
        result = {{"holds", false}, {"margin", nullptr}, {"checked", json::object()},
                  {"counterexample", "an outside claim is proved for triangle proxies only, and this proxy is a sphere set"}};
        result["claim"] = kind_claim(kind);
        break;
      }
      result = check_mesh_containment(proxy.mesh, mesh, false, "mesh", "proxy");
      result["claim"] = kind_claim(kind);
      break;
    }
    case ProxyKind::inside: {
      result["claim"] = kind_claim(kind);
      if (const std::string problem = closed_mesh_problem(mesh); !problem.empty()) {
        result["holds"] = false;
        result["margin"] = nullptr;
        result["counterexample"] = problem;
        break;
      }
      if (proxy.type == PrimitiveType::sphere) {
        result.update(check_sphere_containment(mesh, proxy.spheres));
        break;
      }
      json checked = check_mesh_containment(mesh, proxy.mesh, true, "proxy", "mesh");
      checked["claim"] = result["claim"];
      result = std::move(checked);
      break;
    }
    case ProxyKind::general: {
      // Sphere sets are measured through the boundary of their union, as polyhedra with
      // vertices on the spheres (level-2 icospheres: within 1.3 % of each radius).
      const SurfaceDistance distance = sampled_hausdorff_distance(
          proxy.type == PrimitiveType::sphere ? sphere_union_boundary_mesh(proxy.spheres, 2) : proxy.mesh, mesh,
          {.samples_per_mesh = options.hausdorff_samples, .seed = options.seed});
      const double diagonal = manifest.at("mesh").at("bbox").at("diagonal").get<double>();
      result = {{"claim", kind_claim(kind)},
                {"holds", true},
                {"margin", nullptr},
                {"counterexample", nullptr},
                {"hausdorff_world", distance.hausdorff_world()},
                {"hausdorff_relative", diagonal > 0 ? distance.hausdorff_world() / diagonal : 0.0},
                {"samples_per_surface", options.hausdorff_samples},
                {"seed", options.seed}};
      break;
    }
  }
  // The folder ships every file of the entry: one that does not hold the geometry proved
  // above breaks the claim (named after the geometry's own counterexample, if any).
  if (!proxy.files_problem.empty()) {
    result["holds"] = false;
    if (!result["counterexample"].is_string()) result["counterexample"] = "the folder's files disagree: " + proxy.files_problem;
  }
  result["kind"] = kind_name(kind);
  result["file"] = entry.value("file", std::string());
  result["files"] = entry.contains("files") ? entry.at("files") : json::array();
  result["mesh_hash"] = content_hash(mesh);
  result["proxy_hash"] = proxy_content_hash(proxy);
  result["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

std::string proxy_content_hash(const ProxyGeometry& proxy) {
  std::vector<unsigned char> bytes(proxy.spheres.size() * 4 * sizeof(double));
  for (std::size_t i = 0; i < proxy.spheres.size(); ++i) {
    const double values[4] = {proxy.spheres[i].center.x(), proxy.spheres[i].center.y(), proxy.spheres[i].center.z(),
                              proxy.spheres[i].radius};
    std::memcpy(bytes.data() + i * sizeof values, values, sizeof values);
  }
  return content_hash(proxy.mesh, bytes);
}

std::string_view kind_claim(ProxyKind kind) {
  switch (kind) {
    case ProxyKind::outside: return "contains the mesh";
    case ProxyKind::inside: return "lies within the mesh";
    case ProxyKind::general: break;
  }
  return "none";
}

bool verdict_proves(const json& verify, const json& entry, const TriangleMesh& mesh, const ProxyGeometry& proxy) {
  const ProxyKind kind = entry_kind(entry);
  if (kind == ProxyKind::general || !proxy.files_problem.empty() || !verify.is_object()) return false;
  const json files = entry.contains("files") ? entry.at("files") : json::array();
  return verify.value("holds", false) == true && verify.value("claim", std::string()) == kind_claim(kind) &&
         verify.value("kind", std::string()) == kind_name(kind) && verify.value("file", std::string()) == entry.value("file", std::string("")) &&
         verify.contains("files") && verify.at("files") == files && verify.value("mesh_hash", std::string()) == content_hash(mesh) &&
         verify.value("proxy_hash", std::string()) == proxy_content_hash(proxy);
}

}  // namespace visproxy
