#include "meshers/mesh_run.hpp"

#include "meshers/polygonize.hpp"
#include "meshers/surface_field.hpp"
#include "runtime/node_params.hpp"
#include "runtime/tape.hpp"

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <limits>

namespace ht {

double default_precision(const Tree& tree, double requested) {
  if (requested > 0) return requested;
  if (tree.mesher_settings().precision > 0) return tree.mesher_settings().precision;
  const Aabb solid = solid_bounds(tree.graph(), tree.root(), tree.threshold());
  return solid.finite() ? std::max(glm::length(solid.size()) / 100.0, 1e-9) : 1.0;
}

void check_float_range(const Tree& tree) {
  // Every subtree with no unprepared ffd is compiled (an ffd stops the compiler, and a check
  // that stopped there let a twist beside it fill memory for 25 s before its error); the
  // subtrees under an ffd are compiled on their own.
  const auto& g = tree.graph_ptr();
  // Per node: 0 unknown, 1 no unprepared ffd at or under it, 2 one at least (memoized: a chain
  // of unions over an ffd asks once a node).
  std::vector<std::uint8_t> ffd(g->size(), 0);
  const std::function<bool(NodeId)> has_ffd = [&](NodeId n) {
    if (ffd[n] == 0) {
      bool any = params::ffd_unprepared(*g, n);
      for (NodeId c : g->children_of(n)) any = has_ffd(c) || any;
      ffd[n] = any ? 2 : 1;
    }
    return ffd[n] == 2;
  };
  std::vector<std::uint8_t> seen(g->size(), 0);
  std::vector<NodeId> stack{tree.root()};
  while (!stack.empty()) {
    const NodeId n = stack.back();
    stack.pop_back();
    if (seen[n]) continue;
    seen[n] = 1;
    if (!has_ffd(n)) {
      (void)compile_tape(g, n, tree.threshold());
      continue;
    }
    for (NodeId c : g->children_of(n)) stack.push_back(c);
  }
}

void check_precision(const Tree& tree, double precision) {
  const Aabb solid = solid_bounds(tree.graph(), tree.root(), tree.threshold());
  if (solid.empty()) return;
  if (const std::string why = unmeshable_extent(solid); !why.empty()) throw PolygonizeError(why);
  if (const std::string why = unresolvable_precision(solid, precision); !why.empty()) throw PolygonizeError(why);
  if (!solid.finite()) return;
  const double across = glm::length(solid.size());
  if (precision <= across) return;
  char buf[256];
  if (!(across > 0))  // a radius of 1e-300: the box underflows to a point
    std::snprintf(buf, sizeof buf,
                  "the scene's solid lies in a box of no size (a radius or scale below what doubles hold?): no "
                  "precision can resolve its surface");
  else
    std::snprintf(buf, sizeof buf,
                  "precision %g is coarser than the whole scene (its solid lies in a box %g across): no part of the "
                  "surface can be resolved; use at most %g (the scene's default: %g)",
                  precision, across, across, default_precision(tree, 0.0));
  throw PolygonizeError(buf);
}

namespace {

// Every mesher returns a closed, oriented manifold with finite vertices; where one did not (a
// scene whose numbers pass what it handles: a disc of radius 1e150 swept open, a normal of 1e155
// squared past doubles into NaN vertices), the run stops rather than return it.
void refuse_broken(const MeshChecks& c) {
  if (c.triangles == 0 || (c.closed() && c.manifold() && c.oriented() && c.nonfinite_vertices == 0)) return;
  // Degenerate triangles and crossings are reported, not refused: a global run may return its
  // last refinement with a few (mesh_plan.cpp), and a closed leaf may hold a zero-area cap.
  MeshChecks topology = c;
  topology.self_intersecting_pairs = topology.degenerate_triangles = 0;
  throw PolygonizeError("the mesh made is no closed manifold (" + describe_defects(topology) +
                        "): a number of the scene's is past what the meshers handle (a radius, normal, rate or "
                        "threshold of extreme size?); nothing was written");
}

MeshStrategy strategy_of(const std::string& name) {
  return name == "global" ? MeshStrategy::Global : name == "local" ? MeshStrategy::Local : MeshStrategy::Auto;
}

std::string scene_strategy(const Tree& tree) {
  const MesherHint s = tree.mesher_settings().strategy;
  return s == MesherHint::Global ? "global" : s == MesherHint::Local ? "local" : "auto";
}

nlohmann::json node_json(const Graph& g, const NodeReport& e) {
  nlohmann::json n = {{"node", g.label(e.node)},
                      {"id", e.node},
                      {"kind", std::string(kind_name(g.kind[e.node]))},
                      {"strategy", to_string(e.strategy)},
                      {"reason", to_string(e.reason)},
                      {"triangles", e.triangles},
                      {"seconds", e.seconds}};
  if (e.rho >= 0) n["rho"] = e.rho;
  if (e.reused) n["reused"] = true;
  if (!e.fallback_cause.empty()) n["fallback_cause"] = e.fallback_cause;
  if (!e.refinements.empty()) n["refinements"] = e.refinements;
  if (e.polygonized) {
    n["bricks"] = {{"total", e.polygonize.bricks_total}, {"active", e.polygonize.bricks_active},
                   {"reused", e.polygonize.bricks_reused}, {"points_evaluated", e.polygonize.points_evaluated},
                   {"refine_evaluations", e.polygonize.refine_evaluations}};
    n["quality"] = {{"collapses", e.polygonize.quality.collapses}, {"flips", e.polygonize.quality.flips},
                    {"moved", e.polygonize.quality.moved}, {"pieces", e.polygonize.quality.pieces},
                    {"pieces_reused", e.polygonize.quality.pieces_reused}, {"retries", e.polygonize.quality.retries},
                    {"seconds", e.polygonize.quality.seconds}};
  }
  if (e.strategy == JobStrategy::TrimBlend || e.strategy == JobStrategy::TrimBoolean ||
      e.strategy == JobStrategy::TrimCrop || e.strategy == JobStrategy::TrimLocalBlend)
    n["local"] = {{"operand_triangles", e.local.operand_triangles},
                  {"kept_triangles", e.local.kept_triangles},
                  {"patch_triangles", e.local.patch_triangles},
                  {"stitch_welded", e.local.stitch.welded},
                  {"stitch_inserted", e.local.stitch.inserted},
                  {"stitch_largest_gap", e.local.stitch.largest_gap},
                  {"band_loops", e.local.bridge.loops},
                  {"band_triangles", e.local.bridge.band_triangles},
                  {"band_widest", e.local.bridge.widest},
                  {"band_holes_closed", e.local.bridge.holes_closed},
                  {"self_intersections", e.local.self_intersections}};
  if (e.edges_split) n["edges_split"] = e.edges_split;
  return n;
}

// The polygonizer's statistics summed over every job that ran it.
PolygonizeStats total_polygonize(const MeshResult& r) {
  PolygonizeStats s;
  for (const NodeReport& e : r.nodes) {
    if (!e.polygonized) continue;
    const PolygonizeStats& p = e.polygonize;
    s.bricks_total += p.bricks_total;
    s.bricks_active += p.bricks_active;
    s.bricks_reused += p.bricks_reused;
    s.points_evaluated += p.points_evaluated;
    s.refine_evaluations += p.refine_evaluations;
    s.crease_edges += p.crease_edges;
    s.corner_vertices += p.corner_vertices;
    s.crease_candidates += p.crease_candidates;
    s.crease_spread += p.crease_spread;
    s.crease_intersections += p.crease_intersections;
    s.unfold.pairs_before += p.unfold.pairs_before;
    s.unfold.pairs_after += p.unfold.pairs_after;
    s.unfold.collapses += p.unfold.collapses;
    s.unfold.seconds += p.unfold.seconds;
    s.folds += p.folds;
    s.snap.merged_vertices += p.snap.merged_vertices;
    s.snap.removed_triangles += p.snap.removed_triangles;
    s.snap.skipped_points += p.snap.skipped_points;
    s.snap.crease_points += p.snap.crease_points;
    s.seconds_classify += p.seconds_classify;
    s.seconds_sample += p.seconds_sample;
    s.seconds_extract += p.seconds_extract;
    s.seconds_merge += p.seconds_merge;
    s.seconds_features += p.seconds_features;
    s.quality += p.quality;
  }
  return s;
}

// With a node cache: jobs reused (hits) and run (misses), and the reused nodes' labels.
nlohmann::json cache_json(const Graph& g, const MeshResult& r) {
  nlohmann::json reused = nlohmann::json::array();
  for (const NodeReport& e : r.nodes)
    if (e.reused) reused.push_back(g.label(e.node));
  return {{"hits", reused.size()}, {"misses", r.nodes.size() - reused.size()}, {"reused_nodes", reused}};
}

nlohmann::json disk_json(const DiskCacheStats& s) {
  nlohmann::json ignored = nlohmann::json::object();
  for (std::size_t i = 0; i < kDiskIgnoreReasons; ++i)
    if (s.ignored[i]) ignored[to_string(DiskIgnore(i))] = s.ignored[i];
  return {{"hits", s.hits},
          {"misses", s.misses},
          {"written", s.written},
          {"write_failures", s.write_failures},
          {"evicted", s.evicted},
          {"ignored", ignored},
          {"parts", {{"hits", s.part_hits}, {"misses", s.part_misses}, {"written", s.part_written}}}};
}

nlohmann::json checks_json(const MeshChecks& c) {
  return {{"closed", c.closed()},
          {"manifold", c.manifold()},
          {"oriented", c.oriented()},
          {"watertight", c.watertight()},
          {"boundary_edges", c.boundary_edges},
          {"nonmanifold_edges", c.nonmanifold_edges},
          {"nonmanifold_vertices", c.nonmanifold_vertices},
          {"misoriented_edges", c.misoriented_edges},
          {"degenerate_triangles", c.degenerate_triangles},
          {"nonfinite_vertices", c.nonfinite_vertices},
          {"components", c.components},
          {"euler_characteristic", c.euler},
          {"genus", c.genus},
          {"area", c.area},
          {"volume", c.volume},
          {"min_angle_degrees", c.min_angle},
          {"min_angle_p1_degrees", c.min_angle_p1},
          {"min_angle_histogram_10deg", c.min_angle_histogram},
          {"surface_error_vertex_max", c.vertex_error_max},
          {"surface_error_vertex_mean", c.vertex_error_mean},
          {"surface_error_face_max", c.face_error_max},
          {"surface_error_face_mean", c.face_error_mean},
          {"self_intersecting_pairs", c.self_intersecting_pairs},
          {"inverted_faces", c.inverted_faces},
          {"inverted_area", c.inverted_area},
          {"folded_triangles", c.folded_triangles},
          {"angles", {{"kept_triangles", c.kept_triangles},
                      {"made_min_degrees", c.made_min_angle},
                      {"made_p1_degrees", c.made_min_angle_p1},
                      {"crease_triangles", c.crease_triangles},
                      {"smooth_triangles", c.smooth_triangles},
                      {"smooth_min_degrees", c.smooth_min_angle},
                      {"smooth_p1_degrees", c.smooth_min_angle_p1}}}};
}

}  // namespace

MeshRun run_mesh(const Tree& tree, const MeshRunOptions& o) {
  using clock = std::chrono::steady_clock;
  MeshRun run;
  MeshOptions& options = run.options;
  options.precision = default_precision(tree, o.precision);
  try {
    check_precision(tree, options.precision);
  } catch (const PolygonizeError& e) {
    // A precision nobody gave is named as the default it is, or the user looks for it in vain.
    char named[48];
    std::snprintf(named, sizeof named, "precision %g ", options.precision);
    if (o.precision > 0 || tree.mesher_settings().precision > 0 || std::string(e.what()).find(named) == std::string::npos) throw;
    char buf[160];
    std::snprintf(buf, sizeof buf, " (precision %g is the default: neither --precision nor the scene's mesher.precision gave one)",
                  options.precision);
    throw PolygonizeError(e.what() + std::string(buf));
  }
  check_float_range(tree);
  // More GiB than size_t holds in bytes (--memory-budget 1e12) is no limit: the cast alone was
  // undefined and gave 0 bytes.
  const double bytes = o.memory_gib * double(1u << 30);
  options.polygonize.memory_budget = bytes < 0x1p64 ? static_cast<std::size_t>(bytes) : std::numeric_limits<std::size_t>::max();
  options.polygonize.sharp_features = o.sharp_features;
  options.polygonize.quality.enabled = o.quality;
  options.blend_overlap = tree.mesher_settings().blend_overlap;
  options.progress = o.progress;
  options.cancel = o.cancel;
  options.cache = o.cache;
  run.strategy = o.strategy.empty() ? scene_strategy(tree) : o.strategy;
  options.strategy = strategy_of(run.strategy);
  DiskCache* disk = o.cache ? o.cache->disk() : nullptr;
  const DiskCacheStats disk_before = disk ? disk->stats() : DiskCacheStats{};
  const auto t1 = clock::now();
  run.result = mesh_tree(tree, options);
  run.mesh_seconds = std::chrono::duration<double>(clock::now() - t1).count();
  if (disk) {
    disk->trim();
    run.disk = disk->stats() - disk_before;
  }
  const auto t2 = clock::now();
  const TriangleMesh& mesh = *run.result.mesh;
  run.checks = check_mesh(mesh, o.full_checks);
  refuse_broken(run.checks);
  if (!mesh.triangles.empty() && o.full_checks) {
    // On tapes specialized to bricks of sixteen cells (as the local strategies'; eight compiles
    // twice the bricks for little shorter tapes): a big tree's root tape would pay for every
    // primitive at each of the vertices and face centres.
    SurfaceField field(run.result.tree->graph_ptr(), run.result.tree->root(), tree.threshold(),
                       mesh.positions.front(), 16.0 * options.precision);
    const auto kept = kept_leaf_triangles(mesh, run.result.tree->graph(), run.result.tree->root());
    measure_surface_error(mesh, field, run.checks, kept);
  }
  run.check_seconds = std::chrono::duration<double>(clock::now() - t2).count();
  return run;
}

std::string root_strategy(const MeshRun& run, NodeId root) {
  for (const NodeReport& e : run.result.nodes)
    if (e.node == root) return std::string(to_string(e.strategy)) + " (" + to_string(e.reason) + ")";
  return "?";
}

std::string mesh_stats_json(const Tree& tree, const MeshRun& run, const std::string& scene, double load_seconds,
                            const std::string& output, double write_seconds) {
  const MeshChecks& c = run.checks;
  nlohmann::json j;
  j["scene"] = scene;
  if (!output.empty()) j["output"] = output;
  j["precision"] = run.options.precision;
  j["strategy"] = run.strategy;
  nlohmann::json nodes = nlohmann::json::array();
  for (const NodeReport& e : run.result.nodes) nodes.push_back(node_json(tree.graph(), e));
  j["nodes"] = nodes;
  if (run.options.cache) j["cache"] = cache_json(tree.graph(), run.result);
  if (run.disk) j["cache"]["disk"] = disk_json(*run.disk);
  j["triangles"] = c.triangles;
  j["vertices"] = c.vertices;
  j["checks"] = checks_json(c);
  const PolygonizeStats stats = total_polygonize(run.result);
  j["bricks"] = {{"total", stats.bricks_total}, {"active", stats.bricks_active}, {"reused", stats.bricks_reused}};
  j["sharp_features"] = {{"candidate_edges", stats.crease_candidates},
                         {"spread_edges", stats.crease_spread},
                         {"crease_edges_split", stats.crease_edges},
                         {"corner_vertices", stats.corner_vertices},
                         {"intersecting_pairs_after_sliding", stats.unfold.pairs_before},
                         {"unfold_collapses", stats.unfold.collapses},
                         {"intersecting_pairs_left", stats.crease_intersections}};
  j["folds"] = {{"found", stats.folds.pairs_before}, {"collapses", stats.folds.collapses}, {"left", stats.folds.pairs_after}};
  j["snap"] = {{"merged_vertices", stats.snap.merged_vertices},
               {"removed_triangles", stats.snap.removed_triangles},
               {"crease_points", stats.snap.crease_points},
               {"skipped_points", stats.snap.skipped_points}};
  j["quality"] = {{"enabled", run.options.polygonize.quality.enabled}, {"collapses", stats.quality.collapses},
                  {"flips", stats.quality.flips},         {"splits", stats.quality.splits},
                  {"moved", stats.quality.moved},         {"reverted", stats.quality.reverted},
                  {"retries", stats.quality.retries},
                  {"skipped", stats.quality.skipped}};
  j["seconds"] = {{"load", load_seconds},
                  {"classify", stats.seconds_classify},
                  {"sample", stats.seconds_sample},
                  {"extract", stats.seconds_extract},
                  {"merge", stats.seconds_merge},
                  {"features", stats.seconds_features},
                  {"unfold", stats.unfold.seconds},
                  {"quality", stats.quality.seconds},
                  {"mesh_total", run.mesh_seconds},
                  {"checks", run.check_seconds}};
  if (!output.empty()) j["seconds"]["write"] = write_seconds;
  return j.dump(2) + "\n";
}

}  // namespace ht
