// The instance tree must find every item a linear scan finds: on thousands of boxes far
// from the origin, with empty boxes, boxes that share one centre, and segments that only
// graze a box's face.

#include "visproxy/render/world/box_tree.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "visproxy/core/random.h"
#include "visproxy/trace/embree_support.h"

namespace visproxy {
namespace {

struct Items {
  std::vector<BoundingBox> boxes;
  std::vector<Sphere> balls;
};

// `count` boxes of seeded sizes scattered in a cube of side 100 at `offset`; every 17th is
// empty (holds nothing).
Items scattered(std::size_t count, const Vertex& offset, std::uint64_t seed) {
  Random random(seed);
  Items items;
  for (std::size_t i = 0; i < count; ++i) {
    BoundingBox box;
    if (i % 17 != 5) {
      const Vertex center = offset + 100.0 * Vertex(random.uniform(), random.uniform(), random.uniform());
      const Vertex half = 2.0 * Vertex(random.uniform(), random.uniform(), random.uniform());
      box.extend(center - half), box.extend(center + half);
    }
    items.boxes.push_back(box);
    const Vertex center = box.empty() ? offset : 0.5 * (box.min + box.max);
    items.balls.push_back({center, box.empty() ? 0.0 : 0.5 * (box.max - box.min).norm()});
  }
  return items;
}

std::vector<std::uint32_t> found(const BoxTree& tree, const Items& items, const Vertex& from, const Vertex& to,
                                 bool by_ball) {
  std::vector<std::uint32_t> out;
  const auto meets = [&](const BoundingBox& box, const Sphere& ball) {
    return by_ball ? segment_meets_ball(ball, from, to - from, 0.0, 1.0) : segment_meets_box(from, to, box);
  };
  tree.any(meets, [&](std::uint32_t i) {
    if (meets(items.boxes[i], items.balls[i])) out.push_back(i);
    return false;
  });
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::uint32_t> scanned(const Items& items, const Vertex& from, const Vertex& to, bool by_ball) {
  std::vector<std::uint32_t> out;
  for (std::uint32_t i = 0; i < items.boxes.size(); ++i)
    if (!items.boxes[i].empty() && (by_ball ? segment_meets_ball(items.balls[i], from, to - from, 0.0, 1.0)
                                            : segment_meets_box(from, to, items.boxes[i])))
      out.push_back(i);
  return out;
}

TEST(BoxTree, FindsWhatALinearScanFindsFarFromTheOrigin) {
  for (const Vertex& offset : {Vertex(0, 0, 0), Vertex(3.0e6, -2.0e6, 7.0e5)}) {
    const Items items = scattered(5000, offset, 41);
    const BoxTree tree(items.boxes, items.balls);
    Random random(42);
    std::size_t total = 0;
    for (int s = 0; s < 400; ++s) {
      const Vertex from = offset + 100.0 * Vertex(random.uniform(), random.uniform(), random.uniform());
      const Vertex to = offset + 100.0 * Vertex(random.uniform(), random.uniform(), random.uniform());
      for (const bool by_ball : {false, true}) {
        const std::vector<std::uint32_t> expected = scanned(items, from, to, by_ball);
        EXPECT_EQ(found(tree, items, from, to, by_ball), expected) << "segment " << s << " offset " << offset.x();
        total += expected.size();
      }
    }
    EXPECT_GT(total, 2000u);  // the segments meet many boxes: the comparison is not of empty sets
  }
}

TEST(BoxTree, SegmentsThatOnlyTouchAFaceOrACornerAreFound) {
  // Boxes side by side along x at a magnitude where their faces are not exactly halfway.
  Items items;
  for (int i = 0; i < 64; ++i) {
    BoundingBox box;
    box.extend(Vertex(1.0e7 + i, 1.0e7, 1.0e7)), box.extend(Vertex(1.0e7 + i + 0.5, 1.0e7 + 0.5, 1.0e7 + 0.5));
    items.boxes.push_back(box);
    items.balls.push_back({0.5 * (box.min + box.max), 0.5 * (box.max - box.min).norm()});
  }
  const BoxTree tree(items.boxes, items.balls);
  for (int i = 0; i < 64; ++i) {
    const BoundingBox& box = items.boxes[i];
    // Ends on the top face from above; along the face's plane; through the corner alone.
    const Vertex top(0.5 * (box.min.x() + box.max.x()), box.min.y(), box.max.z());
    EXPECT_EQ(found(tree, items, top + Vertex(0, 0, 3), top, false), std::vector<std::uint32_t>{std::uint32_t(i)});
    const Vertex corner = box.max;
    const std::vector<std::uint32_t> at_corner = found(tree, items, corner + Vertex(0, 1, 1), corner - Vertex(0, 1, 1), false);
    EXPECT_TRUE(std::find(at_corner.begin(), at_corner.end(), std::uint32_t(i)) != at_corner.end()) << i;
    EXPECT_EQ(at_corner, scanned(items, corner + Vertex(0, 1, 1), corner - Vertex(0, 1, 1), false));
  }
}

TEST(BoxTree, BoxesSharingOneCentreAndEmptyBoxes) {
  Items items;
  for (int i = 0; i < 300; ++i) {
    BoundingBox box;
    if (i % 3 != 0) box.extend(Vertex(-1.0 - i, -1, -1)), box.extend(Vertex(1.0 + i, 1, 1));
    items.boxes.push_back(box);
  }
  const BoxTree tree(items.boxes, {});
  items.balls.assign(items.boxes.size(), Sphere{});
  // A segment at x = 150 meets the boxes reaching it (1 + i >= 150), and no empty one.
  const std::vector<std::uint32_t> hits = found(tree, items, Vertex(150, -5, 0), Vertex(150, 5, 0), false);
  EXPECT_EQ(hits, scanned(items, Vertex(150, -5, 0), Vertex(150, 5, 0), false));
  EXPECT_EQ(hits.size(), 101u);  // i in [149, 300) with i % 3 != 0
  // All empty: an empty tree that finds nothing.
  const BoxTree none(std::vector<BoundingBox>(10), {});
  EXPECT_TRUE(none.empty());
  EXPECT_FALSE(none.any([](const BoundingBox&, const Sphere&) { return true; }, [](std::uint32_t) { return true; }));
}

// Ordered along a direction, the search finds the same items, and among boxes in a row it
// comes to the nearest leaf first, from either end.
TEST(BoxTree, AlongADirectionTheSameItemsNearestFirst) {
  const Items items = scattered(3000, Vertex(1.0e6, 0, 0), 9);
  const BoxTree tree(items.boxes, items.balls);
  Random random(10);
  for (int s = 0; s < 100; ++s) {
    const Vertex from = Vertex(1.0e6, 0, 0) + 100.0 * Vertex(random.uniform(), random.uniform(), random.uniform());
    const Vertex to = Vertex(1.0e6, 0, 0) + 100.0 * Vertex(random.uniform(), random.uniform(), random.uniform());
    std::vector<std::uint32_t> along;
    tree.any_along(
        to - from, [&](const BoundingBox& box, const Sphere&) { return segment_meets_box(from, to, box); },
        [&](std::uint32_t i) {
          if (segment_meets_box(from, to, items.boxes[i])) along.push_back(i);
          return false;
        });
    std::sort(along.begin(), along.end());
    EXPECT_EQ(along, scanned(items, from, to, false)) << s;
  }
  Items row;
  for (int i = 0; i < 200; ++i) {
    BoundingBox box;
    box.extend(Vertex(2.0 * i, 0, 0)), box.extend(Vertex(2.0 * i + 1, 1, 1));
    row.boxes.push_back(box);
  }
  const BoxTree line(row.boxes, {});
  for (const double sign : {1.0, -1.0}) {
    std::uint32_t first = 0, visits = 0;
    line.any_along(
        Vertex(sign, 0.01, 0), [](const BoundingBox&, const Sphere&) { return true; },
        [&](std::uint32_t i) {
          first = i, ++visits;
          return true;
        });
    EXPECT_EQ(visits, 1u);
    // The nearest leaf (of at most 4 items, in no order within it) comes first.
    EXPECT_TRUE(sign > 0 ? first < 4u : first > 195u) << first;
  }
}

TEST(BoxTree, StopsAtTheFirstItemVisitAccepts) {
  const Items items = scattered(1000, Vertex::Zero(), 7);
  const BoxTree tree(items.boxes, items.balls);
  int visits = 0;
  EXPECT_TRUE(tree.any([](const BoundingBox&, const Sphere&) { return true; }, [&](std::uint32_t) { return ++visits == 3; }));
  EXPECT_EQ(visits, 3);
  // Visiting all, every non-empty item is visited exactly once.
  std::vector<int> seen(items.boxes.size(), 0);
  EXPECT_FALSE(tree.any([](const BoundingBox&, const Sphere&) { return true; }, [&](std::uint32_t i) {
    ++seen[i];
    return false;
  }));
  for (std::size_t i = 0; i < seen.size(); ++i) EXPECT_EQ(seen[i], items.boxes[i].empty() ? 0 : 1) << i;
}

}  // namespace
}  // namespace visproxy
