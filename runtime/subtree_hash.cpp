#include "runtime/subtree_hash.hpp"

#include "nodes/mesh_leaf.hpp"
#include "nodes/operators.hpp"

#include <bit>
#include <cstring>

namespace ht {

namespace {

constexpr std::uint64_t kSeed = 0x48796272'69645472ull;  // "HybridTr"

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

bool is_boolean(NodeKind k) {
  return k == NodeKind::Union || k == NodeKind::Intersection || k == NodeKind::Difference ||
         k == NodeKind::LocalBlend;
}

// The hash of node n in one context; children's hashes (in their context) are already known.
std::uint64_t node_hash(const Graph& g, NodeId n, bool under_blend, const std::vector<std::uint64_t>& below,
                        const std::vector<std::uint64_t>& mesh_hashes, std::uint64_t t_bits) {
  const NodeKind k = g.kind[n];
  std::uint64_t h = hash_mix(kSeed, t_bits);
  h = hash_mix(h, static_cast<std::uint64_t>(k));
  h = hash_mix(h, static_cast<std::uint64_t>(g.boolean[n]));
  h = hash_mix(h, static_cast<std::uint64_t>(g.mesher[n]));
  if (is_boolean(k)) h = hash_mix(h, use_rfunction(g.boolean[n], under_blend) ? 2 : 1);
  const auto p = g.params_of(n);
  h = hash_mix(h, p.size());
  for (double v : p) h = hash_mix(h, std::bit_cast<std::uint64_t>(v));
  const auto c = g.children_of(n);
  h = hash_mix(h, c.size());
  for (NodeId child : c) h = hash_mix(h, below[child]);
  if (g.mesh[n] != kNone) h = hash_mix(h, mesh_hashes[g.mesh[n]]);
  return h;
}

}  // namespace

std::uint64_t hash_mix(std::uint64_t state, std::uint64_t word) {
  return splitmix64(state ^ splitmix64(word + 0x632be59bd9b4e019ull));
}

std::uint64_t hash_bytes(std::uint64_t state, const void* data, std::size_t count) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  std::size_t i = 0;
  for (; i + 8 <= count; i += 8) {
    std::uint64_t w;
    std::memcpy(&w, bytes + i, 8);
    state = hash_mix(state, w);
  }
  if (i < count) {
    std::uint64_t w = 0;
    std::memcpy(&w, bytes + i, count - i);
    state = hash_mix(state, w);
  }
  return hash_mix(state, count);
}

std::uint64_t mesh_contents_hash(const MeshLeaf& leaf) {
  const auto& pos = leaf.positions();
  const auto& tri = leaf.triangles();
  std::uint64_t h = hash_mix(kSeed, static_cast<std::uint64_t>(leaf.inside_mode()));
  h = hash_bytes(h, pos.data(), pos.size() * sizeof(pos[0]));
  return hash_bytes(h, tri.data(), tri.size() * sizeof(tri[0]));
}

SubtreeHashes subtree_hashes(const Graph& graph, double threshold) {
  std::vector<std::uint64_t> mesh_hashes(graph.meshes.size(), 0);
  for (std::size_t i = 0; i < graph.meshes.size(); ++i)
    if (graph.meshes[i]) mesh_hashes[i] = mesh_contents_hash(*graph.meshes[i]);
  const std::uint64_t t_bits = std::bit_cast<std::uint64_t>(threshold);
  SubtreeHashes out;
  out.alone.resize(graph.size());
  out.blended.resize(graph.size());
  for (NodeId n = 0; n < graph.size(); ++n) {
    const bool blends = graph.kind[n] == NodeKind::Blend || graph.kind[n] == NodeKind::LocalBlend;
    // The context a child sees: under a blend if n is one or n is under one.
    out.alone[n] = node_hash(graph, n, false, blends ? out.blended : out.alone, mesh_hashes, t_bits);
    out.blended[n] = node_hash(graph, n, true, out.blended, mesh_hashes, t_bits);
  }
  return out;
}

}  // namespace ht
