// Triangles' sides grouped by the edge they lie on, each with its triangle, corner and direction
// spelled out (sixteen bytes): the first step of loading a mesh into OpenMesh in bulk. Where eight
// bytes a side will do, nodes/edge_keys.hpp files the same grouping.
#pragma once

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace ht {

/// Side `corner` of triangle `tri`: from its corner `corner` to the next, between vertices
/// lo < hi; `forward` when it runs from lo to hi.
struct Side {
  std::uint32_t lo, hi, tri;
  std::uint8_t corner;
  bool forward;
};

/// Every side of `triangles` (vertex indices below `vertices`), ordered by (lo, hi, tri, corner):
/// the sides on one edge are consecutive. Linear time (a counting sort by the lower vertex, then
/// each vertex's few sides sorted by the upper one); parallel inside.
std::vector<Side> sides_by_edge(std::size_t vertices, std::span<const glm::uvec3> triangles);

/// Calls f(run) for each edge in turn, `run` its sides (consecutive in sides_by_edge's order).
template <class F>
void for_each_edge(std::span<const Side> sides, F&& f) {
  for (std::size_t i = 0; i < sides.size();) {
    std::size_t j = i + 1;
    while (j < sides.size() && sides[j].lo == sides[i].lo && sides[j].hi == sides[i].hi) ++j;
    f(sides.subspan(i, j - i));
    i = j;
  }
}

}  // namespace ht
