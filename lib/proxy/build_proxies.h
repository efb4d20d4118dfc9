#pragma once
// `visproxy build`: every requested proxy of one mesh, with what each reached.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "mesh/triangle_mesh.h"
#include "proxy/bounding_boxes.h"
#include "proxy/proxy_spec.h"

namespace visproxy {

enum class PrimitiveType { triangle, box, sphere };
std::string_view primitive_type_name(PrimitiveType type);

struct BuiltProxy {
  ProxySpec spec;
  std::string method;     ///< how it was made, in words ("CGAL 3D alpha wrap")
  nlohmann::json params;  ///< parameters as applied, relative and in mesh units
  PrimitiveType primitive_type = PrimitiveType::triangle;
  std::size_t primitives = 0;      ///< boxes, triangles or spheres
  TriangleMesh mesh;               ///< the proxy as triangles (boxes as their 12 triangles)
  std::vector<OrientedBox> boxes;  ///< box proxies: one per component
  double build_seconds = 0;        ///< wall time of the builder alone (not of the error measurement)
  nlohmann::json result;           ///< what the builder reached: bounds, volumes, per-component figures
  nlohmann::json error;            ///< sampled two-sided Hausdorff distance to the mesh
};

struct BuildOptions {
  /// One proxy per connected component (triangles sharing a vertex), joined into one
  /// file; counts such as N apply to each component.
  bool per_component = false;
  std::size_t hausdorff_samples = 20000;  ///< area-uniform samples per surface for the error
  std::uint64_t seed = 1;                 ///< seeds the error's samples and CGAL's box search
  /// Called before each proxy is built with its name (progress display); may be empty.
  std::function<void(std::string_view)> on_start;
};

/// Builds every spec for `mesh`, in order. `source` names the mesh in error messages:
/// input a builder cannot handle (no triangles, collinear vertices, ...) throws
/// InvalidInputError("SOURCE", "SPEC: problem").
std::vector<BuiltProxy> build_proxies(const TriangleMesh& mesh, const std::filesystem::path& source,
                                      std::span<const ProxySpec> specs, const BuildOptions& options = {});

}  // namespace visproxy
