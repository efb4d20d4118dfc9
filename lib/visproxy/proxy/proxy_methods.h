#pragma once
// The proxy methods: one row per method (its spec's name and grammar, its kind, what it
// makes, how it is described, how its parameters are read and how it is built), the one
// table that the spec parser, build_proxies' dispatch and every help text read. Adding a
// method is adding a row here (proxy_methods.cpp) beside the method's own files.

#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "visproxy/core/proxy_kind.h"
#include "visproxy/mesh/sphere_set.h"
#include "visproxy/mesh/triangle_mesh.h"
#include "visproxy/proxy/bounding_boxes.h"

namespace visproxy {

struct ProxySpec;
struct BuildOptions;

enum class PrimitiveType { triangle, box, sphere };
std::string_view primitive_type_name(PrimitiveType type);

/// What a method makes of one mesh (the whole input, or one of its components).
struct MethodPiece {
  TriangleMesh mesh;                        ///< triangle and box methods
  std::vector<OrientedBox> boxes;           ///< box methods: one box per piece
  std::vector<std::vector<Sphere>> levels;  ///< sphere methods: one set per level of the spec (ProxySpec::levels)
  nlohmann::json result = nlohmann::json::object();  ///< what the builder reached
  /// What describes the whole spec rather than this piece (the same for every component):
  /// joined into the proxy's result beside the pieces'.
  nlohmann::json summary = nlohmann::json::object();
};

/// Where a proxy's parameters are stated in mesh units: the input's extent.
struct MethodContext {
  double diagonal = 0;  ///< of the input's bounding box
  BoundingBox bounds;
  const BuildOptions* options = nullptr;
};

struct ProxyMethodRow {
  std::string_view id;       ///< stable name in code and tests: "bounded_hull"
  std::string_view name;     ///< the spec's name before ':': "hull"
  std::string_view grammar;  ///< how its spec is written: "hull:N"
  /// Whether the spec takes a ':' argument: never ("hull"), always ("hull:N"), or either ("wrap").
  enum class Argument { none, required, optional } argument = Argument::none;
  ProxyKind kind = ProxyKind::general;
  PrimitiveType primitives = PrimitiveType::triangle;
  std::string_view summary;  ///< one line for the help: "convex polytope with at most N faces"
  std::string_view method;   ///< how it is made, as the manifest records it
  int cost_rank = 4;         ///< rough order of the builders' cost on one mesh, slowest (0) first
  /// Reads the argument after ':' into the spec (empty when there is none); throws
  /// visproxy::Error through fail_spec for a bad one.
  void (*parse)(ProxySpec& spec, std::string_view argument) = nullptr;
  /// The parameters as applied, relative and in mesh units (the manifest's "params"); for
  /// sphere methods of the level `level`.
  nlohmann::json (*params)(const ProxySpec& spec, const MethodContext& context, std::size_t level) = nullptr;
  /// Builds the proxy of one mesh; throws InvalidInputError("", problem) for input it cannot handle.
  MethodPiece (*build)(const ProxySpec& spec, const TriangleMesh& mesh, const BuildOptions& options) = nullptr;
  /// Said when every triangle collapsed and the proxy would be empty ("use a smaller cell").
  std::string_view empty_hint;
  /// Needs a closed mesh (the default set (BuildOptions::default_set) leaves it out otherwise).
  bool needs_closed_mesh = false;
};

/// Every method, in the order the help lists them.
const std::vector<ProxyMethodRow>& proxy_methods();
/// The row of `id`; a programming error (std::logic_error) for an unknown id.
const ProxyMethodRow& proxy_method(std::string_view id);
/// The grammar of every spec, one per line with its kind and summary, as the help shows it:
///   "  hull:N   convex polytope with at most N faces (outside)"
std::string proxy_spec_help();

/// Throws visproxy::Error "--proxy 'SPEC': problem", the one form of every spec error.
[[noreturn]] void fail_spec(std::string_view spec, std::string_view problem);

}  // namespace visproxy
