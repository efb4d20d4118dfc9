#include "visproxy/asset/float_proxy.h"

#include <cmath>
#include <limits>

#include "visproxy/core/errors.h"
#include "visproxy/folder/verdict.h"
#include "visproxy/mesh/sphere_set.h"

namespace visproxy {
namespace {

// `value` in float, rounded to nearest (direction 0) or toward the sign of `direction`.
float round_directed(double value, double direction) {
  float f = static_cast<float>(value);
  if (direction > 0 && static_cast<double>(f) < value) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  if (direction < 0 && static_cast<double>(f) > value) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}

// Area-weighted vertex normals (the sum of the cross products of the triangles around
// each vertex), unit length; zero where they cancel.
std::vector<Vertex> vertex_normals(const TriangleMesh& mesh) {
  std::vector<Vertex> normals(mesh.positions.size(), Vertex::Zero());
  for (const Triangle& t : mesh.triangles) {
    const Vertex n = (mesh.positions[t[1]] - mesh.positions[t[0]]).cross(mesh.positions[t[2]] - mesh.positions[t[0]]);
    for (const VertexIndex v : t) normals[v] += n;
  }
  for (Vertex& n : normals) {
    const double length = n.norm();
    n = length > 0 && std::isfinite(length) ? Vertex(n / length) : Vertex::Zero();
  }
  return normals;
}

// The proxy's triangles: its mesh, or a sphere set's icospheres (vertices on the spheres).
TriangleMesh proxy_triangles(const ProxyGeometry& proxy) {
  return proxy.type == PrimitiveType::sphere ? sphere_set_mesh(proxy.spheres, 2) : proxy.mesh;
}

// `mesh` in float, each vertex moved by `distance` along `normals` (scaled by `sign`) and
// rounded in the direction of the move (to nearest when distance is 0).
std::vector<float> rounded(const TriangleMesh& mesh, const std::vector<Vertex>& normals, double distance, double sign) {
  std::vector<float> out;
  out.reserve(3 * mesh.positions.size());
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    const Vertex direction = distance > 0 ? Vertex(sign * normals[v]) : Vertex::Zero();
    const Vertex p = mesh.positions[v] + distance * direction;
    for (int axis = 0; axis < 3; ++axis) out.push_back(round_directed(p[axis], direction[axis]));
  }
  return out;
}

}  // namespace

TriangleMesh FloatProxy::mesh() const {
  TriangleMesh out;
  out.positions.reserve(positions.size() / 3);
  for (std::size_t i = 0; i + 2 < positions.size(); i += 3)
    out.positions.emplace_back(positions[i], positions[i + 1], positions[i + 2]);
  out.triangles.reserve(indices.size() / 3);
  for (std::size_t i = 0; i + 2 < indices.size(); i += 3)
    out.triangles.push_back({indices[i], indices[i + 1], indices[i + 2]});
  return out;
}

FloatProxy round_proxy_to_float(const TriangleMesh& mesh, const nlohmann::json& manifest, const nlohmann::json& entry,
                                const ProxyGeometry& proxy, const std::filesystem::path& folder) {
  const TriangleMesh triangles = proxy_triangles(proxy);
  double magnitude = 0;
  for (const Vertex& p : triangles.positions) magnitude = std::max(magnitude, p.cwiseAbs().maxCoeff());
  if (!(magnitude <= static_cast<double>(std::numeric_limits<float>::max()) / 2))
    throw InvalidInputError(folder / entry.value("file", entry.value("name", std::string("proxy"))),
                            "a coordinate of magnitude " + std::to_string(magnitude) + " is beyond float32's range");

  FloatProxy out;
  out.claimed = entry_kind(entry);
  out.indices.reserve(3 * triangles.triangles.size());
  for (const Triangle& t : triangles.triangles) out.indices.insert(out.indices.end(), t.begin(), t.end());
  const std::vector<Vertex> normals = vertex_normals(triangles);
  out.positions = rounded(triangles, normals, 0, 0);
  if (out.claimed == ProxyKind::general) {
    out.verify = nullptr;
    return out;
  }

  // The entry as it is proved here: the float geometry is triangles whatever it was.
  nlohmann::json as_triangles = entry;
  as_triangles["primitive_type"] = "triangle";
  as_triangles.erase("files");
  const double sign = out.claimed == ProxyKind::outside ? 1.0 : -1.0;
  // One float ulp at the largest magnitude (2^-23 of the power of two at or below it).
  const double ulp = magnitude > 0 ? std::ldexp(1.0, std::ilogb(magnitude) - 23) : std::numeric_limits<float>::min();
  const std::vector<float> nearest = out.positions;
  nlohmann::json nearest_verdict;  // the verdict on the geometry exported when no try holds
  std::string problem;
  for (int attempt = 0; attempt <= 3; ++attempt) {
    const double distance = attempt == 0 ? 0.0 : ulp * std::ldexp(1.0, 2 * (attempt - 1));
    std::vector<float> positions = attempt == 0 ? nearest : rounded(triangles, normals, distance, sign);
    out.positions = std::move(positions);
    ProxyGeometry geometry;
    geometry.type = PrimitiveType::triangle;
    geometry.mesh = out.mesh();
    nlohmann::json verdict = verify_proxy(mesh, manifest, as_triangles, geometry);
    if (verdict.at("holds").get<bool>()) {
      out.kind = out.claimed;
      out.moved = distance;
      out.verify = std::move(verdict);
      return out;
    }
    if (attempt == 0) {  // the counterexample named is the exported geometry's
      problem = verdict.contains("counterexample") && verdict["counterexample"].is_string()
                         ? verdict["counterexample"].get<std::string>()
                         : std::string("the claim does not hold");
      nearest_verdict = std::move(verdict);
    }
  }
  out.positions = nearest;
  out.verify = std::move(nearest_verdict);
  out.kind = ProxyKind::general;
  out.note = "its " + std::string(kind_name(out.claimed)) + " claim did not survive rounding to float32 (" +
             problem + "), so it is exported as general";
  return out;
}

}  // namespace visproxy
