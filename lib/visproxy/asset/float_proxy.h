#pragma once
// A proxy in single precision, as asset formats store it (glTF's positions are float32),
// with its claim proved again on the rounded coordinates.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "visproxy/core/proxy_kind.h"
#include "visproxy/folder/proxy_folder.h"
#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

/// A proxy's triangles in float32, and what is proved of exactly these coordinates.
struct FloatProxy {
  std::vector<float> positions;            ///< x y z per vertex
  std::vector<std::uint32_t> indices;      ///< 3 per triangle
  ProxyKind claimed = ProxyKind::general;  ///< the manifest's kind
  /// The kind the float geometry keeps: `claimed` when verify_proxy proves it on these very
  /// coordinates, else general.
  ProxyKind kind = ProxyKind::general;
  /// How far (mesh units) each vertex was moved along its normal before rounding, outward
  /// for an outside claim and inward for an inside one: 0 when rounding to nearest kept the
  /// claim. Each coordinate is then rounded in the direction of that move.
  double moved = 0;
  /// verify_proxy's verdict on the float geometry exported (null for general proxies; the
  /// failed verdict on the nearest rounding when the claim was dropped)
  nlohmann::json verify;
  std::string note;       ///< why a claim was dropped, or empty

  /// The float geometry as a double mesh (every value exact).
  TriangleMesh mesh() const;
};

/// Rounds `proxy` (read from its folder; sphere sets become their icospheres, whose
/// vertices lie on the spheres, so that each polyhedron lies within its ball) to float32
/// so that its claim still holds, and proves that claim again with verify_proxy on the
/// rounded coordinates against `mesh`:
///   1. every coordinate rounded to nearest;
///   2. if that breaks the claim, every vertex moved by d along its area-weighted normal
///      (outward for outside claims, inward for inside) and each coordinate rounded in the
///      direction of the move, for d = 1, 4 and 16 float ulps of the largest coordinate
///      magnitude, until the claim is proved. The moves only make up for rounding (half an
///      ulp per coordinate): a proxy that needs more does not hold its claim as it is.
/// When no try proves it, the float geometry is the nearest rounding, its kind general and
/// `note` names the last counterexample. General proxies are rounded to nearest and not
/// verified. Throws InvalidInputError naming `folder` when a coordinate is beyond float's range.
FloatProxy round_proxy_to_float(const TriangleMesh& mesh, const nlohmann::json& manifest, const nlohmann::json& entry,
                                const ProxyGeometry& proxy, const std::filesystem::path& folder);

}  // namespace visproxy
