#include "meshers/edges.hpp"

#include "nodes/edge_keys.hpp"

#include <tbb/parallel_for.h>

namespace ht {

std::vector<BoundaryEdge> boundary_edges(const TriangleMesh& mesh) {
  // The sides grouped by edge as keys (nodes/edge_keys.hpp): eight bytes a side where the general
  // sides_by_edge keeps sixteen and a count per range (on a whole operand mesh that scratch was a
  // tenth of a Boolean's peak memory). Each vertex counts its edges used once, then writes them
  // into its own stretch of the output.
  const auto& T = mesh.triangles;
  const std::size_t V = mesh.positions.size();
  const EdgeKeys e = edge_keys(T, V);
  auto for_each_single = [&](std::size_t v, auto&& f) {
    e.for_each_edge(std::uint32_t(v), [&](std::span<const std::uint64_t> run) {
      if (run.size() == 1) f(EdgeKeys::side(run[0]));
    });
  };
  std::vector<std::uint32_t> at(V + 1, 0);
  tbb::parallel_for(std::size_t(0), V, [&](std::size_t v) { for_each_single(v, [&](std::uint32_t) { ++at[v + 1]; }); });
  for (std::size_t v = 0; v < V; ++v) at[v + 1] += at[v];
  std::vector<BoundaryEdge> out(at[V]);
  tbb::parallel_for(std::size_t(0), V, [&](std::size_t v) {
    std::uint32_t o = at[v];
    for_each_single(v, [&](std::uint32_t s) { out[o++] = {T[s / 3][s % 3], T[s / 3][(s % 3 + 1) % 3], s}; });
  });
  return out;
}

}  // namespace ht
