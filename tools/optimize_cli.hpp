// The optimizer on the command line: `hybridtree optimize SCENE -o OUT.json`, the tree every
// other command runs (optimized unless --no-optimize), and the lines `info` prints about it.
#pragma once

#include "runtime/optimize.hpp"

#include <string>

namespace ht::cli {

/// The scene as loaded (runtime/scene.hpp), optimized when `optimize` (stats filled if given).
Tree load_tree(const std::string& scene, bool optimize, OptimizeStats* stats = nullptr);

/// What the optimizer did, one line a figure (for `info` and `optimize`).
std::string optimizer_report(const OptimizeStats& s);

struct OptimizeArgs {
  std::string scene, out;  ///< out: the rewritten scene (JSON); "-" for stdout
};

/// Writes the optimized scene (atomically) and prints the report; 0 on success.
int cmd_optimize(const OptimizeArgs& a);

}  // namespace ht::cli
