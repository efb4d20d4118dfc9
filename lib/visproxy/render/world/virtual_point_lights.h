#pragma once
// Virtual point lights (instant radiosity, Keller 1997): light paths traced from the area
// lights leave a point light at each diffuse hit, which then lights the scene as the
// indirect illumination of those paths.

#include <cstdint>
#include <vector>

#include "visproxy/render/world/render_world.h"
#include "visproxy/render/world/sampling.h"
#include "visproxy/scene/scene.h"

namespace visproxy {

struct VirtualPointLight {
  Vertex position;  ///< on the surface (not moved off it)
  Vertex normal;    ///< unit, towards the side the light arrived from
  Color power;      ///< flux the path carries to the point, watts-like units of the scene's radiance x area x sr
  Color brdf;       ///< the surface's Lambertian BRDF there: albedo / pi
  int instance = -1;
  int bounce = 1;   ///< 1 at the path's first hit
  /// Length of the ray that found the point (world units): its position carries rounding of
  /// that length, which the end of its connections must clear (RenderWorld::surface_offset).
  double distance = 0;
};

struct VplOptions {
  int paths = 1024;         ///< N: light paths traced
  int bounces = 1;          ///< B: hits per path that leave a light (1: one-bounce indirect)
  std::uint64_t seed = 1;
};

/// Traces `options.paths` light paths: a point on the lights by area, a cosine-distributed
/// direction (either side of two-sided lights), then up to B diffuse hits, each leaving a
/// VirtualPointLight and continuing in a cosine-distributed direction. A path's power is
/// Le x (total light area) x pi / N (x 2 for two-sided lights), times the albedo of every
/// surface it left; so that the lights together carry the lights' flux into each bounce.
/// Light paths pass through lights (lights do not reflect). Path i uses its own random
/// stream (seed, i): the lights do not depend on the number of threads.
std::vector<VirtualPointLight> trace_virtual_point_lights(const Scene& scene, const RenderWorld& world, const VplOptions& options);

/// The end of every connection to `light`: moved off its surface towards the side its
/// normal faces, the side connections reach it from (vpl_geometry), so the same for every
/// shading point.
Vertex vpl_connection_end(const RenderWorld& world, const VirtualPointLight& light);

/// The diagonal of the box holding every instance (as RenderWorld bounds it) and every
/// light: the length VPL clamps are relative to. World units.
double scene_diagonal(const Scene& scene, const RenderWorld& world);

/// The geometric term cos_x cos_v / d^2 of a connection from x (unit normal n) to `light`,
/// and whether the connection faces both surfaces. G is at most `max_geometric` when it is
/// clamped (the energy above it is dropped).
struct VplGeometry {
  bool faces = false;
  double geometric = 0;  ///< unclamped
};
VplGeometry vpl_geometry(const Vertex& x, const Vertex& n, const VirtualPointLight& light);

/// The lights' positions and normals in structure-of-arrays form, for the batched
/// vpl_geometry() below.
struct VplArrays {
  std::vector<double> px, py, pz, nx, ny, nz;
  explicit VplArrays(const std::vector<VirtualPointLight>& lights);
  std::size_t size() const { return px.size(); }
};
/// vpl_geometry() for every light at once: faces[i] (-1 where the connection faces both
/// surfaces, else 0) and geometric[i] (0 where it does not face) for light i; the same
/// arithmetic as the single form, vectorised across the lights.
void vpl_geometry(const Vertex& x, const Vertex& n, const VplArrays& lights, double* geometric, std::int64_t* faces);

}  // namespace visproxy
