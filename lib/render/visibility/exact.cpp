// Exact visibility: every segment traced against the meshes.

#include <vector>

#include "render/visibility/visibility.h"

namespace visproxy {
namespace {

class ExactPoint final : public PointVisibility {
 public:
  ExactPoint(const RenderWorld& world, bool group) : world_(world), group_(group) {}
  void begin(const ShadingPoint& point) override {
    x_ = point.position;
    stats_ = point.stats;
    x_shells_ = world_.convex_shells_holding(x_);
  }
  double to_light(const Vertex& end) override {
    ++stats_->exact_tests;
    return world_.mesh_blocks(x_, end) ? 0 : 1;
  }
  // Connections skip the instances whose convex shell holds both ends (they cannot block).
  double connection(const Vertex& end) override {
    ++stats_->exact_tests;
    const unsigned cleared = x_shells_ & world_.convex_shells_holding(end);
    return world_.mesh_blocks(x_, end, {.skip = -1, .only = -1, .bits = ~cleared & 0x7FFFFFFFu}) ? 0 : 1;
  }
  void connections(std::span<const Vertex> ends, std::span<const unsigned> end_shells, std::span<double> out) override {
    if (!group_) return PointVisibility::connections(ends, end_shells, out);
    stats_->exact_tests += ends.size();
    blocked_.resize(ends.size());
    lanes_.resize(ends.size());
    for (std::size_t i = 0; i < ends.size(); ++i)
      lanes_[i] = ~(x_shells_ & (end_shells.empty() ? world_.convex_shells_holding(ends[i]) : end_shells[i]));
    world_.mesh_blocks(x_, ends, blocked_, {}, lanes_);
    for (std::size_t i = 0; i < ends.size(); ++i) out[i] = blocked_[i] ? 0 : 1;
  }

 private:
  const RenderWorld& world_;
  bool group_;
  Vertex x_;
  RenderStats* stats_ = nullptr;
  unsigned x_shells_ = 0;
  std::vector<std::uint8_t> blocked_;
  std::vector<unsigned> lanes_;
};

class ExactVisibility final : public Visibility {
 public:
  explicit ExactVisibility(const VisibilityContext& context) : world_(context.world), group_(context.options.group_connections) {}
  std::unique_ptr<PointVisibility> point_visibility() override { return std::make_unique<ExactPoint>(world_, group_); }

 private:
  const RenderWorld& world_;
  bool group_;
};

}  // namespace

std::unique_ptr<Visibility> make_exact_visibility(const VisibilityContext& context) {
  return std::make_unique<ExactVisibility>(context);
}

}  // namespace visproxy
