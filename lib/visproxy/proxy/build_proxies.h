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

#include "visproxy/mesh/sphere_set.h"
#include "visproxy/core/errors.h"
#include "visproxy/mesh/triangle_mesh.h"
#include "visproxy/proxy/bounding_boxes.h"
#include "visproxy/proxy/circumsphere_set.h"
#include "visproxy/proxy/proxy_spec.h"

namespace visproxy {

/// A builder or a measure of build_proxies() ran out of memory (std::bad_alloc, or the
/// limit the process was given). what() reads "FILE: SPEC: out of memory while ...",
/// naming the builder or the measure; the CLI exits with code 3.
class OutOfMemoryError : public Error {
 public:
  OutOfMemoryError(const std::filesystem::path& file, std::string_view problem) : Error(located_message(file, problem)) {}
};

struct BuiltProxy {
  ProxySpec spec;
  std::string name;       ///< the file and manifest name: spec.name(), or "spheres-N" for each level
  std::string method;     ///< how it was made, in words ("CGAL 3D alpha wrap")
  nlohmann::json params;  ///< parameters as applied, relative and in mesh units
  PrimitiveType primitive_type = PrimitiveType::triangle;
  std::size_t primitives = 0;      ///< boxes, triangles or spheres
  TriangleMesh mesh;               ///< the proxy as triangles (boxes as their 12 triangles, spheres as icospheres)
  std::vector<OrientedBox> boxes;  ///< box proxies: one per component
  std::vector<Sphere> spheres;     ///< sphere proxies
  /// Wall time of the builder alone (not of the error measurement), longer while other
  /// builders share the cores (BuildOptions::builders_at_once); the levels of one spheres
  /// spec are built in one pass and each reports the time of the whole pass.
  double build_seconds = 0;
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
  /// With builders_at_once above 1, every callback here may be called from several
  /// threads at once.
  std::function<void(std::string_view)> on_start;
  /// How spheres:N finds the tetrahedra inside the mesh (circumsphere_set.h).
  InnerTetrahedra tets = InnerTetrahedra::normals;
  /// Isotropic lines (seeded by `seed`) for the GSSA ratio of sphere proxies.
  std::size_t gssa_lines = 100000;
  /// The specs are the default set (default_proxy_specs), not asked for by name. Then
  /// inside:N is left out when the mesh is not closed (it needs a closed mesh), and so is a
  /// proxy of more than kDefaultMaxShareOfMesh of the mesh's triangles and at least
  /// kLargeProxyPrimitives primitives (the default set's proxies are meant to be far
  /// simpler than the mesh; a convex hull of a finely curved mesh can keep a sixth of its
  /// triangles), each with a call to on_skip naming it and why.
  bool default_set = false;
  std::function<void(std::string_view name, std::string_view reason)> on_skip = {};
  /// Called before each proxy's error (and GSSA) is measured, with its spec's text, once
  /// every proxy is built; may be empty.
  std::function<void(std::string_view spec)> on_measure = {};
  /// Specs built and measured at once, each by one worker that measures what it built at
  /// once: 0 chooses (builders_at_once); 1 builds every spec one after another and
  /// measures once all are built, which holds the least memory. The proxies are the same
  /// bit for bit; only build_seconds, each builder's wall time, grows while builders share
  /// the cores.
  std::size_t builders_at_once = 0;
  /// Called with a spec's text when work on it stops for now: after it is built and again
  /// after it is measured when builders run one after another, once both are done when
  /// they run at once (a watchdog's list of steps in progress); may be empty.
  std::function<void(std::string_view spec)> on_step_done = {};
};

/// The default set's largest share of the mesh's triangles (BuildOptions::default_set),
/// and the size below which a proxy is never left out for its share.
inline constexpr double kDefaultMaxShareOfMesh = 0.1;
inline constexpr std::size_t kLargeProxyPrimitives = 4096;

/// Above this many triangles, builders_at_once(0, ...) builds one spec at a time: each
/// builder's memory grows with the input (2.25 GB for the default set at 4.8 M triangles).
inline constexpr std::size_t kConcurrentBuildTriangles = std::size_t{1} << 20;

/// The specs build_proxies builds at once for `requested` (BuildOptions::builders_at_once)
/// on a mesh of `triangles`: `requested` if not 0; otherwise the threads TBB may use, or 1
/// above kConcurrentBuildTriangles.
std::size_t builders_at_once(std::size_t requested, std::size_t triangles);

/// Builds every spec for `mesh`, in order (a spheres spec gives one proxy per level).
/// `source` names the mesh in error messages: input a builder cannot handle (no
/// triangles, collinear vertices, not closed for inside:N, ...) throws
/// InvalidInputError("SOURCE", "SPEC: problem"). Sphere proxies' results hold the GSSA
/// ratio of the set to the mesh over options.gssa_lines isotropic lines (95 % interval).
/// The proxies come in spec order however many are built at once; when several specs
/// fail, the error thrown is the first one's in spec order.
std::vector<BuiltProxy> build_proxies(const TriangleMesh& mesh, const std::filesystem::path& source,
                                      std::span<const ProxySpec> specs, const BuildOptions& options = {});

}  // namespace visproxy
