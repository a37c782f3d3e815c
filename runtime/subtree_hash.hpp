// Content hashes of subtrees: the key of incremental re-meshing (issue 15).
//
// A node's hash covers what its field means, and nothing that merely names it:
//   kind, Boolean mode, mesher hint, every parameter bit for bit, the children's hashes in
//   order, a mesh leaf's inside test and its vertex and triangle arrays (the loaded CONTENTS, not the path), the
//   threshold T, and the `auto` Boolean rule as resolved in its context (min/max when the node
//   is a root on its own, R-functions under a blend; nodes/operators.hpp use_rfunction).
// Names, node ids and the arena layout are not hashed, so identical subtrees anywhere in a
// graph, or in two graphs, get equal hashes.
//
// The hash is 64-bit, written here (a splitmix64 finalizer over 64-bit words): deterministic
// across runs, thread counts and little-endian machines. Equal hashes of different content are
// possible in principle (about 2^-64 per pair); a cache keyed by them accepts that risk.
#pragma once

#include "runtime/graph.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace ht {

/// One hash per node and per context. `alone[n]` is node n's hash when n is meshed or evaluated
/// as a root of its own (what a mesh job does); `blended[n]` when something above n blends
/// (its `auto` Booleans pick R-functions). They differ only for subtrees holding an `auto` Boolean.
struct SubtreeHashes {
  std::vector<std::uint64_t> alone, blended;
  std::uint64_t of(NodeId n, bool under_blend) const { return under_blend ? blended[n] : alone[n]; }
};

/// Hashes every node of `graph` bottom-up (children have smaller ids), with threshold T.
/// Mesh leaves are hashed once per leaf however many nodes name them. Pure; thread-safe on a
/// const graph. Cost: linear in parameters plus mesh-leaf vertices and triangles.
SubtreeHashes subtree_hashes(const Graph& graph, double threshold);

/// The hash of a mesh leaf's inside test (MeshInside), vertex positions (doubles, bit for bit) and triangles, in order.
std::uint64_t mesh_contents_hash(const MeshLeaf& leaf);

/// The word mixer used by both: folds `word` into `state`. Exposed so that cache keys built on
/// these hashes (meshers/node_cache.hpp) mix the same way.
std::uint64_t hash_mix(std::uint64_t state, std::uint64_t word);

/// Folds `count` bytes into `state`, 8 at a time (the tail zero-padded, the length mixed last).
std::uint64_t hash_bytes(std::uint64_t state, const void* data, std::size_t count);

}  // namespace ht
