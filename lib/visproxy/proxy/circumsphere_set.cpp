// Initial sphere sets: circumspheres of the tetrahedra inside a mesh. L. Szecsi, L.
// Szirmay-Kalos, "Efficient approximate visibility testing using occluding spheres", WSCG
// 2004, section 3 and 3.1 (Delaunay of surface samples, inner tetrahedra by normals); the
// robust alternative uses H. Si, "TetGen, a Delaunay-based quality tetrahedral mesh
// generator", ACM TOMS 41(2), 2015 (constrained Delaunay tetrahedralization of the surface).

#include "visproxy/proxy/circumsphere_set.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tetgen.h>

#include <algorithm>
#include <memory>
#include <string>
#include <tuple>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/mesh_topology.h"
#include "visproxy/proxy/detail/delaunay_cells.h"
#include "visproxy/proxy/detail/surface_samples.h"
#include "visproxy/proxy/detail/watertight_input.h"
#include "visproxy/verify/containment.h"

namespace visproxy {
namespace {

// Six times the signed volume, about the box centre.
double six_signed_volume(const TriangleMesh& mesh) {
  const BoundingBox box = bounding_box(mesh);
  const Vertex centre = 0.5 * (box.min + box.max);
  double six_volume = 0;
  for (const Triangle& t : mesh.triangles)
    six_volume += (mesh.positions[t[0]] - centre).dot((mesh.positions[t[1]] - centre).cross(mesh.positions[t[2]] - centre));
  return six_volume;
}

// Signed distance of each centre to the surface: positive inside (exact winding number),
// magnitude from CGAL's AABB tree.
std::vector<double> signed_distances(const TriangleMesh& mesh, const std::vector<Sphere>& spheres) {
  std::vector<Vertex> centers;
  centers.reserve(spheres.size());
  for (const Sphere& s : spheres) centers.push_back(s.center);
  const std::vector<PointLocation> locations = locate_points(mesh, centers);
  using Kernel = CGAL::Simple_cartesian<double>;
  using Triangles = std::vector<Kernel::Triangle_3>;
  using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, CGAL::AABB_triangle_primitive<Kernel, Triangles::const_iterator>>>;
  Triangles triangles;
  triangles.reserve(mesh.triangles.size());
  for (const Triangle& t : mesh.triangles) {
    auto p = [&](VertexIndex v) { return Kernel::Point_3(mesh.positions[v].x(), mesh.positions[v].y(), mesh.positions[v].z()); };
    triangles.emplace_back(p(t[0]), p(t[1]), p(t[2]));
  }
  Tree tree(triangles.begin(), triangles.end());
  tree.build();
  tree.accelerate_distance_queries();
  std::vector<double> distances(centers.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, centers.size(), 256), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const double d = std::sqrt(tree.squared_distance(Kernel::Point_3(centers[i].x(), centers[i].y(), centers[i].z())));
      distances[i] = locations[i] == PointLocation::inside ? d : -d;
    }
  });
  return distances;
}

CircumsphereSet by_normals(const TriangleMesh& mesh, const CircumsphereOptions& options) {
  const std::vector<SurfaceSample> samples = sample_surface_evenly(mesh, options.samples, options.seed);
  // Normals must point out: a closed, consistently oriented mesh that is inside out is flipped.
  const MeshTopology topology = analyze_topology(mesh);
  const double sign =
      topology.closed() && topology.consistently_oriented() && six_signed_volume(mesh) < 0 ? -1.0 : 1.0;
  std::vector<Vertex> points;
  points.reserve(samples.size());
  for (const SurfaceSample& sample : samples) points.push_back(sample.position);

  const std::vector<DelaunayCell> cells = delaunay_cells(points);
  CircumsphereSet set;
  set.points = points.size();
  set.tetrahedra = cells.size();
  for (const DelaunayCell& cell : cells) {
    const Vertex& center = cell.circumsphere.center;
    const bool inner = std::all_of(cell.corners.begin(), cell.corners.end(), [&](std::uint32_t corner) {
      return sign * (points[corner] - center).dot(samples[corner].normal) >= 0;
    });
    if (inner) set.spheres.push_back(cell.circumsphere);
  }
  return set;
}

CircumsphereSet by_tetgen(const TriangleMesh& mesh) {
  require_watertight(mesh,
                     "TetGen's constrained tetrahedralization (--tets tetgen) needs a closed surface without "
                     "self-intersections to know its inside; use --tets normals");
  // Only the vertices that triangles use: TetGen would insert the others as Steiner points.
  std::vector<int> renumbered(mesh.positions.size(), -1);
  std::vector<Vertex> used;
  for (const Triangle& t : mesh.triangles)
    for (const VertexIndex v : t)
      if (renumbered[v] < 0) {
        renumbered[v] = static_cast<int>(used.size());
        used.push_back(mesh.positions[v]);
      }

  tetgenio in;  // frees its arrays with delete[]
  tetgenio out;
  in.firstnumber = 0;
  in.numberofpoints = static_cast<int>(used.size());
  in.pointlist = new REAL[3 * used.size()];
  for (std::size_t i = 0; i < used.size(); ++i)
    for (int axis = 0; axis < 3; ++axis) in.pointlist[3 * i + static_cast<std::size_t>(axis)] = used[i][axis];
  in.numberoffacets = static_cast<int>(mesh.triangles.size());
  in.facetlist = new tetgenio::facet[mesh.triangles.size()];
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    tetgenio::facet& facet = in.facetlist[f];
    tetgenio::init(&facet);
    facet.numberofpolygons = 1;
    facet.polygonlist = new tetgenio::polygon[1];
    tetgenio::init(&facet.polygonlist[0]);
    facet.polygonlist[0].numberofvertices = 3;
    facet.polygonlist[0].vertexlist = new int[3];
    for (int k = 0; k < 3; ++k) facet.polygonlist[0].vertexlist[k] = renumbered[mesh.triangles[f][static_cast<std::size_t>(k)]];
  }
  // p: tetrahedralize the surface (a piecewise linear complex), z: number from zero, Q: quiet.
  // No quality refinement (q): it multiplies the tetrahedra (bunny00: 0.13 M -> 0.47 M at
  // q2) and the time; the ball choice below keeps flat tetrahedra from bulging instead.
  char switches[] = "pzQ";
  try {
    tetrahedralize(switches, &in, &out);
  } catch (int code) {
    throw InvalidInputError("", "TetGen could not tetrahedralize the mesh (TetGen error " + std::to_string(code) + ")");
  }
  if (out.numberoftetrahedra <= 0 || out.numberofcorners < 4)
    throw InvalidInputError("", "TetGen produced no tetrahedra");

  CircumsphereSet set;
  set.points = static_cast<std::size_t>(out.numberofpoints);
  set.tetrahedra = static_cast<std::size_t>(out.numberoftetrahedra);
  auto point = [&](int index) {
    const REAL* p = out.pointlist + 3 * static_cast<std::ptrdiff_t>(index);
    return Vertex(p[0], p[1], p[2]);
  };
  // Each tetrahedron is covered by its circumsphere or its smallest enclosing ball,
  // whichever reaches less far out of the surface: radius minus the signed distance of the
  // centre to the surface (positive inside; exact inside test, AABB distance).
  std::vector<Sphere> circumspheres, smallest;
  circumspheres.reserve(static_cast<std::size_t>(out.numberoftetrahedra));
  smallest.reserve(static_cast<std::size_t>(out.numberoftetrahedra));
  for (int t = 0; t < out.numberoftetrahedra; ++t) {
    const int* corners = out.tetrahedronlist + static_cast<std::ptrdiff_t>(t) * out.numberofcorners;
    const Vertex a = point(corners[0]), b = point(corners[1]), c = point(corners[2]), d = point(corners[3]);
    circumspheres.push_back(tetrahedron_circumsphere(a, b, c, d));
    smallest.push_back(smallest_enclosing_ball(a, b, c, d));
  }
  // Where the circumcentre is inside the tetrahedron the two balls are one; elsewhere
  // compare how far each reaches out of the surface.
  std::vector<std::size_t> differ;
  for (std::size_t i = 0; i < circumspheres.size(); ++i)
    if (!(circumspheres[i].radius <= smallest[i].radius)) differ.push_back(i);
  std::vector<Sphere> both;
  both.reserve(2 * differ.size());
  for (const std::size_t i : differ) both.push_back(circumspheres[i]);
  for (const std::size_t i : differ) both.push_back(smallest[i]);
  const std::vector<double> signed_distance = signed_distances(mesh, both);
  std::vector<std::uint8_t> use_smallest(circumspheres.size(), 0);
  for (std::size_t k = 0; k < differ.size(); ++k) {
    const double circumsphere_reach = circumspheres[differ[k]].radius - signed_distance[k];
    const double smallest_reach = smallest[differ[k]].radius - signed_distance[differ.size() + k];
    use_smallest[differ[k]] = circumspheres[differ[k]].radius <= 0 || smallest_reach < circumsphere_reach;
  }
  set.balls_replaced = 0;
  for (std::size_t i = 0; i < circumspheres.size(); ++i) {
    set.balls_replaced += use_smallest[i];
    const Sphere& sphere = use_smallest[i] ? smallest[i] : circumspheres[i];
    if (sphere.radius > 0) set.spheres.push_back(sphere);
  }
  return set;
}

}  // namespace

std::size_t default_circumsphere_samples(std::size_t largest_level) {
  return std::clamp<std::size_t>(4 * largest_level, 4000, 2'000'000);
}

template <>
const std::vector<std::pair<std::string_view, InnerTetrahedra>>& choice_names<InnerTetrahedra>() {
  static const std::vector<std::pair<std::string_view, InnerTetrahedra>> names{{"normals", InnerTetrahedra::normals},
                                                                              {"tetgen", InnerTetrahedra::tetgen}};
  return names;
}

CircumsphereSet build_circumsphere_set(const TriangleMesh& mesh, const CircumsphereOptions& options) {
  CircumsphereSet set = options.tetrahedra == InnerTetrahedra::tetgen ? by_tetgen(mesh) : by_normals(mesh, options);
  if (set.spheres.empty())
    throw InvalidInputError("", set.tetrahedra == 0
                                    ? "the surface samples are flat: no tetrahedra, so no spheres (a flat mesh has "
                                      "no volume for a sphere set to stand in for)"
                                    : "no tetrahedron is inside the mesh by the normal criterion (are the normals "
                                      "consistent?)");
  const auto key = [](const Sphere& s) { return std::tuple(s.center.x(), s.center.y(), s.center.z(), s.radius); };
  std::sort(set.spheres.begin(), set.spheres.end(), [&](const Sphere& a, const Sphere& b) { return key(a) < key(b); });
  return set;
}

}  // namespace visproxy
