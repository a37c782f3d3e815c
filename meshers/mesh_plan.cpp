#include "meshers/mesh_plan.hpp"

#include "meshers/ffd.hpp"
#include "meshers/mesh_checks.hpp"
#include "meshers/node_cache.hpp"
#include "meshers/self_intersections.hpp"
#include "meshers/sweep.hpp"
#include "meshers/warp_mesh.hpp"
#include "meshers/winding_surface.hpp"
#include "nodes/mesh_leaf.hpp"
#include "nodes/warps.hpp"
#include "runtime/node_params.hpp"
#include "runtime/subtree_hash.hpp"
#include "runtime/tape.hpp"
#include "runtime/tape_eval.hpp"

#include <glm/geometric.hpp>
#include <tbb/flow_graph.h>
#include <tbb/parallel_for.h>

#include <bit>
#include <chrono>
#include <cmath>
#include <exception>
#include <functional>
#include <mutex>

namespace ht {

const char* to_string(JobStrategy s) {
  switch (s) {
    case JobStrategy::SharedLeaf: return "shared leaf mesh";
    case JobStrategy::Sweep: return "sweep";
    case JobStrategy::WarpedChild: return "warped child";
    case JobStrategy::DeformedChild: return "deformed child (ffd)";
    case JobStrategy::Global: return "global";
    case JobStrategy::TrimBlend: return "trim blend";
    case JobStrategy::TrimBoolean: return "trim boolean";
    case JobStrategy::TrimCrop: return "trim crop";
    case JobStrategy::TrimLocalBlend: return "trim local blend";
    case JobStrategy::Empty: return "empty";
  }
  return "?";
}

const char* to_string(JobReason r) {
  switch (r) {
    case JobReason::Kind: return "kind";
    case JobReason::Hint: return "hint";
    case JobReason::Requested: return "requested";
    case JobReason::LowOverlap: return "low overlap";
    case JobReason::HighOverlap: return "high overlap";
    case JobReason::NoLocalMethod: return "no local method";
    case JobReason::WindingLeaf: return "winding leaf";
    case JobReason::Fallback: return "fallback";
    case JobReason::EmptyBounds: return "solid empty by its bounds";
    case JobReason::UnboundedOperand: return "an operand's solid is unbounded";
  }
  return "?";
}

namespace {

constexpr std::uint32_t kNoJob = ~0u;
// A warped child's refinement makes at most this many times the child's triangles, plus the
// slack (a small child under a strong taper): 64 is an edge stretched eightfold everywhere.
constexpr std::size_t kWarpGrowth = 64;
constexpr std::size_t kWarpSlack = std::size_t(1) << 16;

// The most triangles a warped child's refinement may make: 64 times the child's, plus four times
// what the warped child's area needs at edges of `edge` (a coarse leaf under a scale at a fine
// precision refines that far, legitimately), plus a slack. A warp that stretches without end
// (a twist of a million radians a unit) passes it within its ten passes.
std::size_t warp_cap(const TriangleMesh& child, const std::function<glm::dvec3(const glm::dvec3&)>& warp, double edge) {
  std::vector<glm::dvec3> moved(child.positions.size());
  tbb::parallel_for(std::size_t(0), moved.size(), [&](std::size_t v) { moved[v] = warp(child.positions[v]); });
  double area = 0.0;
  for (const glm::uvec3& t : child.triangles)
    area += 0.5 * glm::length(glm::cross(moved[t[1]] - moved[t[0]], moved[t[2]] - moved[t[0]]));
  const double needed = area / (0.433 * edge * edge);  // equilateral triangles of that edge
  const double cap = double(kWarpGrowth) * double(child.triangles.size()) + double(kWarpSlack) + 4.0 * needed;
  return cap < 1e15 ? std::size_t(cap) : std::size_t(1e15);
}

// The strength F of a node whose field goes through a mesh: a mesh leaf's (its parameters R, F,
// ...) or an ffd's (nodes/warps.hpp: the header's last value).
double leaf_strength(const Graph& g, NodeId n) {
  const auto p = g.params_of(n);
  return g.kind[n] == NodeKind::Ffd ? p[kFfdHeader - 1] : p[1];
}

struct Job {
  NodeId node = kNone;
  JobStrategy strategy = JobStrategy::Global;
  JobReason reason = JobReason::Kind;
  double rho = -1.0;
  std::vector<std::uint32_t> deps;  // jobs whose results this one reads
};

// Walks the tree from the root once: one job per node reached.
class Planner {
 public:
  Planner(const Graph& g, double T, const MeshOptions& o) : g_(g), T_(T), o_(o), job_of_(g.size(), kNoJob) {}

  std::uint32_t need(NodeId n) {
    if (job_of_[n] != kNoJob) return job_of_[n];
    if (root_ == kNone) root_ = n;
    const std::uint32_t j = std::uint32_t(jobs.size());
    job_of_[n] = j;
    jobs.push_back(choose(n));
    std::vector<std::uint32_t> deps;
    const JobStrategy s = jobs[j].strategy;
    if (s == JobStrategy::Empty) {
      // No mesh under it is needed: an ffd under a difference whose first operand is empty was
      // deformed and polygonized (7.4 s) before the difference found its result empty. Below the
      // root, the parent's local strategy may evaluate this node's field, and with it the ffds'.
      if (n != root_) {
        std::vector<std::uint8_t> seen(g_.size(), 0);
        ffds_under(n, seen, deps);
      }
    } else if (s == JobStrategy::Global) {
      std::vector<std::uint8_t> seen(g_.size(), 0);
      ffds_under(n, seen, deps);
    } else if (s == JobStrategy::TrimLocalBlend) {  // the region is a field, not a surface
      const auto c = g_.children_of(n);
      deps = {need(c[0]), need(c[1])};
      std::vector<std::uint8_t> seen(g_.size(), 0);
      ffds_under(c[2], seen, deps);
    } else if (s != JobStrategy::SharedLeaf && s != JobStrategy::Sweep) {
      for (NodeId c : g_.children_of(n)) deps.push_back(need(c));
    }
    jobs[j].deps = std::move(deps);
    return j;
  }
  /// Only what the field needs: the ffd nodes under `root`.
  void need_fields(NodeId root) {
    std::vector<std::uint8_t> seen(g_.size(), 0);
    std::vector<std::uint32_t> unused;
    ffds_under(root, seen, unused);
  }
  std::vector<Job> jobs;

 private:
  // The unprepared ffds under n (n included), outermost first along each path: an ffd's own job
  // takes care of what lies under it.
  void ffds_under(NodeId n, std::vector<std::uint8_t>& seen, std::vector<std::uint32_t>& deps) {
    if (seen[n]) return;
    seen[n] = 1;
    if (params::ffd_unprepared(g_, n)) {
      deps.push_back(need(n));
      return;
    }
    for (NodeId c : g_.children_of(n)) ffds_under(c, seen, deps);
  }

  Job choose(NodeId n) const {
    Job j;
    j.node = n;
    MeshStrategy want = o_.strategy;
    JobReason why = want == MeshStrategy::Auto ? JobReason::Kind : JobReason::Requested;
    if (g_.mesher[n] != MesherHint::Auto) {
      want = g_.mesher[n] == MesherHint::Global ? MeshStrategy::Global : MeshStrategy::Local;
      why = JobReason::Hint;
    }
    const NodeKind kind = g_.kind[n];
    auto set = [&](JobStrategy s, JobReason r) {
      j.strategy = s;
      j.reason = r;
      return j;
    };
    if (kind == NodeKind::Ffd) {
      if (params::ffd_unprepared(g_, n)) return set(JobStrategy::DeformedChild, JobReason::Kind);
      // A deformed mesh that crosses itself is a winding leaf (meshers/ffd.hpp): polygonized.
      if (g_.mesh[n] != kNone && g_.meshes[g_.mesh[n]]->inside_mode() == MeshInside::Winding)
        return set(JobStrategy::Global, JobReason::WindingLeaf);
      return set(JobStrategy::SharedLeaf, JobReason::Kind);
    }
    // After the ffd's own strategies: prepare_fields() needs every unprepared ffd the field
    // reaches, empty or not (need() keeps them as an empty node's deps for the same reason).
    if (solid_empty(g_, n, T_)) return set(JobStrategy::Empty, JobReason::EmptyBounds);
    if (want == MeshStrategy::Global) return set(JobStrategy::Global, why);
    switch (kind_family(kind)) {
      case Family::Mesh:
        // A winding leaf's triangles may be open or cross: its solid's surface is polygonized.
        if (g_.meshes[g_.mesh[n]]->inside_mode() == MeshInside::Winding) return set(JobStrategy::Global, JobReason::WindingLeaf);
        return set(JobStrategy::SharedLeaf, why);
      case Family::Primitive: return set(JobStrategy::Sweep, why);
      case Family::Warp: return set(JobStrategy::WarpedChild, why);
      case Family::Operator: break;
    }
    // The local strategies trim their operands' meshes: an operand whose own solid is unbounded
    // (a blend of two R-function differences, 1.17 T far from everything) has none, though the
    // node itself may be bounded (intersected with a ball).
    const auto operand_nodes = g_.children_of(n).first(kind == NodeKind::LocalBlend ? 2 : g_.child_count[n]);
    for (NodeId c : operand_nodes)  // a local blend's region is a field, not a mesh
      if (!solid_bounds(g_, c, T_).finite() && !solid_empty(g_, c, T_))
        return set(JobStrategy::Global, JobReason::UnboundedOperand);
    const std::size_t operands = flat_operands(n);
    switch (kind) {
      case NodeKind::Blend: {
        j.rho = blend_overlap(g_, n);
        if (operands > kMaxLocalBlendOperands) return set(JobStrategy::Global, JobReason::NoLocalMethod);
        if (want == MeshStrategy::Local) return set(JobStrategy::TrimBlend, why);
        return j.rho > o_.blend_overlap ? set(JobStrategy::Global, JobReason::HighOverlap)
                                         : set(JobStrategy::TrimBlend, JobReason::LowOverlap);
      }
      case NodeKind::Union:
      case NodeKind::Intersection:
      case NodeKind::Difference:
        return operands <= kMaxLocalBooleanOperands ? set(JobStrategy::TrimBoolean, why)
                                                    : set(JobStrategy::Global, JobReason::NoLocalMethod);
      case NodeKind::Crop: return set(JobStrategy::TrimCrop, why);
      case NodeKind::LocalBlend: return set(JobStrategy::TrimLocalBlend, why);
      default: return set(JobStrategy::Global, JobReason::NoLocalMethod);
    }
  }

  // The operands of n counted through nested plain nodes of its kind and mode (no name, no
  // hint): the groups the optimizer makes of a big blend or union (runtime/optimize.hpp) are an
  // evaluation detail, and the blend of 250 curves stays one for its strategy.
  std::size_t flat_operands(NodeId n) const {
    if (g_.kind[n] != NodeKind::Blend && g_.kind[n] != NodeKind::Union) return g_.child_count[n];
    std::size_t count = 0;
    for (NodeId c : g_.children_of(n)) {
      const bool group = g_.kind[c] == g_.kind[n] && g_.boolean[c] == g_.boolean[n] && g_.name[c] == kNone &&
                         g_.mesher[c] == MesherHint::Auto;
      count += group ? flat_operands(c) : 1;
    }
    return count;
  }

  const Graph& g_;
  double T_;
  const MeshOptions& o_;
  std::vector<std::uint32_t> job_of_;
  NodeId root_ = kNone;  // the first node needed: the run's root
};

double since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Why a local result cannot be returned, or empty when it can. The strategy has looked for
// self-intersections where it changed the mesh (LocalStats::self_intersections).
std::string local_defect(const TriangleMesh& m, const LocalStats& local) {
  // Operands lying on each other's surfaces (a subtree used twice in a union) cut each other
  // away entirely; the global polygonizer tells a truly empty result from that.
  if (m.triangles.empty() && local.operand_triangles > 0) return "no triangles from non-empty operands";
  MeshChecks c = check_watertight(m);
  c.self_intersecting_pairs = local.self_intersections;
  return describe_defects(c);
}

// The global polygonizer's result when it is not what every mesher must return: how many
// topological defects, degenerate triangles and intersecting pairs its repair steps left.
std::string global_defect(const TriangleMesh& m, const PolygonizeStats& stats) {
  if (m.triangles.empty()) return "";
  LocalStats local;
  local.self_intersections = stats.crease_intersections;
  return local_defect(m, local);
}

// Runs the jobs on a flow graph; each job reads the results of its deps only.
class Runner {
 public:
  Runner(const Tree& tree, const MeshOptions& o, std::vector<Job> jobs)
      : tree_(tree), o_(o), owned_budget_(o.polygonize.memory_budget),
        budget_(o.polygonize.budget ? *o.polygonize.budget : owned_budget_), graph_(tree.graph_ptr()),
        jobs_(std::move(jobs)), meshes_(jobs_.size()), reports_(jobs_.size()), errors_(jobs_.size()),
        leaves_(jobs_.size()), emptied_(jobs_.size(), 0), consumers_(new std::atomic<std::uint32_t>[jobs_.size()]) {
    for (std::uint32_t j = 0; j < jobs_.size(); ++j) consumers_[j] = 0;
    held_.assign(jobs_.size(), 0);
    for (const Job& job : jobs_)
      for (std::uint32_t d : job.deps) ++consumers_[d];
    if (o_.cache && !o_.polygonize.brick_filter) compute_keys();
    // The mesh leaves are held for the whole run.
    for (const auto& leaf : graph_->meshes)
      if (leaf)
        budget_.take(double(leaf->bytes()), "mesh leaf " + leaf->name() + " (" + std::to_string(leaf->triangles().size()) +
                                                " triangles)");
  }

  void run_all();
  std::shared_ptr<const TriangleMesh> mesh(std::uint32_t j) const { return meshes_[j]; }
  std::vector<NodeReport> reports() const;
  /// The tree's graph with every ffd's mesh attached in plan order (the working graph attaches
  /// them as the jobs finish, in whatever order that is).
  std::shared_ptr<const Graph> graph() const {
    std::shared_ptr<const Graph> g = tree_.graph_ptr();
    for (std::uint32_t j = 0; j < jobs_.size(); ++j)
      if (leaves_[j]) g = attach_ffd_mesh(*g, jobs_[j].node, leaves_[j]);
      else if (emptied_[j]) g = attach_empty_ffd(*g, jobs_[j].node);
    return g;
  }

 private:
  void run(std::uint32_t j);
  void compute_keys();
  std::uint64_t key(std::uint32_t j, const SubtreeHashes& h, std::uint64_t options);
  bool reuse(std::uint32_t j, NodeReport& r);
  std::shared_ptr<const TriangleMesh> execute(const Job& job, NodeReport& r);
  std::shared_ptr<const TriangleMesh> global(NodeId n, const std::shared_ptr<const Graph>& g, NodeReport& r, bool report_progress);
  std::shared_ptr<const TriangleMesh> trim(const Job& job, const std::shared_ptr<const Graph>& g, NodeReport& r);
  // `mesh` (a sweep's or a warp's, named by `what`) when it crosses nothing, else the node's
  // surface polygonized, reported as a fallback.
  std::shared_ptr<const TriangleMesh> unless_crossing(std::shared_ptr<const TriangleMesh> mesh, const char* what, NodeId n,
                                                      const std::shared_ptr<const Graph>& g, NodeReport& r);
  std::shared_ptr<const Graph> current_graph() {
    std::lock_guard lock(graph_mutex_);
    return graph_;
  }
  const TriangleMesh& input(const Job& job, std::size_t i) const { return *meshes_[job.deps[i]]; }
  bool cancelled() const { return o_.cancel && o_.cancel->load(std::memory_order_relaxed); }
  void progress(double within_job);

  const Tree& tree_;
  const MeshOptions& o_;
  MemoryBudget owned_budget_;  // when the options bring none
  MemoryBudget& budget_;       // every stage of the run takes from it
  std::mutex graph_mutex_, progress_mutex_;
  std::shared_ptr<const Graph> graph_;
  std::vector<Job> jobs_;
  std::vector<std::shared_ptr<const TriangleMesh>> meshes_;
  std::vector<NodeReport> reports_;
  std::vector<std::exception_ptr> errors_;
  std::vector<std::shared_ptr<const MeshLeaf>> leaves_;  // ffd jobs: their deformed meshes
  std::vector<std::uint8_t> emptied_;                     // ffd jobs whose child was empty
  // With a cache: each job's key, and whether it may be cached (0: not computed, 1: yes, 2: no).
  std::vector<std::uint64_t> keys_;
  std::vector<std::uint8_t> cacheable_;
  std::atomic<std::size_t> done_{0};
  // Jobs still to read each job's mesh: at zero the mesh is dropped (the root's never is).
  std::unique_ptr<std::atomic<std::uint32_t>[]> consumers_;
  std::vector<std::size_t> held_;  // bytes taken from the budget for each job's mesh
  double reported_ = 0.0;
};

void Runner::progress(double within_job) {
  if (!o_.progress) return;
  std::lock_guard lock(progress_mutex_);
  const double f = std::min(1.0, (double(done_.load()) + within_job) / double(std::max<std::size_t>(1, jobs_.size())));
  if (f <= reported_ && f < 1.0) return;
  reported_ = f;
  o_.progress(f);
}

void Runner::run(std::uint32_t j) {
  const Job& job = jobs_[j];
  for (std::uint32_t d : job.deps)
    if (errors_[d]) {
      errors_[j] = errors_[d];
      return;
    }
  if (cancelled()) {
    errors_[j] = std::make_exception_ptr(MeshCancelled("meshing was cancelled"));
    return;
  }
  const auto t0 = std::chrono::steady_clock::now();
  NodeReport& r = reports_[j];
  r.node = job.node;
  r.strategy = job.strategy;
  r.reason = job.reason;
  r.rho = job.rho;
  try {
    if (!reuse(j, r)) {
      meshes_[j] = execute(job, r);
      // A winding leaf found to be its own surface is shared, as a leaf's mesh is: not copied.
      if (!cacheable_.empty() && cacheable_[j] == 1 && r.strategy != JobStrategy::SharedLeaf)
        o_.cache->insert(keys_[j], CachedJob{meshes_[j], r});
    }
    r.triangles = meshes_[j]->triangles.size();
    // A job's mesh is held until the jobs that read it are done (the root's until the run
    // ends); a shared leaf's is the leaf's own, counted above.
    if (r.strategy != JobStrategy::SharedLeaf) {
      const std::size_t bytes = 24 * meshes_[j]->positions.size() + 12 * r.triangles;
      budget_.take(double(bytes), "the mesh of node " + graph_->label(job.node) + " (" + std::to_string(r.triangles) + " triangles)");
      held_[j] = bytes;
    }
  } catch (...) {
    errors_[j] = std::current_exception();
  }
  for (std::uint32_t d : job.deps)
    if (consumers_[d].fetch_sub(1) == 1) {  // the last reader: no other job touches meshes_[d] now
      budget_.give_back(held_[d]);
      held_[d] = 0;
      meshes_[d].reset();
    }
  r.seconds = since(t0);
  ++done_;
  try {
    progress(0.0);
  } catch (...) {  // a callback that throws ends the run as this job's error, in plan order
    if (!errors_[j]) errors_[j] = std::current_exception();
  }
}

// A job's key: its subtree's hash (as a root of its own), what it does and why, the keys of the
// jobs it reads, and the options. Jobs that read an ffd's field (attached as the run goes) and
// shared leaves (nothing to save) are not cached, nor is anything that reads them.
std::uint64_t Runner::key(std::uint32_t j, const SubtreeHashes& h, std::uint64_t options) {
  if (cacheable_[j]) return keys_[j];
  const Job& job = jobs_[j];
  bool ok = job.strategy != JobStrategy::SharedLeaf && job.strategy != JobStrategy::DeformedChild &&
            !needs_ffd_preparation(*graph_, job.node);
  std::uint64_t k = hash_mix(hash_mix(hash_mix(options, h.alone[job.node]), std::uint64_t(job.strategy)),
                             std::uint64_t(job.reason));
  k = hash_mix(k, std::bit_cast<std::uint64_t>(job.rho));
  for (std::uint32_t d : job.deps) {
    k = hash_mix(k, key(d, h, options));
    ok = ok && (cacheable_[d] == 1 || jobs_[d].strategy == JobStrategy::SharedLeaf);
  }
  keys_[j] = k;
  cacheable_[j] = ok ? 1 : 2;
  return k;
}

void Runner::compute_keys() {
  const SubtreeHashes h = subtree_hashes(*graph_, tree_.threshold());
  const std::uint64_t options = mesh_options_hash(o_);
  keys_.assign(jobs_.size(), 0);
  cacheable_.assign(jobs_.size(), 0);
  for (std::uint32_t j = 0; j < jobs_.size(); ++j) key(j, h, options);
}

// Takes job j's result from the cache when it is there.
bool Runner::reuse(std::uint32_t j, NodeReport& r) {
  if (cacheable_.empty() || cacheable_[j] != 1) return false;
  std::optional<CachedJob> hit = o_.cache->find(keys_[j]);
  if (!hit) return false;
  meshes_[j] = std::move(hit->mesh);
  r = std::move(hit->report);
  r.node = jobs_[j].node;
  r.reused = true;
  return true;
}

void Runner::run_all() {
  tbb::flow::graph fg;
  using Node = tbb::flow::continue_node<tbb::flow::continue_msg>;
  std::vector<std::unique_ptr<Node>> nodes;
  nodes.reserve(jobs_.size());
  for (std::uint32_t j = 0; j < jobs_.size(); ++j)
    nodes.push_back(std::make_unique<Node>(fg, [this, j](const tbb::flow::continue_msg&) { run(j); }));
  for (std::uint32_t j = 0; j < jobs_.size(); ++j)
    for (std::uint32_t d : jobs_[j].deps) tbb::flow::make_edge(*nodes[d], *nodes[j]);
  for (std::uint32_t j = 0; j < jobs_.size(); ++j)
    if (jobs_[j].deps.empty()) nodes[j]->try_put(tbb::flow::continue_msg());
  fg.wait_for_all();
  // The first error by job order (the order of the plan, not of completion).
  for (const auto& e : errors_)
    if (e) std::rethrow_exception(e);
}

std::vector<NodeReport> Runner::reports() const {
  std::vector<NodeReport> out = reports_;
  std::sort(out.begin(), out.end(), [](const NodeReport& a, const NodeReport& b) { return a.node < b.node; });
  return out;
}

std::shared_ptr<const TriangleMesh> Runner::execute(const Job& job, NodeReport& r) {
  const std::shared_ptr<const Graph> g = current_graph();
  const NodeId n = job.node;
  const double T = tree_.threshold(), h = o_.precision;
  switch (job.strategy) {
    case JobStrategy::Empty: return std::make_shared<const TriangleMesh>();
    case JobStrategy::SharedLeaf:
      // A leaf of negative strength carves what it is blended with; alone its field is nowhere
      // above T (> 0), so its solid, and its mesh, is empty; so is an empty ffd's (strength 0).
      if (leaf_strength(*g, n) <= 0) return std::make_shared<const TriangleMesh>();
      return g->meshes[g->mesh[n]]->manifold_surface();
    case JobStrategy::Global:
      // A winding leaf whose triangles are its solid's surface all the same keeps them.
      if (job.reason == JobReason::WindingLeaf && leaf_strength(*g, n) > 0 &&
          winding_leaf_is_its_surface(*g->meshes[g->mesh[n]])) {
        r.strategy = JobStrategy::SharedLeaf;
        return g->meshes[g->mesh[n]]->manifold_surface();
      }
      return global(n, g, r, jobs_.size() == 1);
    case JobStrategy::Sweep: {
      // Held while it is built: the mesh's arrays (about 24 bytes a triangle) and their growth.
      const double triangles = sweep_triangle_estimate(*g, n, T, h);
      const MemoryReservation building(budget_, 48.0 * triangles,
                                       "the sweep mesh of node " + g->label(n) + " (" + format_estimate(triangles) +
                                           " triangles)");
      return unless_crossing(std::make_shared<const TriangleMesh>(sweep_mesh(*g, n, T, h)), "the sweep mesh", n, g, r);
    }
    case JobStrategy::WarpedChild: {
      const TapeEvaluator child_field(std::make_shared<const Tape>(compile_tape(g, g->children_of(n)[0], T)));
      WarpRemeshStats ws;
      const TriangleMesh& child = input(job, 0);
      const auto warp = forward_map(*g, n);
      // Refined no further than the budget holds: a twist of rate 1.7e308 stretches every edge
      // past any count the area predicts (an infinite area caps nothing) and filled memory. The
      // budget's limit, not its room at the moment, so that the result does not depend on what
      // other jobs hold then.
      const std::size_t by_area = warp_cap(child, warp, 1.5 * h);
      const std::size_t by_budget = std::size_t(double(budget_.limit()) / kWarpedBytesPerTriangle);
      const std::size_t cap = std::min(by_area, by_budget);
      auto mesh = std::make_shared<const TriangleMesh>(warp_mesh(child, warp, &child_field, T, 1.5 * h, &ws, nullptr, {}, cap));
      r.edges_split = ws.edges_split;
      if (ws.stopped) {
        // The warp stretches the child's edges past any refinement (a twist of a million
        // radians a unit): the node's own surface is polygonized, as the grid bounds it.
        mesh.reset();
        r.reason = JobReason::Fallback;
        r.fallback_cause = "the warped mesh would need more than " + std::to_string(cap) + " triangles" +
                           (by_budget < by_area ? " (what the memory budget holds)" : "");
        r.strategy = JobStrategy::Global;
        return global(n, g, r, false);
      }
      // An affine map that split nothing moves the child's triangles as a whole: they cross as
      // little as the child's did. A bent map's straight triangles, and midpoints projected onto
      // the child's surface where it comes near itself (one may land on the other sheet), can
      // cross: then the node's surface is polygonized, as for a sweep that overlaps itself.
      if (g->kind[n] == NodeKind::Affine && ws.edges_split == 0) return mesh;
      return unless_crossing(std::move(mesh), "the warped mesh", n, g, r);
    }
    case JobStrategy::DeformedChild: {
      if (input(job, 0).triangles.empty()) {  // nothing to deform: the node's field is 0
        std::lock_guard lock(graph_mutex_);
        graph_ = attach_empty_ffd(*graph_, n);
        emptied_[std::size_t(&job - jobs_.data())] = 1;
        return std::make_shared<const TriangleMesh>();
      }
      std::size_t crossing = 0;
      auto leaf = deform_child_mesh(g, n, input(job, 0), 1.5 * h, T, &crossing, &budget_);
      std::shared_ptr<const Graph> attached;
      {
        std::lock_guard lock(graph_mutex_);
        graph_ = attach_ffd_mesh(*graph_, n, leaf);
        attached = graph_;
        leaves_[std::size_t(&job - jobs_.data())] = leaf;
      }
      if (crossing == 0) return leaf->manifold_surface();
      // The deformed mesh defines the node's field all the same; its surface is polygonized.
      r.reason = JobReason::Fallback;
      r.fallback_cause = "the deformed mesh overlaps itself (" + std::to_string(crossing) + " intersecting triangle pairs)";
      r.strategy = JobStrategy::Global;
      return global(n, attached, r, false);
    }
    default: return trim(job, g, r);
  }
}

std::shared_ptr<const TriangleMesh> Runner::global(NodeId n, const std::shared_ptr<const Graph>& g, NodeReport& r,
                                                   bool report_progress) {
  PolygonizeOptions p = o_.polygonize;
  p.budget = &budget_;
  p.precision = o_.precision;
  p.cancel = o_.cancel;
  p.brick_filter = {};
  p.progress = {};
  p.pieces = o_.cache ? &o_.cache->pieces() : nullptr;
  if (report_progress && o_.progress) p.progress = [this](double f) { progress(std::min(f, 0.999)); };
  r.polygonized = true;
  // A grid that under-resolves the surface (features thinner than a cell) can leave folds the
  // repair steps cannot undo; a finer grid resolves them. Each try is as deterministic as the first.
  for (int attempt = 0;; ++attempt) {
    auto mesh = std::make_shared<const TriangleMesh>(polygonize(g, n, tree_.threshold(), p, &r.polygonize));
    const std::string why = global_defect(*mesh, r.polygonize);
    if (why.empty() || attempt == kRefinements) return mesh;
    r.refinements.push_back("precision " + std::to_string(p.precision) + ": " + why);
    p.precision *= kRefineFactor;
  }
}

std::shared_ptr<const TriangleMesh> Runner::unless_crossing(std::shared_ptr<const TriangleMesh> mesh, const char* what,
                                                            NodeId n, const std::shared_ptr<const Graph>& g, NodeReport& r) {
  const std::size_t pairs = find_self_intersections(*mesh, 0).pairs;
  if (pairs == 0) return mesh;
  r.reason = JobReason::Fallback;
  r.fallback_cause = std::string(what) + " overlaps itself (" + std::to_string(pairs) + " intersecting triangle pairs)";
  r.strategy = JobStrategy::Global;
  return global(n, g, r, false);
}

std::shared_ptr<const TriangleMesh> Runner::trim(const Job& job, const std::shared_ptr<const Graph>& g, NodeReport& r) {
  std::vector<std::shared_ptr<const TriangleMesh>> children;
  for (std::uint32_t d : job.deps) children.push_back(meshes_[d]);
  LocalInput in;
  in.graph = g;
  in.node = job.node;
  in.threshold = tree_.threshold();
  in.precision = o_.precision;
  in.child_meshes = children;
  in.polygonize = o_.polygonize;
  in.polygonize.budget = &budget_;
  in.polygonize.cancel = o_.cancel;
  in.remesh_seams = o_.remesh_seams;
  std::string cause;
  try {
    TriangleMesh m = job.strategy == JobStrategy::TrimBlend     ? trim_blend(in, &r.local)
                     : job.strategy == JobStrategy::TrimBoolean ? trim_boolean(in, &r.local)
                     : job.strategy == JobStrategy::TrimCrop    ? trim_crop(in, &r.local)
                                                                : trim_local_blend(in, &r.local);
    r.polygonized = r.local.patched;
    r.polygonize = r.local.patch;
    cause = local_defect(m, r.local);
    if (cause.empty()) return std::make_shared<const TriangleMesh>(std::move(m));
    if (!m.triangles.empty()) cause = "the result had " + cause;
  } catch (const MeshCancelled&) {
    throw;
  } catch (const MemoryBudgetError&) {
    throw;  // the global strategy would need more, not less
  } catch (const std::exception& e) {
    cause = e.what();
  } catch (...) {
    cause = "an unknown exception";
  }
  r.reason = JobReason::Fallback;
  r.fallback_cause = cause;
  r.strategy = JobStrategy::Global;
  return global(job.node, g, r, false);
}

void check_options(const MeshOptions& o) {
  if (!(o.precision > 0.0) || !std::isfinite(o.precision)) throw PolygonizeError("precision must be a finite number > 0");
  if (!(o.blend_overlap >= 0.0 && o.blend_overlap <= 1.0)) throw PolygonizeError("blend_overlap must be in [0, 1]");
}

}  // namespace

MeshResult mesh_tree(const Tree& tree, const MeshOptions& options) {
  check_options(options);
  Planner plan(tree.graph(), tree.threshold(), options);
  const std::uint32_t root = plan.need(tree.root());
  Runner runner(tree, options, std::move(plan.jobs));
  runner.run_all();
  MeshResult result;
  result.mesh = runner.mesh(root);
  result.nodes = runner.reports();
  result.tree.emplace(runner.graph(), tree.root(), tree.threshold(), tree.mesher_settings());
  if (options.progress) options.progress(1.0);
  return result;
}

Tree prepare_fields(const Tree& tree, const MeshOptions& options) {
  if (!needs_ffd_preparation(tree.graph(), tree.root())) return tree;
  check_options(options);
  Planner plan(tree.graph(), tree.threshold(), options);
  plan.need_fields(tree.root());
  Runner runner(tree, options, std::move(plan.jobs));
  runner.run_all();
  return Tree(runner.graph(), tree.root(), tree.threshold(), tree.mesher_settings());
}

}  // namespace ht
