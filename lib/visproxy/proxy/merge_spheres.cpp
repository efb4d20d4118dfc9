// Greedy pairwise merging of a sphere set: L. Szecsi, L. Szirmay-Kalos, "Efficient
// approximate visibility testing using occluding spheres", WSCG 2004, section 3.2 (pair
// distances D1 and D2, best partner per sphere from a spatial search structure, remembered
// and updated only when needed) with the merge of section 3.3-3.4 (two_sphere_gssa.h).

#include "visproxy/proxy/merge_spheres.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>
#include <queue>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "visproxy/core/errors.h"

namespace visproxy {
namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr std::uint32_t kLeafSize = 8;

// A k-d tree over sphere slots. The topology is fixed at construction; a slot can die or
// change its sphere, after which the boxes of centres and balls and the radius ranges are
// refitted from its leaf up to the root. Leaves keep copies of their spheres side by side.
class SphereTree {
 public:
  SphereTree(const std::vector<Sphere>& spheres, PairDistance measure)
      : split_radius_(measure == PairDistance::d2), item_of_slot_(spheres.size()), slot_of_item_(spheres.size()) {
    std::vector<std::uint32_t> order(spheres.size());
    for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
    nodes_.reserve(4 * spheres.size() / kLeafSize + 2);
    build(spheres, order, 0, static_cast<std::uint32_t>(order.size()), kNone);
    x_.resize(order.size());
    y_.resize(order.size());
    z_.resize(order.size());
    r_.resize(order.size());
    for (std::uint32_t item = 0; item < order.size(); ++item) {
      slot_of_item_[item] = order[item];
      item_of_slot_[order[item]] = item;
      store(item, spheres[order[item]]);
    }
    for (std::uint32_t index = static_cast<std::uint32_t>(nodes_.size()); index-- > 0;) refit(index);
  }

  void remove(std::uint32_t slot) {
    const std::uint32_t item = item_of_slot_[slot];
    r_[item] = -1;
    refit_from(leaf_of_item(item));
  }
  void update(std::uint32_t slot, const Sphere& sphere) {
    const std::uint32_t item = item_of_slot_[slot];
    store(item, sphere);
    refit_from(leaf_of_item(item));
  }

  // The live slot (other than `slot`, whose sphere is `query`) with the smallest pair
  // distance to it; ties go to the lower slot. kNone when no other slot lives.
  // `stack` is scratch space, so that queries can run in parallel.
  std::pair<std::uint32_t, double> best_partner(std::uint32_t slot, const Sphere& query, PairDistance measure,
                                                std::vector<std::pair<std::uint32_t, double>>& stack) const {
    const std::uint32_t self = item_of_slot_[slot];
    const bool by_radius = measure == PairDistance::d2;
    std::uint32_t best = kNone;
    double best_distance = kInfinity;
    stack.clear();  // (node, lower bound)
    stack.emplace_back(0, lower_bound(nodes_[0], query, measure));
    while (!stack.empty()) {
      const auto [index, bound] = stack.back();
      stack.pop_back();
      if (bound > best_distance) continue;
      const Node& node = nodes_[index];
      if (node.left == kNone) {
        for (std::uint32_t item = node.begin; item < node.end; ++item) {
          if (r_[item] < 0 || item == self) continue;
          const double dx = x_[item] - query.center.x(), dy = y_[item] - query.center.y(),
                       dz = z_[item] - query.center.z();
          const double squared = dx * dx + dy * dy + dz * dz;
          const double radius_gap = by_radius ? std::abs(r_[item] - query.radius) : 0.0;
          const double reach = best_distance + radius_gap;  // better needs d <= reach
          if (reach < 0 || squared > reach * reach) continue;
          const double distance = std::sqrt(squared) - radius_gap;
          const std::uint32_t other = slot_of_item_[item];
          if (distance < best_distance || (distance == best_distance && other < best)) {
            best_distance = distance;
            best = other;
          }
        }
        continue;
      }
      const double left = lower_bound(nodes_[node.left], query, measure);
      const double right = lower_bound(nodes_[node.right], query, measure);
      // Push the farther first so that the nearer is examined next.
      if (left <= right) {
        if (right <= best_distance) stack.emplace_back(node.right, right);
        if (left <= best_distance) stack.emplace_back(node.left, left);
      } else {
        if (left <= best_distance) stack.emplace_back(node.left, left);
        if (right <= best_distance) stack.emplace_back(node.right, right);
      }
    }
    return {best, best_distance};
  }

  static double pair_distance(const Sphere& a, const Sphere& b, PairDistance measure) {
    const double d = (a.center - b.center).norm();
    return measure == PairDistance::d1 ? d : d - std::abs(a.radius - b.radius);
  }

 private:
  struct Node {
    Vertex low = Vertex::Constant(kInfinity);  // box of the live centres
    Vertex high = Vertex::Constant(-kInfinity);
    Vertex ball_low = Vertex::Constant(kInfinity);  // box of the live balls
    Vertex ball_high = Vertex::Constant(-kInfinity);
    double radius_min = kInfinity;
    double radius_max = -kInfinity;
    std::uint32_t left = kNone, right = kNone, parent = kNone;
    std::uint32_t begin = 0, end = 0;  // items
    std::uint32_t live = 0;
  };

  void store(std::uint32_t item, const Sphere& sphere) {
    x_[item] = sphere.center.x();
    y_[item] = sphere.center.y();
    z_[item] = sphere.center.z();
    r_[item] = sphere.radius;
  }

  std::uint32_t leaf_of_item(std::uint32_t item) const {
    std::uint32_t index = 0;
    while (nodes_[index].left != kNone)
      index = item < nodes_[nodes_[index].left].end ? nodes_[index].left : nodes_[index].right;
    return index;
  }

  std::uint32_t build(const std::vector<Sphere>& spheres, std::vector<std::uint32_t>& order, std::uint32_t begin,
                      std::uint32_t end, std::uint32_t parent) {
    const auto index = static_cast<std::uint32_t>(nodes_.size());
    nodes_.push_back({});
    nodes_[index].parent = parent;
    nodes_[index].begin = begin;
    nodes_[index].end = end;
    if (end - begin <= kLeafSize) return index;
    // Split the widest of x, y, z and (for D2) the radius, so that nodes also hold spheres
    // of similar size and D2's bounds, which subtract radius differences, stay tight.
    Eigen::Vector4d low = Eigen::Vector4d::Constant(kInfinity), high = Eigen::Vector4d::Constant(-kInfinity);
    auto coordinates = [&](std::uint32_t slot) {
      const Sphere& sphere = spheres[slot];
      return Eigen::Vector4d(sphere.center.x(), sphere.center.y(), sphere.center.z(), split_radius_ ? sphere.radius : 0.0);
    };
    for (std::uint32_t k = begin; k < end; ++k) {
      low = low.cwiseMin(coordinates(order[k]));
      high = high.cwiseMax(coordinates(order[k]));
    }
    int axis = 0;
    (high - low).maxCoeff(&axis);
    const std::uint32_t middle = begin + (end - begin) / 2;
    std::nth_element(order.begin() + begin, order.begin() + middle, order.begin() + end,
                     [&](std::uint32_t a, std::uint32_t b) {
                       const double ca = coordinates(a)[axis], cb = coordinates(b)[axis];
                       return ca < cb || (ca == cb && a < b);
                     });
    const std::uint32_t left = build(spheres, order, begin, middle, index);
    const std::uint32_t right = build(spheres, order, middle, end, index);
    nodes_[index].left = left;
    nodes_[index].right = right;
    return index;
  }

  void refit(std::uint32_t index) {
    Node& node = nodes_[index];
    node.low = node.ball_low = Vertex::Constant(kInfinity);
    node.high = node.ball_high = Vertex::Constant(-kInfinity);
    node.radius_min = kInfinity;
    node.radius_max = -kInfinity;
    node.live = 0;
    if (node.left == kNone) {
      for (std::uint32_t item = node.begin; item < node.end; ++item) {
        if (r_[item] < 0) continue;
        const Vertex center(x_[item], y_[item], z_[item]);
        node.low = node.low.cwiseMin(center);
        node.high = node.high.cwiseMax(center);
        node.ball_low = node.ball_low.cwiseMin(center - Vertex::Constant(r_[item]));
        node.ball_high = node.ball_high.cwiseMax(center + Vertex::Constant(r_[item]));
        node.radius_min = std::min(node.radius_min, r_[item]);
        node.radius_max = std::max(node.radius_max, r_[item]);
        ++node.live;
      }
      return;
    }
    for (const std::uint32_t child : {node.left, node.right}) {
      const Node& part = nodes_[child];
      if (part.live == 0) continue;
      node.low = node.low.cwiseMin(part.low);
      node.high = node.high.cwiseMax(part.high);
      node.ball_low = node.ball_low.cwiseMin(part.ball_low);
      node.ball_high = node.ball_high.cwiseMax(part.ball_high);
      node.radius_min = std::min(node.radius_min, part.radius_min);
      node.radius_max = std::max(node.radius_max, part.radius_max);
      node.live += part.live;
    }
  }

  void refit_from(std::uint32_t index) {
    for (; index != kNone; index = nodes_[index].parent) refit(index);
  }

  static double box_distance(const Vertex& p, const Vertex& low, const Vertex& high) {
    const double squared = (p.cwiseMax(low).cwiseMin(high) - p).squaredNorm();
    return squared > 0 ? std::sqrt(squared) : 0.0;
  }

  // A lower bound of the pair distance from `query` to any live sphere of the node.
  static double lower_bound(const Node& node, const Sphere& query, PairDistance measure) {
    if (node.live == 0) return kInfinity;
    const double to_centers = box_distance(query.center, node.low, node.high);
    if (measure == PairDistance::d1) return to_centers;
    // D2 = d - |r - r_j|. Smaller partners (r_j <= r): d + r_j - r >= to_centers + r_min - r.
    // Larger partners: d - r_j >= to_centers - r_max always, and when the query's centre is
    // outside the box of the balls it is outside every ball, so d - r_j (its distance to
    // ball j) is at least its distance to that box.
    double bound = kInfinity;
    if (node.radius_min <= query.radius) bound = to_centers + node.radius_min - query.radius;
    if (node.radius_max >= query.radius) {
      const double to_balls = box_distance(query.center, node.ball_low, node.ball_high);
      const double outside = to_centers - node.radius_max;
      bound = std::min(bound, query.radius + (to_balls > 0 ? std::max(to_balls, outside) : outside));
    }
    return bound;
  }

  bool split_radius_ = false;
  std::vector<Node> nodes_;
  std::vector<std::uint32_t> item_of_slot_, slot_of_item_;
  std::vector<double> x_, y_, z_, r_;  // by item; r < 0: dead
};

// A pair waiting in the queue, or (b == kNone) a sphere whose partner changed and that
// must search again: `distance` is then a lower bound of its new best pair distance.
struct Candidate {
  double distance;
  std::uint32_t a, b;                  // slots
  std::uint32_t version_a, version_b;  // of the slots when the entry was made
};

struct LaterCandidate {
  bool operator()(const Candidate& x, const Candidate& y) const {
    if (x.distance != y.distance) return x.distance > y.distance;
    if (x.a != y.a) return x.a > y.a;
    return x.b > y.b;
  }
};

}  // namespace

std::string_view pair_distance_name(PairDistance distance) { return distance == PairDistance::d1 ? "d1" : "d2"; }

std::vector<std::vector<Sphere>> merge_spheres(std::span<const Sphere> input, std::span<const std::size_t> targets,
                                               const MergeSpheresOptions& options, MergeSpheresStatistics* statistics) {
  for (const std::size_t target : targets) {
    if (target == 0) throw InvalidInputError("", "cannot merge a sphere set down to 0 spheres");
    if (target > input.size())
      throw InvalidInputError("", std::to_string(target) + " spheres asked for, but the initial set has only " +
                                      std::to_string(input.size()));
  }
  if (input.size() >= kNone) throw InvalidInputError("", "too many spheres to merge (at most 2^32 - 2)");
  for (const Sphere& sphere : input)
    if (!sphere.center.allFinite() || !std::isfinite(sphere.radius) || sphere.radius < 0)
      throw InvalidInputError("", "a sphere to merge has a non-finite centre or radius, or a negative radius");

  std::vector<Sphere> spheres(input.begin(), input.end());
  const auto count = static_cast<std::uint32_t>(spheres.size());
  SphereTree tree(spheres, options.pair_distance);
  std::vector<std::uint8_t> alive(count, 1);
  std::vector<std::uint32_t> version(count, 0);
  std::vector<std::uint32_t> partner(count, kNone);
  std::vector<double> partner_distance(count, kInfinity);
  std::vector<std::vector<std::uint32_t>> partner_of(count);  // slots that chose this one (may be stale)
  std::priority_queue<Candidate, std::vector<Candidate>, LaterCandidate> queue;
  MergeSpheresStatistics counted;
  auto push = [&](const Candidate& candidate) {
    queue.push(candidate);
    ++counted.queue_entries;
  };

  auto set_partner = [&](std::uint32_t slot, std::uint32_t best, double distance) {
    partner[slot] = best;
    partner_distance[slot] = distance;
    if (best == kNone) return;
    partner_of[best].push_back(slot);
    push({distance, slot, best, version[slot], version[best]});
  };
  std::vector<std::pair<std::uint32_t, double>> stack;
  auto search_partner = [&](std::uint32_t slot) {
    ++counted.partner_searches;
    const auto [best, distance] = tree.best_partner(slot, spheres[slot], options.pair_distance, stack);
    set_partner(slot, best, distance);
  };
  {
    // The first searches are independent: in parallel, then queued in slot order.
    std::vector<std::pair<std::uint32_t, double>> first(count);
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, count, 256), [&](const tbb::blocked_range<std::uint32_t>& range) {
      std::vector<std::pair<std::uint32_t, double>> scratch;
      for (std::uint32_t slot = range.begin(); slot != range.end(); ++slot)
        first[slot] = tree.best_partner(slot, spheres[slot], options.pair_distance, scratch);
    });
    counted.partner_searches += count;
    for (std::uint32_t slot = 0; slot < count; ++slot) set_partner(slot, first[slot].first, first[slot].second);
  }

  // Levels from the most spheres to the fewest; each snapshot goes to every equal target.
  std::vector<std::size_t> levels(targets.begin(), targets.end());
  std::sort(levels.begin(), levels.end(), std::greater<>());
  levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
  std::vector<std::vector<Sphere>> result(targets.size());

  // Invariant: the smallest valid key in the queue is at most the smallest pair distance.
  // Every live sphere's entry has a key at most its distance to each sphere unchanged since
  // its last search; pairs with a newer sphere are covered by the newer one's search.
  std::size_t live = count;
  std::vector<std::uint32_t> affected;
  for (const std::size_t level : levels) {
    while (live > level) {
      assert(!queue.empty());
      const Candidate top = queue.top();
      queue.pop();
      ++counted.queue_pops;
      if (!alive[top.a] || version[top.a] != top.version_a) continue;
      if (top.b == kNone) {  // a partner changed and could not be kept: search now
        if (partner[top.a] == kNone) search_partner(top.a);
        continue;
      }
      if (!alive[top.b] || version[top.b] != top.version_b) continue;
      const Sphere merged = merge_two_spheres(spheres[top.a], spheres[top.b], options.radius);
      // The merged sphere takes the larger one's slot (it stays near that leaf's region).
      const bool keep_a = spheres[top.a].radius > spheres[top.b].radius ||
                          (spheres[top.a].radius == spheres[top.b].radius && top.a < top.b);
      const std::uint32_t keep = keep_a ? top.a : top.b;
      const std::uint32_t gone = keep_a ? top.b : top.a;
      alive[gone] = 0;
      ++version[gone];
      tree.remove(gone);
      --live;
      // A sphere that holds the other absorbs it unchanged: it keeps its version, so the
      // entries of the spheres that chose it stay valid, and only the spheres that chose
      // the absorbed one are affected (one huge sphere among many small ones would
      // otherwise send all of them to look again at every merge: quadratic).
      const bool changed = merged.radius != spheres[keep].radius || merged.center != spheres[keep].center;
      const bool keep_searches = changed || partner[keep] == gone;
      if (changed) {
        spheres[keep] = merged;
        ++version[keep];
        tree.update(keep, merged);
      }

      // Spheres whose partner was one of the two: if the merged sphere is at least as close
      // as their old partner was, it is their best (everything else was farther); otherwise
      // they search again when their old distance, a lower bound, comes up in the queue.
      affected.clear();
      for (const std::uint32_t slot : partner_of[gone])
        if (alive[slot] && slot != keep && partner[slot] == gone) affected.push_back(slot);
      partner_of[gone].clear();
      if (changed) {
        for (const std::uint32_t slot : partner_of[keep])
          if (alive[slot] && partner[slot] == keep) affected.push_back(slot);
        partner_of[keep].clear();
      }
      std::sort(affected.begin(), affected.end());
      affected.erase(std::unique(affected.begin(), affected.end()), affected.end());
      if (keep_searches) search_partner(keep);
      for (const std::uint32_t slot : affected) {
        const double distance = SphereTree::pair_distance(spheres[slot], merged, options.pair_distance);
        if (distance <= partner_distance[slot]) {
          set_partner(slot, keep, distance);
        } else {
          push({partner_distance[slot], slot, kNone, version[slot], 0});
          partner[slot] = kNone;
          partner_distance[slot] = kInfinity;
        }
      }
    }
    std::vector<Sphere> snapshot;
    snapshot.reserve(live);
    for (std::uint32_t slot = 0; slot < count; ++slot)
      if (alive[slot]) snapshot.push_back(spheres[slot]);
    for (std::size_t k = 0; k < targets.size(); ++k)
      if (targets[k] == level) result[k] = snapshot;
  }
  if (statistics) *statistics = counted;
  return result;
}

}  // namespace visproxy
