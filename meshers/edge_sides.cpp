#include "meshers/edge_sides.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <numeric>
#include <utility>

namespace ht {

std::vector<Side> sides_by_edge(std::size_t vertices, std::span<const glm::uvec3> T) {
  std::vector<std::uint32_t> first(vertices + 1, 0);
  for (const glm::uvec3& t : T)
    for (int k = 0; k < 3; ++k) ++first[std::min(t[k], t[(k + 1) % 3]) + 1];
  std::partial_sum(first.begin(), first.end(), first.begin());
  std::vector<Side> sides(3 * T.size());
  std::vector<std::uint32_t> fill(first.begin(), first.end() - 1);
  for (std::uint32_t t = 0; t < T.size(); ++t)
    for (std::uint8_t k = 0; k < 3; ++k) {
      const std::uint32_t a = T[t][k], b = T[t][(k + 1) % 3];
      sides[fill[std::min(a, b)]++] = {std::min(a, b), std::max(a, b), t, k, a < b};
    }
  // Filled in triangle order, so a stable sort by the upper vertex leaves (tri, corner) in order.
  tbb::parallel_for(std::size_t(0), vertices, [&](std::size_t v) {
    for (std::uint32_t i = first[v] + 1; i < first[v + 1]; ++i)  // insertion sort: a few sides each
      for (std::uint32_t j = i; j > first[v] && sides[j - 1].hi > sides[j].hi; --j) std::swap(sides[j - 1], sides[j]);
  });
  return sides;
}

}  // namespace ht
