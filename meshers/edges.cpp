#include "meshers/edges.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>

namespace ht {

std::vector<BoundaryEdge> boundary_edges(const TriangleMesh& mesh) {
  // Each side filed under its lower vertex as one key, upper vertex above slot (3 * triangle +
  // corner): eight bytes a side and one count a vertex, where the general sides_by_edge keeps
  // sixteen and a count per range (on a whole operand mesh that scratch was a tenth of a
  // Boolean's peak memory). Each vertex's keys are sorted, so the order they were filed in (in
  // parallel) does not show.
  const auto& T = mesh.triangles;
  const std::size_t V = mesh.positions.size();
  const auto slots = static_cast<std::uint32_t>(3 * T.size());
  auto ends = [&](std::uint32_t s) { return std::pair(T[s / 3][s % 3], T[s / 3][(s % 3 + 1) % 3]); };
  std::vector<std::uint32_t> first(V + 1, 0);
  tbb::parallel_for(std::uint32_t(0), slots, [&](std::uint32_t s) {
    const auto [a, b] = ends(s);
    std::atomic_ref<std::uint32_t>(first[std::min(a, b)]).fetch_add(1, std::memory_order_relaxed);
  });
  std::uint32_t at = 0;
  for (std::uint32_t& f : first) at += std::exchange(f, at);  // exclusive prefix sums
  std::vector<std::uint32_t> fill(first.begin(), first.end() - 1);
  std::vector<std::uint64_t> key(slots);
  tbb::parallel_for(std::uint32_t(0), slots, [&](std::uint32_t s) {
    const auto [a, b] = ends(s);
    const std::uint32_t k = std::atomic_ref<std::uint32_t>(fill[std::min(a, b)]).fetch_add(1, std::memory_order_relaxed);
    key[k] = std::uint64_t(std::max(a, b)) << 32 | s;
  });
  // Per vertex: its keys in order (insertion sort: a few each), then the edges used once,
  // counted first so that each vertex writes its own stretch of the output.
  std::vector<std::uint32_t>& count = fill;
  tbb::parallel_for(std::size_t(0), V, [&](std::size_t v) {
    const auto b = key.begin() + first[v], e = key.begin() + first[v + 1];
    for (auto i = b + (b != e); i < e; ++i) {
      const std::uint64_t x = *i;
      auto j = i;
      for (; j != b && *(j - 1) > x; --j) *j = *(j - 1);
      *j = x;
    }
    std::uint32_t n = 0;
    for (auto i = b; i != e; ++i) n += (i == b || *(i - 1) >> 32 != *i >> 32) && (i + 1 == e || (*(i + 1) >> 32) != *i >> 32);
    count[v] = n;
  });
  at = 0;
  for (std::uint32_t& c : count) at += std::exchange(c, at);
  std::vector<BoundaryEdge> out(at);
  tbb::parallel_for(std::size_t(0), V, [&](std::size_t v) {
    std::uint32_t o = count[v];
    const auto b = key.begin() + first[v], e = key.begin() + first[v + 1];
    for (auto i = b; i != e; ++i)
      if ((i == b || *(i - 1) >> 32 != *i >> 32) && (i + 1 == e || (*(i + 1) >> 32) != *i >> 32)) {
        const auto s = static_cast<std::uint32_t>(*i);
        out[o++] = {ends(s).first, ends(s).second, s};
      }
  });
  return out;
}

}  // namespace ht
