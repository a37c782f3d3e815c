// Shared by the test suites: where the meshes are, a deterministic random source, and a way to
// run the command-line tool.
#pragma once

#include "meshers/mesh_checks.hpp"
#include "meshers/mesh_plan.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <random>
#include <string>

namespace ht::test {

/// data/meshes/NAME from tools/setup.sh (libcgal-demo); the test fails if it is missing.
std::filesystem::path cgal_mesh(const std::string& name);
/// ../shared/data/meshes/NAME beside the checkout, or empty when absent.
std::filesystem::path shared_mesh(const std::string& name);
/// Whether Igea (igea-67k.ply, from ../shared beside the checkout) is in data/meshes/ or
/// ../shared: the examples that stand for the paper's Igea scenes (bowl, restoration, both
/// snake-women) load it; where it is missing, so are they.
bool igea_available();
/// A fresh empty folder for one test's files.
std::filesystem::path temp_dir(const std::string& tag);
/// Writes text to a file.
void write_file(const std::filesystem::path& file, const std::string& text);
/// A file's bytes (empty when it cannot be read).
std::string read_file(const std::filesystem::path& file);
/// The same vertex positions (bit for bit) and triangles.
bool same_bytes(const TriangleMesh& a, const TriangleMesh& b);

/// Runs the hybridtree CLI with `args` (shell words), stdin from `input`; returns exit code and
/// the captured stdout and stderr. Safe to call from several threads at once.
struct CliResult {
  int code;
  std::string out, err;
};
CliResult run_cli(const std::string& args, const std::string& input = "");

/// True in the sanitized build (-DHYBRIDTREE_SANITIZE=ON, cmake/Sanitize.cmake), where code runs
/// several times slower and stack frames are several times larger (the sanitizers' redzones).
/// The one switch the tests read to adapt to it; the normal builds run every test in full.
inline constexpr bool kSanitized =
#ifdef HYBRIDTREE_SANITIZED
    true;
#else
    false;
#endif

/// Runs fn on a thread of its own whose stack is `bytes` long and waits for it; rethrows what fn
/// throws. For deep recursions whose frames the sanitizers inflate past the main thread's stack.
void run_on_stack(std::size_t bytes, const std::function<void()>& fn);

/// An icosahedron subdivided `levels` times (each triangle into four) onto the sphere of `radius`
/// around `centre`: 20 * 4^levels triangles, counter-clockwise from outside, closed.
TriangleMesh icosphere(int levels, double radius = 1.0, glm::dvec3 centre = glm::dvec3(0.0));

/// Mesh plan options at precision h with strategy s (meshers/mesh_plan.hpp).
MeshOptions mesh_options(double h, MeshStrategy s = MeshStrategy::Auto);

/// Deterministic random numbers: every property test seeds from its own name.
using Rng = std::mt19937_64;

/// A generator seeded from the running test's name (FNV-1a, the same on every platform).
Rng seeded();

/// A tree's root polygonized at T = tree.threshold(), with its checks and surface error.
struct Polygonized {
  TriangleMesh mesh;
  MeshChecks checks;
  PolygonizeStats stats;
};
Polygonized polygonize_checked(const Tree& tree, const PolygonizeOptions& options);

/// check_mesh() of a mesh plan's result with its surface error measured on the result's tree at
/// T = threshold: the checks that count folded triangles, which check_mesh() alone leaves at 0.
MeshChecks checks_with_surface(const MeshResult& r, double threshold);

}  // namespace ht::test
