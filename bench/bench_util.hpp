// Shared by the benchmarks: quick mode, where the meshes are, and scene generators.
#pragma once

#include "runtime/tree.hpp"

#include <filesystem>
#include <string>

namespace ht::bench {

extern bool quick_mode;

/// data/meshes/NAME (tools/setup.sh extracts it from Debian's libcgal-demo).
inline std::filesystem::path cgal_mesh(const std::string& name) {
  return std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / "data" / "meshes" / name;
}

}  // namespace ht::bench
