// Exact visibility: every segment traced against the meshes.

#include <vector>

#include "visproxy/render/visibility/visibility.h"

namespace visproxy {
namespace {

class ExactPoint final : public PointVisibility {
 public:
  ExactPoint(const RenderWorld& world, bool group) : world_(world), group_(group) {}
  void begin(const ShadingPoint& point) override {
    x_ = point.position;
    stats_ = point.stats;
    connections_.begin(world_, x_);
  }
  double to_light(const Vertex& end) override {
    ++stats_->exact_tests;
    return world_.mesh_blocks(x_, end) ? 0 : 1;
  }
  double connection(const Vertex& end) override {
    ++stats_->exact_tests;
    return connections_.blocked(end) ? 0 : 1;
  }
  void connections(std::span<const Vertex> ends, std::span<const unsigned> end_shells, std::span<double> out) override {
    if (!group_) return PointVisibility::connections(ends, end_shells, out);
    stats_->exact_tests += ends.size();
    blocked_.resize(ends.size());
    connections_.blocked(ends, end_shells, blocked_);
    for (std::size_t i = 0; i < ends.size(); ++i) out[i] = blocked_[i] ? 0 : 1;
  }

 private:
  const RenderWorld& world_;
  bool group_;
  Vertex x_;
  RenderStats* stats_ = nullptr;
  ExactConnections connections_;
  std::vector<std::uint8_t> blocked_;
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
