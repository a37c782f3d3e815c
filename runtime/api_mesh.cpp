// Meshing and mesh output of the embedding API (runtime/api.hpp): the run `hybridtree mesh`
// makes (meshers/mesh_run.hpp), its result as flat arrays, and meshers/mesh_io.hpp's writer.
#include "runtime/api.hpp"

#include "meshers/disk_cache.hpp"
#include "meshers/mesh_io.hpp"
#include "meshers/mesh_run.hpp"
#include "meshers/node_cache.hpp"
#include "runtime/api_impl.hpp"

#include <tbb/task_arena.h>

#include <cmath>

namespace hybridtree {

namespace {

ht::MeshRunOptions run_options(const MeshOptions& o) {
  if (!(std::isfinite(o.precision) && o.precision >= 0))
    throw InputError("precision: must be >= 0 (0: the scene's), not " + std::to_string(o.precision), {}, "precision");
  if (!(std::isfinite(o.memory_budget_gib) && o.memory_budget_gib > 0))
    throw InputError("memory_budget_gib: must be > 0, not " + std::to_string(o.memory_budget_gib), {},
                     "memory_budget_gib");
  if (o.threads < 0) throw InputError("threads: must be >= 0, not " + std::to_string(o.threads), {}, "threads");
  ht::MeshRunOptions r;
  r.precision = o.precision;
  r.strategy = o.strategy == Strategy::Auto     ? "auto"
               : o.strategy == Strategy::Global ? "global"
               : o.strategy == Strategy::Local  ? "local"
                                                : "";
  r.memory_gib = o.memory_budget_gib;
  r.sharp_features = o.sharp_features;
  r.quality = o.quality;
  r.progress = o.progress;
  r.cancel = o.cancel;
  return r;
}

Mesh to_mesh(const Tree::Impl& impl, const ht::MeshRun& run) {
  const ht::TriangleMesh& m = *run.result.mesh;
  Mesh out;
  out.vertices.reserve(3 * m.positions.size());
  for (const glm::dvec3& p : m.positions) out.vertices.insert(out.vertices.end(), {p.x, p.y, p.z});
  out.triangles.reserve(3 * m.triangles.size());
  for (const glm::uvec3& t : m.triangles) out.triangles.insert(out.triangles.end(), {t.x, t.y, t.z});
  MeshStats& s = out.stats;
  s.triangles = run.checks.triangles;
  s.vertices = run.checks.vertices;
  s.precision = run.options.precision;
  s.seconds = run.mesh_seconds;
  s.watertight = run.checks.watertight();
  s.genus = run.checks.genus;
  s.strategy = run.strategy;
  s.root_strategy = ht::root_strategy(run, impl.loaded.root());
  s.json = ht::mesh_stats_json(impl.loaded, run, impl.source, impl.load_seconds);
  if (run.options.cache)
    for (const ht::NodeReport& r : run.result.nodes) {
      if (r.reused) s.reused_nodes.push_back(impl.loaded.graph().label(r.node));
      else ++s.cache_misses;
    }
  return out;
}

// Tree::mesh and Session::mesh: the run, in a task arena of options.threads when asked.
Mesh mesh_with(const Tree::Impl& impl, const MeshOptions& options, ht::NodeCache* cache) {
  ht::MeshRunOptions o = run_options(options);
  o.cache = cache;
  return guarded(impl.source, [&] {
    auto run = [&] { return to_mesh(impl, ht::run_mesh(impl.loaded, o)); };
    if (options.threads == 0) return run();
    tbb::task_arena arena(options.threads);
    return arena.execute(run);
  });
}

}  // namespace

struct Session::Impl {
  Impl(std::size_t bytes, std::unique_ptr<ht::DiskCache> folder) : disk(std::move(folder)), cache(bytes, disk.get()) {}
  std::unique_ptr<ht::DiskCache> disk;  // before the cache, which holds it
  ht::NodeCache cache;
};

Mesh Tree::mesh(const MeshOptions& options) const { return mesh_with(*impl_, options, nullptr); }

Mesh Session::mesh(const Tree& tree, const MeshOptions& options) { return mesh_with(*tree.impl_, options, &impl_->cache); }

Session::Session(std::size_t cache_bytes) : impl_(std::make_unique<Impl>(cache_bytes, nullptr)) {}

namespace {
std::unique_ptr<ht::DiskCache> open_folder(const std::string& folder, std::uint64_t bytes) {
  try {
    return std::make_unique<ht::DiskCache>(folder, bytes);
  } catch (const ht::DiskCacheError& e) {
    throw InputError(e.what(), folder);
  }
}
}  // namespace

Session::Session(std::size_t cache_bytes, const std::string& folder, std::uint64_t folder_bytes)
    : impl_(std::make_unique<Impl>(cache_bytes, open_folder(folder, folder_bytes))) {}
Session::~Session() = default;
std::size_t Session::cache_bytes() const { return impl_->cache.stats().bytes + impl_->cache.pieces().stats().bytes; }
std::size_t Session::cache_entries() const {
  return impl_->cache.stats().entries + impl_->cache.pieces().stats().entries;
}
void Session::clear() { impl_->cache.clear(); }

void write_mesh(std::span<const double> vertices, std::span<const std::uint32_t> triangles, const std::string& file) {
  if (!ht::supported_mesh_extension(file))
    throw InputError(file + ": unsupported output extension (use .ply, .obj, .off or .stl)", file);
  if (vertices.size() % 3 != 0 || triangles.size() % 3 != 0)
    throw InputError(file + ": vertices and triangles must be (n, 3) arrays (sizes " + std::to_string(vertices.size()) +
                         " and " + std::to_string(triangles.size()) + " are not multiples of 3)", file);
  ht::TriangleMesh m;
  m.positions.resize(vertices.size() / 3);
  for (std::size_t i = 0; i < m.positions.size(); ++i)
    m.positions[i] = {vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2]};
  m.triangles.resize(triangles.size() / 3);
  for (std::size_t i = 0; i < m.triangles.size(); ++i) {
    m.triangles[i] = {triangles[3 * i], triangles[3 * i + 1], triangles[3 * i + 2]};
    for (int k = 0; k < 3; ++k)
      if (m.triangles[i][k] >= m.positions.size())
        throw InputError(file + ": triangles[" + std::to_string(i) + "] names vertex " +
                             std::to_string(m.triangles[i][k]) + " of " + std::to_string(m.positions.size()), file,
                         "triangles[" + std::to_string(i) + "]");
  }
  guarded(file, [&] { ht::write_mesh(m, file); });
}

void write_mesh(const Mesh& mesh, const std::string& file) { write_mesh(mesh.vertices, mesh.triangles, file); }

}  // namespace hybridtree
