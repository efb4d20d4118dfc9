#include "evaluate/verify_proxy.h"

#include <chrono>
#include <cstdio>
#include <string>

#include "core/errors.h"
#include "mesh/mesh_topology.h"
#include "proxy/surface_distance.h"
#include "verify/containment.h"
#include "verify/sphere_containment.h"

namespace visproxy {
namespace {

using nlohmann::json;

std::string point_text(const Vertex& p) {
  char buffer[96];
  std::snprintf(buffer, sizeof buffer, "(%.9g, %.9g, %.9g)", p.x(), p.y(), p.z());
  return buffer;
}

bool is_convex_method(const json& entry) {
  const std::string spec = entry.value("spec", "");
  const std::string method = spec.substr(0, spec.find(':'));
  return method == "aabb" || method == "obb" || method == "hull";
}

// The container holds the contents (both triangle meshes). `names` say which is which in
// the counterexample ("mesh vertex 12 ... is outside the proxy").
json check_mesh_containment(const TriangleMesh& container, const TriangleMesh& contents, bool convex_parts,
                            const char* contents_name, const char* container_name) {
  const Containment containment =
      check_containment(container, contents, {.check_surface = !convex_parts, .convex_components = convex_parts});
  json result = {{"checked",
                  {{"vertices", containment.vertices_checked},
                   {"vertices_on_surface", containment.vertices_on_boundary},
                   {"triangles_tested", convex_parts ? "each in one convex part" : "no surface contact"}}}};
  result["holds"] = containment.contained();
  std::string counterexample;
  if (containment.first_vertex_outside) {
    const Vertex& p = contents.positions[*containment.first_vertex_outside];
    counterexample = std::string(contents_name) + " vertex " + std::to_string(*containment.first_vertex_outside) + " " +
                     point_text(p) + " is outside the " + container_name;
    const std::vector<Vertex> outside{p};
    result["margin"] = -closest_distance_to_surface(container, outside).distance;
  } else if (containment.first_crossing) {
    counterexample = std::string(contents_name) + " triangle " + std::to_string(containment.first_crossing->second) +
                     " meets " + container_name + " triangle " + std::to_string(containment.first_crossing->first);
    result["margin"] = 0.0;
  } else if (containment.first_triangle_split) {
    counterexample = std::string(contents_name) + " triangle " + std::to_string(*containment.first_triangle_split) +
                     " has its corners in different convex parts of the " + container_name;
    result["margin"] = 0.0;
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

std::string closed_mesh_problem(const TriangleMesh& mesh) {
  const MeshTopology topology = analyze_topology(mesh);
  if (!topology.closed()) return "the mesh has " + std::to_string(topology.boundary_edges) + " boundary edges, so it has no inside";
  if (!topology.manifold()) return "the mesh is not manifold, so its inside is not defined";
  if (!topology.consistently_oriented()) return "the mesh is not consistently oriented, so its inside is not defined";
  return {};
}

}  // namespace

json verify_proxy(const TriangleMesh& mesh, const json& manifest, const json& entry, const ProxyGeometry& proxy,
                  const VerifyOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const ProxyKind kind = entry_kind(entry);
  json result;
  switch (kind) {
    case ProxyKind::outside: {
      result = check_mesh_containment(proxy.mesh, mesh, is_convex_method(entry), "mesh", "proxy");
      result["claim"] = "contains the mesh";
      break;
    }
    case ProxyKind::inside: {
      result["claim"] = "lies within the mesh";
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
      json checked = check_mesh_containment(mesh, proxy.mesh, false, "proxy", "mesh");
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
      result = {{"claim", "none"},
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
  result["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace visproxy
