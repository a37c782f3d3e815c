#include "meshers/edges.hpp"

#include <algorithm>

namespace ht {

std::vector<BoundaryEdge> boundary_edges(const TriangleMesh& mesh) {
  const std::size_t nv = mesh.positions.size();
  std::vector<std::uint32_t> begin(nv + 1, 0);
  for (const glm::uvec3& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) ++begin[std::min(t[k], t[(k + 1) % 3]) + 1];
  for (std::size_t v = 0; v < nv; ++v) begin[v + 1] += begin[v];
  struct Entry {
    std::uint32_t hi, slot;
  };
  std::vector<Entry> bucket(begin[nv]);
  std::vector<std::uint32_t> fill(begin.begin(), begin.end() - 1);
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = mesh.triangles[t][k], b = mesh.triangles[t][(k + 1) % 3];
      bucket[fill[std::min(a, b)]++] = {std::max(a, b), 3 * t + std::uint32_t(k)};
    }
  std::vector<BoundaryEdge> out;
  for (std::size_t v = 0; v < nv; ++v) {
    // A bucket holds a vertex's edges to higher vertices: sorted, an edge used once is a run of one.
    const auto first = bucket.begin() + begin[v], last = bucket.begin() + begin[v + 1];
    std::sort(first, last, [](const Entry& x, const Entry& y) { return x.hi != y.hi ? x.hi < y.hi : x.slot < y.slot; });
    for (auto it = first; it != last;) {
      auto run = it;
      while (run != last && run->hi == it->hi) ++run;
      if (run - it == 1) {
        const std::uint32_t slot = it->slot, t = slot / 3, k = slot % 3;
        out.push_back({mesh.triangles[t][k], mesh.triangles[t][(k + 1) % 3], slot});
      }
      it = run;
    }
  }
  return out;
}

}  // namespace ht
