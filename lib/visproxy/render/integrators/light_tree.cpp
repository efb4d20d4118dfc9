#include "visproxy/render/integrators/light_tree.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>

#include "visproxy/core/errors.h"
#include "visproxy/image/image.h"
#include "visproxy/render/world/sampling.h"

namespace visproxy {
namespace {

// Van der Corput's radical inverse in base 2.
double radical_inverse(std::uint32_t bits) {
  bits = (bits << 16u) | (bits >> 16u);
  bits = ((bits & 0x55555555u) << 1u) | ((bits & 0xAAAAAAAAu) >> 1u);
  bits = ((bits & 0x33333333u) << 2u) | ((bits & 0xCCCCCCCCu) >> 2u);
  bits = ((bits & 0x0F0F0F0Fu) << 4u) | ((bits & 0xF0F0F0F0u) >> 4u);
  bits = ((bits & 0x00FF00FFu) << 8u) | ((bits & 0xFF00FF00u) >> 8u);
  return static_cast<double>(bits) * 0x1.0p-32;
}

// An angle in [0, pi] by its cosine and sine, so that cones combine without acos and cos.
struct Angle {
  double cos = 1, sin = 0;
  static Angle between(const Vertex& a, const Vertex& b) {  // both unit
    const double c = std::clamp(a.dot(b), -1.0, 1.0);
    return {c, std::sqrt(std::max(0.0, 1 - c * c))};
  }
  // a + b, at most pi.
  friend Angle operator+(const Angle& a, const Angle& b) {
    const double s = a.sin * b.cos + a.cos * b.sin;
    if (s < 0 || (s == 0 && a.cos * b.cos - a.sin * b.sin < 0)) return {-1, 0};
    return {a.cos * b.cos - a.sin * b.sin, s};
  }
  // cos(max(0, a - b)).
  double cos_of_excess_over(const Angle& b) const { return cos >= b.cos ? 1.0 : cos * b.cos + sin * b.sin; }
};

}  // namespace

std::vector<PointLight> area_light_points(const Scene& scene, const RenderWorld& world, int per_light, std::uint64_t seed) {
  std::vector<PointLight> points;
  if (per_light <= 0) return points;
  for (std::size_t l = 0; l < scene.lights.size(); ++l) {
    const AreaLight& light = scene.lights[l];
    std::vector<double> cumulative;
    double total = 0;
    for (const auto& t : light.triangles) cumulative.push_back(total += 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).norm());
    if (!(total > 0)) continue;
    PixelRandom random(seed ^ kLightPathStream, l, 1);
    const double r1 = random.uniform(), r2 = random.uniform();  // one rotation of the pattern per light
    long before = 0;
    for (std::size_t i = 0; i < light.triangles.size(); ++i) {
      // The triangle's share of the K points, from the running sum of areas; its points
      // carry its area equally.
      const long upto = std::lround(static_cast<double>(per_light) * cumulative[i] / total);
      const long count = upto - before;
      before = upto;
      const auto& t = light.triangles[i];
      const Vertex cross = (t[1] - t[0]).cross(t[2] - t[0]);
      const double area = 0.5 * cross.norm();
      if (count <= 0 || !(area > 0)) continue;
      const Vertex normal = cross.normalized();
      for (long j = 0; j < count; ++j) {
        // A rotated (0, 2)-sequence mapped to the triangle by the square-root map.
        const double u = std::fmod((static_cast<double>(j) + 0.5) / static_cast<double>(count) + r1, 1.0);
        const double v = std::fmod(radical_inverse(static_cast<std::uint32_t>(j)) + r2, 1.0);
        const double s = std::sqrt(u);
        const Vertex p = (1 - s) * t[0] + s * (1 - v) * t[1] + s * v * t[2];
        PointLight point;
        point.position = p;
        point.normal = normal;
        point.intensity = light.radiance * (area / static_cast<double>(count));
        point.two_sided = light.two_sided;
        point.on_light = true;
        point.end = p;
        point.end_offset = world.surface_offset(p, 0.0);
        points.push_back(point);
      }
    }
  }
  return points;
}

std::vector<PointLight> vpl_point_lights(const RenderWorld& world, const std::vector<VirtualPointLight>& lights,
                                         double max_geometric) {
  std::vector<PointLight> points;
  for (const VirtualPointLight& light : lights) {
    PointLight point;
    point.position = light.position;
    point.normal = light.normal;
    point.intensity = light.power.cwiseProduct(light.brdf);
    point.max_geometric = max_geometric;
    point.end = vpl_connection_end(world, light);
    point.end_offset = (point.end - light.position).norm();
    points.push_back(point);
  }
  return points;
}

LightTree::LightTree(std::vector<PointLight> lights) : lights_(std::move(lights)) {
  if (lights_.empty()) return;
  std::vector<std::uint32_t> order(lights_.size());
  std::iota(order.begin(), order.end(), 0u);
  // Builds the node for order[begin, end) at `index` (already allocated), children first.
  auto build = [&](auto& self, std::size_t index, std::size_t begin, std::size_t end) -> void {
    Node node;
    node.lights = static_cast<std::uint32_t>(end - begin);
    Vertex normals = Vertex::Zero();
    bool two_sided = false;
    double least_clamp = std::numeric_limits<double>::infinity();
    for (std::size_t k = begin; k < end; ++k) {
      const PointLight& light = lights_[order[k]];
      node.box.extend(light.position - Vertex::Constant(light.end_offset));
      node.box.extend(light.position + Vertex::Constant(light.end_offset));
      node.box.extend(light.end);
      normals += light.normal;
      two_sided = two_sided || light.two_sided;
      node.intensity += light.intensity;
      node.on_lights = node.on_lights && light.on_light;
      node.max_geometric = std::max(node.max_geometric, light.max_geometric);
      least_clamp = std::min(least_clamp, light.max_geometric);
    }
    node.min_geometric = least_clamp;
    if (!two_sided && normals.norm() > 1e-9 * static_cast<double>(end - begin)) {
      node.axis = normals.normalized();
      node.cos_half = 1;
      for (std::size_t k = begin; k < end; ++k) node.cos_half = std::min(node.cos_half, node.axis.dot(lights_[order[k]].normal));
      // A cone wider than a hemisphere bounds little; keep it only while it is a proper cone.
      if (node.cos_half <= -1 + 1e-12) node.cos_half = -1;
    }
    if (end - begin == 1) {
      node.representative = node.central = order[begin];
      nodes_[index] = node;
      return;
    }
    int axis = 0;
    BoundingBox positions;
    for (std::size_t k = begin; k < end; ++k) positions.extend(lights_[order[k]].position);
    (positions.max - positions.min).maxCoeff(&axis);
    // Points on lights apart from VPLs first, so that the upper bound (for clusters on
    // lights only) applies from the root's child on; then median splits.
    const auto on_lights_end = static_cast<std::size_t>(
        std::stable_partition(order.begin() + static_cast<std::ptrdiff_t>(begin), order.begin() + static_cast<std::ptrdiff_t>(end),
                              [&](std::uint32_t i) { return lights_[i].on_light; }) -
        order.begin());
    const bool mixed = on_lights_end > begin && on_lights_end < end;
    const std::size_t middle = mixed ? on_lights_end : begin + (end - begin) / 2;
    if (!mixed)
      std::nth_element(order.begin() + static_cast<std::ptrdiff_t>(begin), order.begin() + static_cast<std::ptrdiff_t>(middle),
                     order.begin() + static_cast<std::ptrdiff_t>(end), [&](std::uint32_t l, std::uint32_t r) {
                       const double a = lights_[l].position[axis], b = lights_[r].position[axis];
                       return a < b || (a == b && l < r);
                     });
    const auto left = static_cast<std::int32_t>(nodes_.size());
    nodes_.emplace_back(), nodes_.emplace_back();
    node.left = left, node.right = left + 1;
    self(self, static_cast<std::size_t>(left), begin, middle);
    self(self, static_cast<std::size_t>(left + 1), middle, end);
    // Two representatives, both by the luminance-weighted centroid of the cluster's lights
    // (ties to the lower index):
    //  - `central`, the light nearest it (a midpoint rule over the cluster), for clusters
    //    whose visibility is proved, where any light costs the same: no ray;
    //  - `representative`, the child's representative nearer it, for traced clusters: one
    //    child keeps it, and its traced answer (Walter et al. pick between the children's
    //    at random by intensity).
    Vertex centroid = Vertex::Zero();
    double weight = 0;
    for (std::size_t k = begin; k < end; ++k) {
      const double w = std::max(0.0, luminance(lights_[order[k]].intensity));
      centroid += w * lights_[order[k]].position, weight += w;
    }
    if (!(weight > 0)) {  // black lights: the plain centroid
      centroid = Vertex::Zero();
      for (std::size_t k = begin; k < end; ++k) centroid += lights_[order[k]].position;
      weight = static_cast<double>(end - begin);
    }
    centroid /= weight;
    auto nearer = [&](std::uint32_t a, std::uint32_t b) {  // a nearer the centroid than b
      const double da = (lights_[a].position - centroid).squaredNorm(), db = (lights_[b].position - centroid).squaredNorm();
      return da < db || (da == db && a < b);
    };
    node.central = order[begin];
    for (std::size_t k = begin + 1; k < end; ++k)
      if (nearer(order[k], node.central)) node.central = order[k];
    const std::uint32_t a = nodes_[static_cast<std::size_t>(left)].representative;
    const std::uint32_t b = nodes_[static_cast<std::size_t>(left + 1)].representative;
    node.representative = nearer(b, a) ? b : a;
    nodes_[index] = node;
  };
  nodes_.emplace_back();
  build(build, 0, 0, lights_.size());
}

double light_geometry(const PointLight& light, const Vertex& x, const Vertex& n) {
  const Vertex w = light.position - x;
  const double d2 = w.squaredNorm();
  if (!(d2 > 0)) return 0;
  const double along_x = n.dot(w);
  double along_l = -light.normal.dot(w);
  if (light.two_sided) along_l = std::abs(along_l);
  if (!(along_x > 0 && along_l > 0)) return 0;
  return std::min(along_x * along_l / (d2 * d2), light.max_geometric);
}

ClusterGeometry cluster_geometry(const LightTree::Node& node, const Vertex& x, const Vertex& n) {
  const Vertex centre = 0.5 * (node.box.min + node.box.max);
  const double radius = 0.5 * (node.box.max - node.box.min).norm();
  const Vertex v = centre - x;
  const double distance = v.norm();
  const Vertex nearest = x.cwiseMax(node.box.min).cwiseMin(node.box.max);
  const double d_min = (nearest - x).norm();
  double d_max = 0;
  for (int k = 0; k < 8; ++k) d_max = std::max(d_max, (box_corner(node.box, k) - x).norm());
  double cos_x_lo = 0, cos_x_hi = 1, cos_l_lo = 0, cos_l_hi = 1;
  if (distance > radius) {
    // Directions from x to the box lie within beta of v; from the box to x within beta of -v.
    const double sin_beta = std::clamp(radius / distance, 0.0, 1.0);
    const Angle beta{std::sqrt(std::max(0.0, 1 - sin_beta * sin_beta)), sin_beta};
    const Vertex u = v / distance;
    const Angle alpha_x = Angle::between(n, u);
    cos_x_hi = alpha_x.cos_of_excess_over(beta);
    cos_x_lo = std::max(0.0, (alpha_x + beta).cos);
    if (node.cos_half > -1) {
      const double c = std::clamp(node.cos_half, -1.0, 1.0);
      const Angle spread = Angle{c, std::sqrt(std::max(0.0, 1 - c * c))} + beta;
      const Angle alpha_l = Angle::between(node.axis, -u);
      cos_l_hi = alpha_l.cos_of_excess_over(spread);
      cos_l_lo = std::max(0.0, (alpha_l + spread).cos);
    }
  }
  ClusterGeometry g;
  if (!(cos_x_hi > 0) || !(cos_l_hi > 0)) return g;  // every light behind the surface or facing away
  g.upper = d_min > 0 ? std::min(cos_x_hi * cos_l_hi / (d_min * d_min), node.max_geometric) : node.max_geometric;
  g.lower = d_max > 0 ? std::min(cos_x_lo * cos_l_lo / (d_max * d_max), node.min_geometric) : 0.0;
  return g;
}

CutResult CutEvaluator::evaluate(const Vertex& x, const SurfaceHit& hit, double offset, const Color& brdf,
                                 const CutOptions& options, const std::function<bool(std::uint32_t light)>& blocked) {
  CutResult result;
  if (tree_.empty()) return result;
  const std::vector<LightTree::Node>& nodes = tree_.nodes();
  const std::vector<PointLight>& lights = tree_.lights();
  const Vertex& n = hit.normal;
  const bool upper = proofs_ && (options.bounds == VisibilityBounds::upper || options.bounds == VisibilityBounds::both);
  const bool lower = proofs_ && (options.bounds == VisibilityBounds::lower || options.bounds == VisibilityBounds::both);
  if (upper || lower) {
    // The area lights' points are the root or its first child (LightTree keeps them apart).
    const LightTree::Node& root = nodes[LightTree::root];
    BoundingBox on_lights;
    if (root.on_lights) on_lights = root.box;
    else if (root.left >= 0 && nodes[static_cast<std::size_t>(root.left)].on_lights) on_lights = nodes[static_cast<std::size_t>(root.left)].box;
    proofs_->begin(x, hit, offset, root.box, on_lights);
  }
  const double brdf_luminance = luminance(brdf);
  Color total = Color::Zero();
  // At error 0 the cut is the exact sum: every cluster that may contribute is refined to its
  // lights (even one whose bounds meet, which a cluster's single estimate would round
  // differently), and no limit on the cut's size applies.
  const bool exact_sum = options.error == 0;

  auto trace = [&](std::uint32_t light) -> signed char {
    ++result.shadow_rays;
    return blocked(light) ? 0 : 1;
  };
  // `failures`: how many generations of the cluster's ancestors in a row failed a lower
  // bound proof; after kLowerBoundRetries the subtree is not tried again (a shaft that its
  // parent's and grandparent's blockers stopped rarely clears for a child, and a failed
  // shaft test costs several rays).
  constexpr int kLowerBoundRetries = 2;
  auto make = [&](std::uint32_t index, std::uint32_t parent_rep, signed char parent_visibility, bool parent_unoccluded,
                  int failures) {
    const LightTree::Node& node = nodes[index];
    Entry entry;
    entry.node = index;
    const ClusterGeometry g = node.lights == 1 ? ClusterGeometry{} : cluster_geometry(node, x, n);
    if (node.lights > 1 && !(g.upper > 0)) return entry;  // contributes nothing: no ray, no error
    bool unoccluded = parent_unoccluded, occluded = false;
    if (node.lights > 1 && !unoccluded && (upper || lower) &&
        brdf_luminance * luminance(node.intensity) * g.upper > options.error * luminance(total)) {
      if (upper) {
        ++result.proofs_tried;
        occluded = proofs_->occluded(node.box, node.on_lights);
      }
      if (!occluded && lower && failures < kLowerBoundRetries) {
        ++result.proofs_tried;
        unoccluded = proofs_->unoccluded(node.box, node.on_lights);
        entry.lower_failures = unoccluded ? 0 : static_cast<unsigned char>(failures + 1);
      } else {
        entry.lower_failures = static_cast<unsigned char>(failures);
      }
      result.proved_occluded += occluded ? 1 : 0;
      result.proved_unoccluded += unoccluded ? 1 : 0;
    }
    entry.proved_unoccluded = unoccluded;
    // A cluster proved unoccluded is shaded by its central light: it needs no ray.
    const std::uint32_t shading = unoccluded ? node.central : node.representative;
    const double rep_g = light_geometry(lights[shading], x, n);
    if (occluded) entry.visibility = 0;
    else if (unoccluded) entry.visibility = 1;
    else if (node.representative == parent_rep && parent_visibility >= 0) entry.visibility = parent_visibility;
    else if (rep_g > 0) entry.visibility = trace(node.representative);
    if (options.check_proofs && (occluded || unoccluded) && blocked(shading) == (entry.visibility == 1))
      ++result.disagreements;
    if (entry.visibility > 0) entry.estimate = brdf.cwiseProduct(node.intensity) * rep_g;
    // (A black cluster has no error, even where its geometric bound is infinite.)
    if (node.lights > 1 && !occluded && luminance(node.intensity) > 0 && brdf_luminance > 0)
      entry.error = exact_sum ? std::numeric_limits<double>::infinity()  // refined to its lights, whatever its bounds
                              : brdf_luminance * luminance(node.intensity) * (g.upper - (unoccluded ? g.lower : 0.0));
    return entry;
  };
  auto by_error = [](const Entry& a, const Entry& b) { return a.error < b.error; };
  heap_.clear();
  heap_.push_back(make(LightTree::root, ~0u, -1, false, 0));
  total = heap_.back().estimate;
  while (!heap_.empty()) {
    const Entry& top = heap_.front();
    // Only clusters refine: a leaf (one light) has error 0, and so has every entry when the
    // largest error is 0. The running total may dip below 0 by rounding (its terms cancel);
    // the threshold is taken of its positive part.
    if (!(top.error > 0) || !(top.error > options.error * std::max(0.0, luminance(total)))) break;
    if (!exact_sum && static_cast<int>(heap_.size()) >= options.max_cut) {
      result.stopped_at_max_cut = true;
      break;
    }
    std::pop_heap(heap_.begin(), heap_.end(), by_error);
    const Entry parent = heap_.back();
    heap_.pop_back();
    total -= parent.estimate;
    const LightTree::Node& node = nodes[parent.node];
    if (node.left < 0 || node.right < 0) throw Error("lightcuts: a leaf of the light tree carried an error bound");
    const std::uint32_t rep = node.representative;
    for (const std::int32_t child : {node.left, node.right}) {
      const Entry entry = make(static_cast<std::uint32_t>(child), rep, parent.visibility, parent.proved_unoccluded, parent.lower_failures);
      total += entry.estimate;
      heap_.push_back(entry);
      std::push_heap(heap_.begin(), heap_.end(), by_error);
    }
  }
  // The sum again, in the order of the clusters' nodes rather than the heap's (which
  // depends on the error bounds, and so on the proofs) or the running total's
  // cancellations: two cuts of the same clusters give the same bits, and proved-occluded
  // clusters add exact zeros.
  std::sort(heap_.begin(), heap_.end(), [](const Entry& a, const Entry& b) { return a.node < b.node; });
  for (const Entry& entry : heap_) result.radiance += entry.estimate;
  result.size = static_cast<int>(heap_.size());
  return result;
}

}  // namespace visproxy
