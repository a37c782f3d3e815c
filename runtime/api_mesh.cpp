// Meshing and mesh output of the embedding API (runtime/api.hpp): the run `hybridtree mesh`
// makes (meshers/mesh_run.hpp), its result as flat arrays, and meshers/mesh_io.hpp's writer.
#include "runtime/api.hpp"

#include "meshers/mesh_io.hpp"
#include "meshers/mesh_run.hpp"
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
  return out;
}

}  // namespace

Mesh Tree::mesh(const MeshOptions& options) const {
  const ht::MeshRunOptions o = run_options(options);
  return guarded(impl_->source, [&] {
    auto run = [&] { return to_mesh(*impl_, ht::run_mesh(impl_->loaded, o)); };
    if (options.threads == 0) return run();
    tbb::task_arena arena(options.threads);
    return arena.execute(run);
  });
}

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
