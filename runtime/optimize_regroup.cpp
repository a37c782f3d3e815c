#include "runtime/optimize_regroup.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>
#include <numeric>

namespace ht::optimize_detail {
namespace {

constexpr std::size_t kParallelItems = 512;  // below this a split is cheaper than a task

struct Split {
  int axis = -1;
  std::size_t at = 0;  // items [0, at) go left in the axis's order
  double cost = std::numeric_limits<double>::infinity();
};

// The best split of `items` (sorted by box centre along each axis in turn, ties by index).
Split best_split(std::span<const Aabb> boxes, std::vector<std::uint32_t>& items) {
  const std::size_t n = items.size();
  Split best;
  std::vector<double> left(n);
  for (int axis = 0; axis < 3; ++axis) {
    std::sort(items.begin(), items.end(), [&](std::uint32_t a, std::uint32_t b) {
      const double ca = boxes[a].lo[axis] + boxes[a].hi[axis], cb = boxes[b].lo[axis] + boxes[b].hi[axis];
      return ca < cb || (ca == cb && a < b);
    });
    Aabb acc;
    for (std::size_t i = 0; i < n; ++i) {
      acc = merge(acc, boxes[items[i]]);
      left[i] = volume(acc) * static_cast<double>(i + 1);
    }
    acc = Aabb{};
    for (std::size_t i = n; i-- > 1;) {
      acc = merge(acc, boxes[items[i]]);
      const double cost = left[i - 1] + volume(acc) * static_cast<double>(n - i);
      if (cost < best.cost) best = {axis, i, cost};
    }
  }
  if (best.axis < 0) best = {0, n / 2, 0.0};  // unbounded boxes: halves in index order
  return best;
}

void split_in_two(std::span<const Aabb> boxes, std::vector<std::uint32_t>& items, std::vector<std::uint32_t>& a,
                  std::vector<std::uint32_t>& b) {
  const Split s = best_split(boxes, items);
  const int axis = std::max(s.axis, 0);
  std::sort(items.begin(), items.end(), [&](std::uint32_t x, std::uint32_t y) {
    const double cx = boxes[x].lo[axis] + boxes[x].hi[axis], cy = boxes[y].lo[axis] + boxes[y].hi[axis];
    return cx < cy || (cx == cy && x < y);
  });
  a.assign(items.begin(), items.begin() + std::ptrdiff_t(s.at));
  b.assign(items.begin() + std::ptrdiff_t(s.at), items.end());
}

Group build(std::span<const Aabb> boxes, std::vector<std::uint32_t> items, int fanout) {
  Group g;
  if (items.size() <= std::size_t(fanout)) {
    std::sort(items.begin(), items.end());
    g.items = std::move(items);
    return g;
  }
  // Split in two, then the larger parts again, until `fanout` parts.
  std::vector<std::vector<std::uint32_t>> parts(1, std::move(items));
  while (parts.size() < std::size_t(fanout)) {
    auto big = std::max_element(parts.begin(), parts.end(), [](const auto& x, const auto& y) { return x.size() < y.size(); });
    if (big->size() <= std::size_t(fanout)) break;
    std::vector<std::uint32_t> a, b, all = std::move(*big);
    split_in_two(boxes, all, a, b);
    *big = std::move(a);
    parts.insert(big + 1, std::move(b));
  }
  g.parts.resize(parts.size());
  const bool parallel = parts.size() >= 2 && parts[0].size() + parts[1].size() >= kParallelItems;
  auto run = [&](std::size_t i) { g.parts[i] = build(boxes, std::move(parts[i]), fanout); };
  if (parallel) {
    tbb::parallel_for(std::size_t(0), parts.size(), run);
  } else {
    for (std::size_t i = 0; i < parts.size(); ++i) run(i);
  }
  return g;
}

}  // namespace

Group spatial_groups(std::span<const Aabb> boxes, int fanout) {
  std::vector<std::uint32_t> items(boxes.size());
  std::iota(items.begin(), items.end(), 0u);
  return build(boxes, std::move(items), std::max(fanout, 2));
}

}  // namespace ht::optimize_detail
