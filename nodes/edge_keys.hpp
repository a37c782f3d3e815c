// Triangles' sides grouped by the edge they lie on, as 8-byte keys filed under each edge's lower
// vertex: the first step of a mesh leaf's neighbour table (nodes/mesh_build.cpp), of the
// strategies' boundary search (meshers/edges.hpp) and of the mesh checks (meshers/mesh_checks.hpp),
// without a hash map or a sort of every side.
#pragma once

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace ht {

/// Side s of triangle s / 3 runs from its corner s % 3 to the next. keys[first[v] .. first[v + 1])
/// are the sides whose lower vertex is v, each as (upper vertex << 32 | s), ascending: the sides of
/// one edge are consecutive, in side order. Eight bytes a side and four a vertex.
struct EdgeKeys {
  std::vector<std::uint32_t> first;
  std::vector<std::uint64_t> keys;

  static std::uint32_t upper(std::uint64_t key) { return static_cast<std::uint32_t>(key >> 32); }
  static std::uint32_t side(std::uint64_t key) { return static_cast<std::uint32_t>(key); }
  /// The end of the run of one edge's sides that starts at index i of vertex v's keys.
  std::size_t run_end(std::uint32_t v, std::size_t i) const {
    std::size_t j = i + 1;
    while (j < first[v + 1] && upper(keys[j]) == upper(keys[i])) ++j;
    return j;
  }
  /// Calls f(run) for each edge filed under vertex v, in order: `run` is its sides' keys.
  template <class F>
  void for_each_edge(std::uint32_t v, F&& f) const {
    for (std::size_t i = first[v]; i < first[v + 1];) {
      const std::size_t j = run_end(v, i);
      f(std::span<const std::uint64_t>(keys).subspan(i, j - i));
      i = j;
    }
  }
};

/// Every side of `triangles`, whose indices are below `vertices`. Filed in parallel (each vertex's
/// keys sorted after), so the same at any thread count.
EdgeKeys edge_keys(std::span<const glm::uvec3> triangles, std::size_t vertices);

}  // namespace ht
