// The fuzz targets' shared parts (fuzz/fuzz_support.hpp). The mesh readers' target checks what
// MeshLeaf promises of a mesh it accepts (nodes/mesh_leaf.hpp): closed, consistently oriented,
// finite, its report true to it, and queries that agree with a brute-force nearest triangle.
#include "fuzz/fuzz_support.hpp"

#include "meshers/mesh_io.hpp"
#include "nodes/mesh_leaf.hpp"
#include "nodes/primitives.hpp"

#include <glm/geometric.hpp>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <typeinfo>
#include <utility>
#include <vector>

namespace ht::fuzz {

void finding(const std::string& what) {
  std::fprintf(stderr, "finding: %s\n", what.c_str());
  std::fflush(stderr);
  std::abort();
}

namespace {

// This process's scratch folder, removed when the process ends normally (after a finding
// libFuzzer keeps the input itself, so a folder left in /tmp holds nothing new).
class ScratchDir {
 public:
  ScratchDir()
      : path_(std::filesystem::temp_directory_path() / ("hybridtree-fuzz-" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

const std::filesystem::path& scratch_dir() {
  static const ScratchDir dir;
  return dir.path();
}

std::string describe(const std::exception& e) { return std::string(typeid(e).name()) + ": " + e.what(); }

// A refusal must say which file and what is wrong, in one readable line.
void check_refusal(const MeshError& e, const std::filesystem::path& file) {
  const std::string msg = e.what();
  require(msg.rfind(file.string() + ": ", 0) == 0, "MeshError does not start with the file name: " + msg);
  require(msg.size() > file.string().size() + 2 && msg.size() < 400, "MeshError message empty or too long: " + msg);
  require(msg.find('\n') == std::string::npos, "MeshError message spans lines: " + msg);
}

// Every directed edge once, and its reverse once: closed, 2-manifold along edges, oriented.
void check_closed_oriented(const MeshLeaf& leaf) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
  edges.reserve(3 * leaf.triangles().size());
  for (const glm::uvec3& t : leaf.triangles())
    for (int k = 0; k < 3; ++k) edges.emplace_back(t[k], t[(k + 1) % 3]);
  std::sort(edges.begin(), edges.end());
  require(std::adjacent_find(edges.begin(), edges.end()) == edges.end(), "a directed edge twice in a loaded mesh");
  for (const auto& [a, b] : edges)
    require(std::binary_search(edges.begin(), edges.end(), std::pair{b, a}), "an unpaired edge in a loaded mesh");
}

void check_report(const MeshLeaf& leaf) {
  const MeshReport& r = leaf.report();
  require(r.triangles == leaf.triangles().size(), "report.triangles differs from the triangles held");
  require(r.vertices == leaf.positions().size(), "report.vertices differs from the vertices held");
  require(r.components >= 1 && r.components <= r.triangles, "report.components out of range");
  for (const glm::uvec3& t : leaf.triangles())
    for (int k = 0; k < 3; ++k) require(t[k] < leaf.positions().size(), "a triangle index past the vertices");
  for (const glm::dvec3& p : leaf.positions()) {
    require(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z), "a non-finite vertex was accepted");
  }
}

double brute_distance(const MeshLeaf& leaf, const glm::dvec3& p) {
  double best = std::numeric_limits<double>::infinity();
  const auto& pos = leaf.positions();
  for (const glm::uvec3& t : leaf.triangles())
    best = std::min(best, glm::length(p - closest_on_triangle(p, pos[t[0]], pos[t[1]], pos[t[2]]).point));
  return best;
}

// A few points around and inside the mesh: the BVH query must find the nearest triangle the
// brute-force walk finds (to float rounding of the box, which Embree works in), and the field
// must lie between 0 and F.
void check_queries(const MeshLeaf& leaf) {
  const Aabb& box = leaf.bounds();
  const double diag = glm::length(box.size());
  const double R = std::isfinite(diag) && diag > 0 ? 0.25 * diag : 1.0;
  const MeshFieldParams params = mesh_field_params(R, 1.0, 0.5);
  std::vector<glm::dvec3> points = {box.center(), box.lo - glm::dvec3(0.1 * R), box.hi + glm::dvec3(0.3 * R),
                                    box.lo + glm::dvec3(0.37, 0.51, 0.23) * box.size()};
  for (std::size_t v = 0; v < std::min<std::size_t>(leaf.positions().size(), 4); ++v)
    points.push_back(leaf.positions()[v] + glm::dvec3(0.01 * R, -0.02 * R, 0.015 * R));
  const double mag = std::max({std::abs(box.lo.x), std::abs(box.lo.y), std::abs(box.lo.z), std::abs(box.hi.x),
                               std::abs(box.hi.y), std::abs(box.hi.z), R});
  for (const glm::dvec3& p : points) {
    if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) continue;
    const MeshLeaf::Closest c = leaf.query(p, R);
    const double brute = brute_distance(leaf, p);
    const double tol = 1e-5 * mag;
    if (std::isfinite(c.distance)) {
      require(c.distance >= 0 && c.distance <= R, "query distance outside [0, radius]");
      require(std::abs(c.distance - brute) <= tol, "query distance " + std::to_string(c.distance) +
                                                       " but the nearest triangle is at " + std::to_string(brute));
    } else {
      require(!(brute < R - tol), "query found no triangle within the radius, but one is at " + std::to_string(brute));
    }
    const double f = mesh_field(leaf, params, p);
    require(std::isfinite(f) && f >= 0.0 && f <= 1.0, "mesh field " + std::to_string(f) + " outside [0, F]");
  }
}

// Written in the format read, then read back: the same triangles. STL keeps no shared vertices:
// its reader merges them by position, and facets that merging makes degenerate (two vertices of a
// repaired hole at one place) are dropped, so there a refusal or fewer triangles are allowed.
void check_round_trip(const MeshLeaf& leaf, const std::string& ext) {
  const std::filesystem::path file = scratch_dir() / ("round" + ext);
  try {
    write_mesh(*leaf.manifold_surface(), file);
  } catch (const MeshWriteError&) {
    return;  // refused with a message (an OpenMesh writer's own limits): no crash, nothing to read
  }
  try {
    const auto back = MeshLeaf::load(file);
    require(ext == ".stl" || back->triangles().size() == leaf.triangles().size(),
            "written and read back: triangle count changed");
  } catch (const MeshError& e) {
    require(ext == ".stl", std::string("a loaded mesh, written, is refused when read back: ") + e.what());
  }
}

}  // namespace

std::filesystem::path scratch_file(const std::string& name, std::string_view bytes) {
  const std::filesystem::path file = scratch_dir() / name;
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  require(static_cast<bool>(out), "cannot write the scratch file " + file.string());
  return file;
}

std::filesystem::path mesh_dir() { return HYBRIDTREE_FUZZ_MESH_DIR; }

int mesh_input(const std::uint8_t* data, std::size_t size, const std::string& ext) {
  if (size > kMaxInputBytes) return 0;
  const std::filesystem::path file =
      scratch_file("input" + ext, std::string_view(reinterpret_cast<const char*>(data), size));
  for (const bool repair : {false, true}) {
    std::shared_ptr<const MeshLeaf> leaf;
    try {
      leaf = MeshLeaf::load(file, repair);
    } catch (const MeshError& e) {
      check_refusal(e, file);
      continue;
    } catch (const std::exception& e) {
      finding("MeshLeaf::load threw " + describe(e));
    } catch (...) {
      finding("MeshLeaf::load threw something not derived from std::exception");
    }
    check_report(*leaf);
    check_closed_oriented(*leaf);
    try {
      check_queries(*leaf);
      check_round_trip(*leaf, ext);
    } catch (const std::exception& e) {
      finding("a loaded mesh's queries or write threw " + describe(e));
    }
    return 0;
  }
  return 0;
}

}  // namespace ht::fuzz
