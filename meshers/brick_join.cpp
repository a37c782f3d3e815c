#include "meshers/brick_join.hpp"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cstdint>

namespace ht::brick {

std::vector<EdgeVertex> join_bricks(std::vector<BrickOutput>&& outputs, TriangleMesh& mesh) {
  // Every brick's vertices by edge key, each key's keeper first (one with a crease normal, else
  // the lowest brick): 16-byte references sort faster than the vertices, and (key, rank) is
  // unique, so any sort gives the same order.
  struct Ref {
    std::uint64_t key;
    std::uint32_t rank;  // bit 31: no normal; below: the brick
    std::uint32_t slot;  // offset[brick] + the vertex's index in its brick
  };
  std::vector<std::size_t> offset(outputs.size() + 1, 0), tri_offset(outputs.size() + 1, 0);
  for (std::size_t b = 0; b < outputs.size(); ++b) {
    offset[b + 1] = offset[b] + outputs[b].vertices.size();
    tri_offset[b + 1] = tri_offset[b] + outputs[b].triangles.size();
  }
  std::vector<Ref> refs(offset.back());
  tbb::parallel_for(std::size_t(0), outputs.size(), [&](std::size_t b) {
    for (std::size_t v = 0; v < outputs[b].vertices.size(); ++v) {
      const EdgeVertex& e = outputs[b].vertices[v];
      const std::uint32_t plain = e.normal == glm::vec3(0.0f) ? 1u << 31 : 0u;
      refs[offset[b] + v] = {e.key, plain | e.brick, static_cast<std::uint32_t>(offset[b] + v)};
    }
  });
  tbb::parallel_sort(refs.begin(), refs.end(),
                     [](const Ref& x, const Ref& y) { return x.key != y.key ? x.key < y.key : x.rank < y.rank; });
  // The keeper of each key becomes a mesh vertex, numbered in key order (a running count of the
  // keys); every copy of the key maps to it. In parallel: each reference knows its vertex from
  // the count.
  std::vector<std::uint32_t> vertex(refs.size());
  std::uint32_t keys = 0;
  for (std::size_t i = 0; i < refs.size(); ++i) {
    keys += i == 0 || refs[i].key != refs[i - 1].key;
    vertex[i] = keys - 1;
  }
  std::vector<std::uint32_t> id(refs.size());
  std::vector<EdgeVertex> all(keys);
  mesh.positions.resize(keys);
  tbb::parallel_for(std::size_t(0), refs.size(), [&](std::size_t i) {
    id[refs[i].slot] = vertex[i];
    if (i != 0 && refs[i].key == refs[i - 1].key) return;
    const std::size_t b =
        std::size_t(std::upper_bound(offset.begin(), offset.end(), std::size_t(refs[i].slot)) - offset.begin()) - 1;
    all[vertex[i]] = outputs[b].vertices[refs[i].slot - offset[b]];
    mesh.positions[vertex[i]] = all[vertex[i]].position;
  });
  std::vector<Ref>().swap(refs);
  std::vector<std::uint32_t>().swap(vertex);
  // Every vertex is copied: the bricks' vertices go before the triangles are made, which need
  // only the numbers (a triangle's corners are its own brick's vertices).
  tbb::parallel_for(std::size_t(0), outputs.size(), [&](std::size_t b) { std::vector<EdgeVertex>().swap(outputs[b].vertices); });
  mesh.triangles.resize(tri_offset.back());
  tbb::parallel_for(std::size_t(0), outputs.size(), [&](std::size_t b) {
    const std::uint32_t* local = id.data() + offset[b];
    for (std::size_t t = 0; t < outputs[b].triangles.size(); ++t) {
      const LocalTriangle& tri = outputs[b].triangles[t];
      mesh.triangles[tri_offset[b] + t] = {local[tri[0]], local[tri[1]], local[tri[2]]};
    }
    outputs[b] = BrickOutput();
  });
  std::vector<BrickOutput>().swap(outputs);
  return all;
}

}  // namespace ht::brick
