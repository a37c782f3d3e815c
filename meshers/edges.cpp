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
  for (std::size_t v = 0; v < nv; ++v)
    for (std::uint32_t i = begin[v]; i < begin[v + 1]; ++i) {
      int uses = 0;
      for (std::uint32_t j = begin[v]; j < begin[v + 1]; ++j) uses += bucket[j].hi == bucket[i].hi;
      if (uses != 1) continue;
      const std::uint32_t slot = bucket[i].slot, t = slot / 3, k = slot % 3;
      out.push_back({mesh.triangles[t][k], mesh.triangles[t][(k + 1) % 3], slot});
    }
  return out;
}

}  // namespace ht
