// Shared by the benchmarks: quick mode, where the meshes are, and scene generators.
#pragma once

#include "runtime/tree.hpp"

#include <filesystem>
#include <string>

namespace ht::bench {

extern bool quick_mode;

/// A meshing benchmark's precision: `full`, or twice as coarse in quick mode (about a quarter of
/// the triangles and the time; the ratios the benchmark is read for hold at either).
inline double precision(double full) { return quick_mode ? 2.0 * full : full; }

/// data/meshes/NAME (tools/setup.sh extracts it from Debian's libcgal-demo).
inline std::filesystem::path cgal_mesh(const std::string& name) {
  return std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / "data" / "meshes" / name;
}

}  // namespace ht::bench
