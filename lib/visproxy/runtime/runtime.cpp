#include "visproxy/runtime/runtime.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "visproxy/core/errors.h"
#include "visproxy/folder/proxy_folder.h"
#include "visproxy/folder/verdict.h"
#include "visproxy/trace/convex_polytope.h"
#include "visproxy/trace/ray_scene.h"
#include "visproxy/verify/containment.h"

namespace visproxy {
namespace {

using nlohmann::json;

std::string claim_text(ProxyKind kind) {
  return kind == ProxyKind::outside ? "outside claim (contains the mesh)" : "inside claim (lies within the mesh)";
}

double magnitude(const TriangleMesh& mesh, const Vertex& origin) {
  double m = 0;
  for (const Vertex& p : mesh.positions) m = std::max(m, (p - origin).cwiseAbs().maxCoeff());
  return m;
}

BoundingBox padded_box(const TriangleMesh& mesh, double pad) {
  BoundingBox box = bounding_box(mesh);
  if (!box.empty()) {
    box.min.array() -= pad;
    box.max.array() += pad;
  }
  return box;
}

bool box_holds(const BoundingBox& box, const Vertex& p) {
  return !box.empty() && (p.array() >= box.min.array()).all() && (p.array() <= box.max.array()).all();
}

}  // namespace

RuntimeProxy RuntimeProxy::load(const std::filesystem::path& folder, std::string_view name,
                                const std::filesystem::path& mesh_path, const RuntimeLoadOptions& options) {
  const json manifest = read_manifest(folder);
  const json* entry = nullptr;
  std::string names;
  for (const json& e : manifest.at("proxies")) {
    if (e.at("name").get<std::string>() == name) entry = &e;
    names += (names.empty() ? "" : ", ") + e.at("name").get<std::string>();
  }
  if (entry == nullptr)
    throw InvalidInputError(folder / "manifest.json", "no proxy named '" + std::string(name) + "' (it lists " +
                                                          (names.empty() ? std::string("none") : names) + ")");
  RuntimeProxy proxy;
  proxy.name_ = std::string(name);
  proxy.source_ = read_manifest_mesh(mesh_path, manifest);
  ProxyGeometry geometry = read_proxy_geometry(folder, *entry);
  const ProxyKind claimed = entry_kind(*entry);
  proxy.kind_ = claimed;
  if (claimed != ProxyKind::general) {
    bool proved = entry->contains("verify") && verdict_proves(entry->at("verify"), *entry, proxy.source_, geometry);
    std::string why = "no verdict of 'visproxy verify' for these files";
    if (!proved && options.verify_now) {
      const json verdict = verify_proxy(proxy.source_, manifest, *entry, geometry);
      proved = verdict.at("holds").get<bool>();
      why = verdict.at("counterexample").is_string() ? verdict.at("counterexample").get<std::string>() : "it does not hold";
    }
    if (!proved) {
      const std::filesystem::path file = folder / entry->at("file").get<std::string>();
      const std::string problem = "proxy " + proxy.name_ + ": its " + claim_text(claimed) + " is not proved for " +
                                  mesh_path.string() + ": " + why;
      if (options.require_proof) throw InvalidInputError(file, problem);
      proxy.note_ = problem + "; used as a general proxy";
      proxy.kind_ = ProxyKind::general;
    }
  }
  proxy.mesh_ = std::move(geometry.mesh);
  proxy.spheres_ = std::move(geometry.spheres);
  return proxy;
}

PlacedProxy RuntimeProxy::place(const Placement& placement) const {
  PlacedProxy out;
  out.kind_ = kind_;
  out.note_ = note_;
  out.origin_ = placement.origin;
  const Eigen::Affine3d& t = placement.transform;
  const TriangleMesh source_world = transformed_mesh(source_, t);
  // Triangles keep their claims under any invertible affine map (convexity and containment
  // are affine properties; a mirror keeps its winding outward, transformed_mesh); balls
  // need a similarity to stay balls.
  if (!(std::abs(t.linear().determinant()) > 0) || !t.matrix().allFinite())
    throw Error("proxy " + name_ + ": the placement's transform must be finite and invertible");
  const std::optional<std::vector<Sphere>> balls = transformed_spheres(spheres_, t);
  if (!spheres_.empty() && !balls) throw Error("proxy " + name_ + ": sphere proxies need a placement without shear or uneven scale");
  TriangleMesh world = transformed_mesh(mesh_, t);
  double m = std::max({placement.ray_magnitude, magnitude(world, placement.origin), magnitude(source_world, placement.origin)});
  if (balls)
    for (const Sphere& s : *balls) m = std::max(m, (s.center - placement.origin).cwiseAbs().maxCoeff() + s.radius);
  const double pad = kFloatRoundingBound * m;
  out.pad_ = pad;

  if (!spheres_.empty()) {
    for (Sphere w : *balls) {
      if (kind_ == ProxyKind::inside) {
        if (w.radius <= pad) continue;
        w.radius -= pad;
      }
      const Vertex c = w.center - placement.origin;
      out.spheres_.insert(out.spheres_.end(), {static_cast<float>(c.x()), static_cast<float>(c.y()),
                                               static_cast<float>(c.z()), static_cast<float>(w.radius)});
    }
    if (kind_ == ProxyKind::outside) {  // not proved for sphere sets; load refuses it unless allowed as general
      out.kind_ = ProxyKind::general;
    }
  } else {
    // Convex: grown by twice the bound, which leaves room for the grown vertices' own rounding.
    std::optional<ConvexPolytope> convex;
    if (kind_ == ProxyKind::outside && world.triangles.size() <= 16384 &&
        grow_convex_mesh(world, 2 * pad, world.triangles.size()))
      convex = ConvexPolytope::from_mesh(world, world.triangles.size());
    const bool scaled = convex.has_value();
    if (kind_ != ProxyKind::general && !scaled && !surfaces_clear_by(world, source_world, 2 * pad)) {
      out.note_ = "proxy " + name_ + ": it comes within float rounding (" + std::to_string(2 * pad) +
                  " world units) of the mesh, so its claim may not survive single-precision ray tests: used as a general proxy";
      out.kind_ = ProxyKind::general;
    }
    if (out.kind_ == ProxyKind::outside && scaled) {
      const ConvexPolytope grown = convex->grown(pad);
      for (const ConvexPolytope::Plane& plane : grown.planes())
        out.planes_.emplace_back(plane.normal.x(), plane.normal.y(), plane.normal.z(), plane.offset);
    }
    for (const Vertex& v : world.positions) {
      const Vertex r = v - placement.origin;
      out.vertices_.insert(out.vertices_.end(), {static_cast<float>(r.x()), static_cast<float>(r.y()), static_cast<float>(r.z())});
    }
    for (const Triangle& tri : world.triangles) out.indices_.insert(out.indices_.end(), tri.begin(), tri.end());
    if (out.kind_ == ProxyKind::outside) out.box_ = padded_box(world, pad);
  }
  if (out.kind_ == ProxyKind::inside) out.box_ = padded_box(source_world, pad);
  return out;
}

bool PlacedProxy::claim_covers(const Vertex& from, const Vertex& to) const {
  if (kind_ == ProxyKind::general) return false;
  auto may_hold = [&](const Vertex& p) {
    if (!planes_.empty())
      return std::all_of(planes_.begin(), planes_.end(), [&](const Eigen::Vector4d& plane) {
        return plane.head<3>().dot(p) <= plane[3];
      });
    return box_holds(box_, p);
  };
  return !may_hold(from) && !may_hold(to);
}

unsigned PlacedProxy::attach(RTCDevice device, RTCScene scene) const {
  const bool balls = !spheres_.empty();
  RTCGeometry geometry = rtcNewGeometry(device, balls ? RTC_GEOMETRY_TYPE_SPHERE_POINT : RTC_GEOMETRY_TYPE_TRIANGLE);
  if (geometry == nullptr) throw Error("Embree refused a new geometry (rtcNewGeometry)");
  if (balls) {
    auto* buffer = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4,
                                                               4 * sizeof(float), spheres_.size() / 4));
    if (buffer == nullptr) {
      rtcReleaseGeometry(geometry);
      throw Error("Embree refused the proxy's sphere buffer");
    }
    std::copy(spheres_.begin(), spheres_.end(), buffer);
  } else {
    auto* positions = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                  3 * sizeof(float), vertices_.size() / 3));
    auto* triangles = static_cast<std::uint32_t*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(std::uint32_t), indices_.size() / 3));
    if (positions == nullptr || triangles == nullptr) {
      rtcReleaseGeometry(geometry);
      throw Error("Embree refused the proxy's triangle buffers");
    }
    std::copy(vertices_.begin(), vertices_.end(), positions);
    std::copy(indices_.begin(), indices_.end(), triangles);
  }
  rtcCommitGeometry(geometry);
  const unsigned id = rtcAttachGeometry(scene, geometry);
  rtcReleaseGeometry(geometry);
  return id;
}

}  // namespace visproxy
