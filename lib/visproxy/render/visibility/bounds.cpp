// Bounds: the exact answer, with proxies that only skip work. A segment to a light that
// misses every other instance's outside proxy is unoccluded by them; one that meets an
// inside proxy is occluded; only the rest is traced.

#include <algorithm>
#include <span>
#include <vector>

#include "visproxy/render/visibility/light_shaft.h"
#include "visproxy/render/visibility/visibility.h"
#include "visproxy/trace/embree_support.h"

namespace visproxy {
namespace {

class BoundsVisibility;

class BoundsPoint final : public PointVisibility {
 public:
  explicit BoundsPoint(BoundsVisibility& shared) : shared_(shared) {}
  void begin(const ShadingPoint& point) override;
  double to_light(const Vertex& end) override;
  double connection(const Vertex& end) override;
  void connections(std::span<const Vertex> ends, std::span<const unsigned> end_shells, std::span<double> out) override;
  void end() override;

 private:
  // The light shaft's instances, found when a second segment to a light leaves this point.
  void find_shaft();

  BoundsVisibility& shared_;
  ShadingPoint point_;
  int segments_ = 0;                          // segments to lights traced from this point so far
  bool shaft_found_ = false;
  std::vector<std::size_t> shaft_instances_;  // the instances (other than the own) the light shaft meets
  unsigned shaft_bits_ = 0;                   // their instance bits
  bool traced_before_ = false;  // a proof failed here: the next segments go straight to the exact query
  bool proof_failed_ = false, proof_tried_ = false;
  ExactConnections connections_;
  std::vector<std::uint8_t> blocked_;
};

class BoundsVisibility final : public Visibility {
 public:
  explicit BoundsVisibility(const VisibilityContext& context)
      : context_(context), shaft_(context.scene), proof_failures_(context.pixels, 0) {}
  std::unique_ptr<PointVisibility> point_visibility() override { return std::make_unique<BoundsPoint>(*this); }

 private:
  friend class BoundsPoint;
  VisibilityContext context_;
  LightShaft shaft_;
  std::vector<std::uint8_t> proof_failures_;  // per pixel: passes in a row in which a proof of the rest of the scene failed
};

void BoundsPoint::begin(const ShadingPoint& point) {
  point_ = point;
  segments_ = 0;
  shaft_found_ = false;
  proof_failed_ = proof_tried_ = false;
  // Where proofs failed in the last passes of this pixel, skip them but every 8th pass.
  traced_before_ = shared_.proof_failures_[point.pixel] >= 2 && point.pass % 8 != 0;
  connections_.begin(shared_.context_.world, point.position);
}

// The shaft from the point to every light costs more than one query of the outside proxies
// (cone tests against the instances' boxes and balls): it pays only when several segments
// leave the point, so the first segment goes to the proxies' query without it.
void BoundsPoint::find_shaft() {
  shaft_found_ = true;
  const int own = point_.hit->instance;
  shaft_instances_.clear();
  LightShaft::From shaft_from = shared_.shaft_.from(point_.position);
  shared_.context_.world.instances_where(
      [&](const BoundingBox& box, const Sphere& ball) { return shared_.shaft_.meets(shaft_from, box, ball); }, shaft_instances_);
  std::erase(shaft_instances_, static_cast<std::size_t>(own));
  shaft_bits_ = 0;
  for (const std::size_t i : shaft_instances_) shaft_bits_ |= instance_bit(i);
  if (shaft_instances_.empty()) ++point_.stats->bounds.shafts_culled;
}

double BoundsPoint::to_light(const Vertex& end) {
  // The own mesh (unless it lies behind the tangent plane) and the rest of the scene's
  // outside proxies: free if the segment misses both (only the instances the light shaft
  // meets can be hit), blocked if it meets the own mesh or an inside proxy; otherwise one
  // exact query. After a segment from this point needed the exact query, the next ones go
  // straight to it: the proxies rarely prove anything where they just failed to.
  const RenderWorld& world = shared_.context_.world;
  RenderStats& stats = *point_.stats;
  const Vertex& x = point_.position;
  const int own = point_.hit->instance;
  // Only the instances in the shaft whose bounding sphere this segment meets can block it.
  // (Among many, their balls are left to the query: the bits are shared beyond 31 instances.)
  // The first segment from a point leaves every other instance to the query.
  unsigned bits = InstanceFilter{}.bits;
  if (segments_++ > 0) {
    if (!shaft_found_) find_shaft();
    bits = 0;
    if (shaft_instances_.size() > 31) {
      bits = shaft_bits_;
    } else {
      for (const std::size_t i : shaft_instances_)
        if (segment_meets_ball(world.instance_sphere(i), x, end - x, 0.0, 1.0)) bits |= instance_bit(i);
    }
  }
  const InstanceFilter rest{.skip = own, .only = -1, .bits = bits};
  const bool own_clear = point_.hit->own_mesh_clear_of(x, end);
  if (bits == 0) {
    ++stats.bounds.unoccluded;
    if (own_clear) return 1;
    ++stats.exact_tests;
    return world.mesh_blocks(x, end, {.skip = -1, .only = own}) ? 0 : 1;
  }
  bool own_known_clear = false;  // the rest is then all an exact query must trace
  if (!traced_before_) {
    proof_tried_ = true;
    if (world.has_split_scene(own)) {
      // One traversal of the own mesh and the rest's outside proxies: the own mesh
      // blocking answers, as a clear segment does.
      const SplitAnswer answer =
          world.split_blocks(x, end, own, !own_clear, stats.exact_tests, stats.proxy_tests, SplitProxies::outside, bits);
      if (answer == SplitAnswer::own_blocks) {
        ++stats.bounds.traced;
        return 0;
      }
      if (answer == SplitAnswer::clear) {
        ++stats.bounds.unoccluded;
        return 1;
      }
      own_known_clear = true;
    } else {
      // Among many instances: the rest's outside proxies first, then the own mesh.
      ++stats.proxy_tests;
      if (!world.outside_blocks(x, end, rest)) {
        ++stats.bounds.unoccluded;
        if (own_clear) return 1;
        ++stats.exact_tests;
        return world.mesh_blocks(x, end, {.skip = -1, .only = own}) ? 0 : 1;
      }
    }
  }
  if (world.has_inside_proxies() && !traced_before_) {
    ++stats.proxy_tests;
    if (world.inside_blocks(x, end, rest)) {
      ++stats.bounds.occluded;
      return 0;
    }
  }
  const InstanceFilter traced = own_known_clear ? InstanceFilter{.skip = own, .only = -1} : InstanceFilter{};
  proof_failed_ = proof_failed_ || !traced_before_;
  traced_before_ = true;
  ++stats.bounds.traced;
  ++stats.exact_tests;
  return world.mesh_blocks(x, end, traced) ? 0 : 1;
}

// The proofs of traced proxies need one end of the segment on a light: connections to
// other points are traced exactly, as the exact strategy traces them.
double BoundsPoint::connection(const Vertex& end) {
  ++point_.stats->bounds.traced;
  ++point_.stats->exact_tests;
  return connections_.blocked(end) ? 0 : 1;
}

void BoundsPoint::connections(std::span<const Vertex> ends, std::span<const unsigned> end_shells, std::span<double> out) {
  if (!shared_.context_.options.group_connections) return PointVisibility::connections(ends, end_shells, out);
  point_.stats->bounds.traced += ends.size();
  point_.stats->exact_tests += ends.size();
  blocked_.resize(ends.size());
  connections_.blocked(ends, end_shells, blocked_);
  for (std::size_t i = 0; i < ends.size(); ++i) out[i] = blocked_[i] ? 0 : 1;
}

void BoundsPoint::end() {
  std::uint8_t& failures = shared_.proof_failures_[point_.pixel];
  if (proof_tried_) failures = proof_failed_ ? static_cast<std::uint8_t>(std::min(failures + 1, 255)) : 0;
}

}  // namespace

std::unique_ptr<Visibility> make_bounds_visibility(const VisibilityContext& context) {
  return std::make_unique<BoundsVisibility>(context);
}

}  // namespace visproxy
