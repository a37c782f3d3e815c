#include "meshers/edge_sides.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <numeric>
#include <utility>

namespace ht {

namespace {

// Triangles are counted and filed in this many fixed ranges in parallel; the ranges depend on
// the mesh alone, so the order of the sides does not depend on the thread count.
constexpr std::size_t kRanges = 8;
constexpr std::size_t kSmall = 1 << 14;  // fewer triangles: one range

}  // namespace

std::vector<Side> sides_by_edge(std::size_t vertices, std::span<const glm::uvec3> T) {
  // A counting sort by the lower vertex, each range of triangles counted apart: range r's sides
  // of vertex v go after those of ranges before it, so they lie in triangle order as a serial
  // pass would put them.
  const std::size_t ranges = T.size() < kSmall ? 1 : kRanges;
  auto range = [&](std::size_t r) { return std::pair(T.size() * r / ranges, T.size() * (r + 1) / ranges); };
  std::vector<std::uint32_t> count(ranges * vertices, 0);
  tbb::parallel_for(std::size_t(0), ranges, [&](std::size_t r) {
    std::uint32_t* c = count.data() + r * vertices;
    const auto [b, e] = range(r);
    for (std::size_t t = b; t < e; ++t)
      for (int k = 0; k < 3; ++k) ++c[std::min(T[t][k], T[t][(k + 1) % 3])];
  });
  std::vector<std::uint32_t> first(vertices + 1, 0);
  std::uint32_t at = 0;
  for (std::size_t v = 0; v < vertices; ++v) {
    first[v] = at;
    for (std::size_t r = 0; r < ranges; ++r) {
      const std::uint32_t n = count[r * vertices + v];
      count[r * vertices + v] = at;  // now where range r's sides of v start
      at += n;
    }
  }
  first[vertices] = at;
  std::vector<Side> sides(3 * T.size());
  tbb::parallel_for(std::size_t(0), ranges, [&](std::size_t r) {
    std::uint32_t* fill = count.data() + r * vertices;
    const auto [b, e] = range(r);
    for (std::size_t t = b; t < e; ++t)
      for (std::uint8_t k = 0; k < 3; ++k) {
        const std::uint32_t a = T[t][k], c = T[t][(k + 1) % 3];
        sides[fill[std::min(a, c)]++] = {std::min(a, c), std::max(a, c), std::uint32_t(t), k, a < c};
      }
  });
  // Filed in triangle order, so a stable sort by the upper vertex leaves (tri, corner) in order.
  tbb::parallel_for(std::size_t(0), vertices, [&](std::size_t v) {
    for (std::uint32_t i = first[v] + 1; i < first[v + 1]; ++i) {  // insertion sort: a few sides each
      const Side x = sides[i];
      std::uint32_t j = i;
      for (; j > first[v] && sides[j - 1].hi > x.hi; --j) sides[j] = sides[j - 1];
      sides[j] = x;
    }
  });
  return sides;
}

}  // namespace ht
