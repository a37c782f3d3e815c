#include "nodes/edge_keys.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <utility>

namespace ht {

EdgeKeys edge_keys(std::span<const glm::uvec3> T, std::size_t vertices) {
  const auto sides = static_cast<std::uint32_t>(3 * T.size());
  auto ends = [&](std::uint32_t s) { return std::pair(T[s / 3][s % 3], T[s / 3][(s % 3 + 1) % 3]); };
  EdgeKeys e;
  e.first.assign(vertices + 1, 0);
  tbb::parallel_for(std::uint32_t(0), sides, [&](std::uint32_t s) {
    const auto [a, b] = ends(s);
    std::atomic_ref<std::uint32_t>(e.first[std::min(a, b)]).fetch_add(1, std::memory_order_relaxed);
  });
  std::uint32_t at = 0;
  for (std::uint32_t& f : e.first) at += std::exchange(f, at);  // exclusive prefix sums
  e.keys.resize(sides);
  {
    std::vector<std::uint32_t> fill(e.first.begin(), e.first.end() - 1);
    tbb::parallel_for(std::uint32_t(0), sides, [&](std::uint32_t s) {
      const auto [a, b] = ends(s);
      const std::uint32_t k = std::atomic_ref<std::uint32_t>(fill[std::min(a, b)]).fetch_add(1, std::memory_order_relaxed);
      e.keys[k] = std::uint64_t(std::max(a, b)) << 32 | s;
    });
  }
  tbb::parallel_for(std::size_t(0), vertices, [&](std::size_t v) {
    const auto b = e.keys.begin() + e.first[v], end = e.keys.begin() + e.first[v + 1];
    for (auto i = b + (b != end); i < end; ++i) {  // insertion sort: a few sides each
      const std::uint64_t x = *i;
      auto j = i;
      for (; j != b && *(j - 1) > x; --j) *j = *(j - 1);
      *j = x;
    }
  });
  return e;
}

}  // namespace ht
