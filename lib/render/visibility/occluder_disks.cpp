// The `spheres` visibility strategy: each instance's sphere-set proxy as occluder disks,
// instances without one (and, with --self-shadow exact, the own instance) traced exactly.

#include "render/visibility/occluder_disks.h"

#include <cmath>

#include "render/visibility/visibility.h"

namespace visproxy {

void OccluderDisks::reset(const Vertex& x, const Vertex& n) {
  x_ = x, n_ = n;
  count_ = 0;
  ux_.clear(), uy_.clear(), uz_.clear(), cos_.clear(), t_.clear();
}

void OccluderDisks::add(const std::vector<Sphere>& spheres, bool self_heuristic) {
  for (const Sphere& ball : spheres) {
    const Vertex v = ball.center - x_;
    if (n_.dot(v) <= -ball.radius) continue;  // behind the tangent plane
    const double t = v.norm();
    if (self_heuristic && t < 2 * ball.radius) continue;
    Vertex u = Vertex::UnitZ();
    double cos_gamma = -2;  // x inside the ball: every direction
    if (t > ball.radius) {
      u = v / t;
      cos_gamma = std::sqrt(t * t - ball.radius * ball.radius) / t;
    }
    ux_.push_back(static_cast<float>(u.x())), uy_.push_back(static_cast<float>(u.y())), uz_.push_back(static_cast<float>(u.z()));
    cos_.push_back(static_cast<float>(cos_gamma));
    t_.push_back(static_cast<float>(t));
    ++count_;
  }
}

void OccluderDisks::finish() {
  // Padding hides nothing: cos gamma above any cosine.
  while (ux_.size() % kDiskBlock != 0) {
    ux_.push_back(0), uy_.push_back(0), uz_.push_back(1), cos_.push_back(2), t_.push_back(0);
  }
}

bool OccluderDisks::occludes(const Vertex& end, std::uint64_t& tests) const {
  if (count_ == 0) return false;
  const Vertex w = end - x_;
  const double z = w.norm();
  if (!(z > 0)) return false;
  const Vertex d = w / z;
  tests += count_;
  return any_disk_occludes(ux_.data(), uy_.data(), uz_.data(), cos_.data(), t_.data(), ux_.size(), static_cast<float>(d.x()),
                           static_cast<float>(d.y()), static_cast<float>(d.z()), static_cast<float>(z));
}

__attribute__((target_clones("avx2", "default"))) bool any_disk_occludes(const float* ux, const float* uy, const float* uz,
                                                                        const float* cos_gamma, const float* t, std::size_t n,
                                                                        float dx, float dy, float dz, float z) {
  constexpr std::size_t block = OccluderDisks::kDiskBlock;
  for (std::size_t base = 0; base < n; base += block) {
    int hidden = 0;
    for (std::size_t j = base; j < base + block; ++j)
      hidden |= static_cast<int>(dx * ux[j] + dy * uy[j] + dz * uz[j] > cos_gamma[j]) & static_cast<int>(t[j] < z);
    if (hidden != 0) return true;
  }
  return false;
}

__attribute__((optimize("no-tree-vectorize"))) bool any_disk_occludes_scalar(const float* ux, const float* uy, const float* uz,
                                                                             const float* cos_gamma, const float* t, std::size_t n,
                                                                             float dx, float dy, float dz, float z) {
  for (std::size_t j = 0; j < n; ++j)
    if (t[j] < z && dx * ux[j] + dy * uy[j] + dz * uz[j] > cos_gamma[j]) return true;
  return false;
}

bool disk_occludes_reference(const Vertex& x, const Sphere& ball, const Vertex& end) {
  const Vertex v = ball.center - x, w = end - x;
  const double t = v.norm(), z = w.norm();
  if (!(t < z)) return false;
  if (t <= ball.radius) return true;
  const double cos_gamma = std::sqrt(t * t - ball.radius * ball.radius) / t;
  return v.dot(w) / (t * z) > cos_gamma;
}

namespace {

class OccluderDiskVisibility;

class OccluderDiskPoint final : public PointVisibility {
 public:
  explicit OccluderDiskPoint(const OccluderDiskVisibility& shared) : shared_(shared) {}
  void begin(const ShadingPoint& point) override;
  double to_light(const Vertex& end) override { return connection(end); }
  double connection(const Vertex& end) override;
  void connections(std::span<const Vertex> ends, std::span<double> out) override;

 private:
  const OccluderDiskVisibility& shared_;
  ShadingPoint point_;
  OccluderDisks disks_;
  InstanceFilter traced_;  // the instances traced exactly
  bool any_traced_ = false;
  std::vector<Vertex> rest_;
  std::vector<std::size_t> rest_index_;
  std::vector<std::uint8_t> blocked_;
};

class OccluderDiskVisibility final : public Visibility {
 public:
  explicit OccluderDiskVisibility(const VisibilityContext& context) : context_(context) {}
  std::unique_ptr<PointVisibility> point_visibility() override { return std::make_unique<OccluderDiskPoint>(*this); }

 private:
  friend class OccluderDiskPoint;
  VisibilityContext context_;
};

void OccluderDiskPoint::begin(const ShadingPoint& point) {
  point_ = point;
  const RenderWorld& world = shared_.context_.world;
  const SelfShadow self = shared_.context_.options.self_shadow;
  const int own = point.hit->instance;
  disks_.reset(point.position, point.hit->normal);
  unsigned bits = 0;
  for (std::size_t i = 0; i < shared_.context_.scene.instances.size(); ++i) {
    const std::vector<Sphere>& balls = world.occluder_spheres(i);
    const bool is_own = static_cast<int>(i) == own;
    if (balls.empty() || (is_own && self == SelfShadow::exact)) {
      // Traced exactly; the own instance needs no trace where it lies behind the tangent plane.
      if (!(is_own && point.hit->own_mesh_behind)) bits |= instance_bit(i);
      continue;
    }
    disks_.add(balls, is_own && self == SelfShadow::heuristic);
  }
  disks_.finish();
  traced_ = InstanceFilter{.skip = -1, .only = -1, .bits = bits};
  any_traced_ = bits != 0;
}

double OccluderDiskPoint::connection(const Vertex& end) {
  RenderStats& stats = *point_.stats;
  ++stats.proxy_tests;
  if (disks_.occludes(end, stats.disk_tests)) return 0;
  if (!any_traced_) return 1;
  ++stats.exact_tests;
  return shared_.context_.world.mesh_blocks(point_.position, end, traced_) ? 0 : 1;
}

void OccluderDiskPoint::connections(std::span<const Vertex> ends, std::span<double> out) {
  RenderStats& stats = *point_.stats;
  rest_.clear(), rest_index_.clear();
  stats.proxy_tests += ends.size();
  for (std::size_t i = 0; i < ends.size(); ++i) {
    out[i] = disks_.occludes(ends[i], stats.disk_tests) ? 0 : 1;
    if (out[i] != 0 && any_traced_) rest_.push_back(ends[i]), rest_index_.push_back(i);
  }
  if (rest_.empty()) return;
  stats.exact_tests += rest_.size();
  blocked_.resize(rest_.size());
  if (shared_.context_.options.group_connections) {
    shared_.context_.world.mesh_blocks(point_.position, rest_, blocked_, traced_);
  } else {
    for (std::size_t k = 0; k < rest_.size(); ++k) blocked_[k] = shared_.context_.world.mesh_blocks(point_.position, rest_[k], traced_);
  }
  for (std::size_t k = 0; k < rest_.size(); ++k)
    if (blocked_[k]) out[rest_index_[k]] = 0;
}

}  // namespace

std::unique_ptr<Visibility> make_occluder_disk_visibility(const VisibilityContext& context) {
  return std::make_unique<OccluderDiskVisibility>(context);
}

}  // namespace visproxy
