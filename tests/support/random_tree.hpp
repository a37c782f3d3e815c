// Random HybridTrees for property tests: every node kind (but ffd, whose field needs meshing),
// every Boolean mode, nested warps and, optionally, mesh leaves.
#pragma once

#include "runtime/builder.hpp"
#include "tests/support/test_support.hpp"

#include <memory>
#include <vector>

namespace ht::test {

struct RandomTreeOptions {
  int max_depth = 4;
  int max_children = 3;
  /// Meshes that mesh leaves pick from (empty: no mesh leaves). Each is scaled to about 1 unit.
  std::vector<std::shared_ptr<const MeshLeaf>> meshes;
};

/// Builds a random subtree in b and returns its root. Shapes live in about [-2, 2]^3.
NodeId random_tree(Builder& b, Rng& rng, const RandomTreeOptions& options, int depth = 0);

/// eight.off and sphere.off as mesh leaves, loaded once for the process (what random trees
/// with mesh leaves pick from).
const std::vector<std::shared_ptr<const MeshLeaf>>& small_meshes();

/// A random point in [-lo, lo]^3.
glm::dvec3 random_point(Rng& rng, double extent);

}  // namespace ht::test
