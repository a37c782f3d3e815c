// hybridtree: the command-line face of the library.
//   hybridtree info SCENE                  what the scene holds and what it costs
//   hybridtree eval SCENE [--points FILE]  field values (and gradients) at points (text or .npy)
//   hybridtree mesh SCENE -o OUT           a closed triangle mesh of the scene's surface
//   hybridtree generate snake [--count N]  a procedural scene (JSON on stdout)
// Exit codes: 0 success, 2 bad input (scene, points, arguments), 1 anything else.
#include "meshers/disk_cache.hpp"
#include "meshers/ffd.hpp"
#include "meshers/mesh_checks.hpp"
#include "meshers/mesh_io.hpp"
#include "meshers/mesh_plan.hpp"
#include "meshers/mesh_run.hpp"
#include "meshers/node_cache.hpp"
#include "meshers/polygonize.hpp"
#include "nodes/mesh_leaf.hpp"
#include "runtime/scene.hpp"
#include "runtime/scene_write.hpp"
#include "runtime/tape.hpp"
#include "runtime/tape_eval.hpp"
#include "runtime/tree_eval.hpp"
#include "tools/cli_io.hpp"
#include "tools/npy.hpp"
#include "tools/optimize_cli.hpp"
#include "tools/render_cli.hpp"
#include "tools/scenes.hpp"

#include <CLI/CLI.hpp>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <csignal>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <new>
#include <string>
#include <vector>

namespace {

// CLI11's PositiveNumber lets "nan" and "inf" through (neither is <= 0).
const CLI::Validator kPositiveFinite(
    [](std::string& text) -> std::string {
      double v = 0.0;
      if (!CLI::detail::lexical_cast(text, v) || !std::isfinite(v) || !(v > 0.0))
        return "must be a finite number > 0, not " + text;
      return {};
    },
    "POSITIVE");

using ht::cli::InputError;

// Ffd nodes need their deformed meshes before their field exists.
ht::Tree ready(const ht::Tree& tree, double precision, const std::string& scene) {
  try {
    return ht::prepare_ffd(tree, precision);
  } catch (const ht::PolygonizeError& e) {
    throw InputError(scene + ": " + e.what());
  } catch (const ht::MemoryBudgetError& e) {
    throw InputError(scene + ": " + e.what());
  }
}

int depth_of(const ht::Graph& g, ht::NodeId n) {
  int d = 0;
  for (ht::NodeId c : g.children_of(n)) d = std::max(d, depth_of(g, c));
  return d + 1;
}

void collect(const ht::Graph& g, ht::NodeId n, std::vector<std::uint8_t>& seen) {
  if (seen[n]) return;
  seen[n] = 1;
  for (ht::NodeId c : g.children_of(n)) collect(g, c, seen);
}

std::string fmt_vec(const glm::dvec3& v) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "[%.6g, %.6g, %.6g]", v.x, v.y, v.z);
  return buf;
}


// What a mesh leaf's report counts as defects, as one line ("" for none). A closed leaf has
// none left (it would have been refused), except what repair closed or duplicate positions.
std::string defects_text(const ht::MeshReport& r) {
  std::string s;
  auto add = [&](std::size_t n, const std::string& what) {
    if (n == 0) return;
    s += (s.empty() ? "" : ", ") + std::to_string(n) + " " + what;
  };
  if (r.boundary_edges > 0)
    add(r.boundary_edges, "boundary edges in " + std::to_string(r.holes) + (r.holes == 1 ? " hole" : " holes"));
  add(r.nonmanifold_edges, "non-manifold edges");
  add(r.duplicate_vertices, "duplicate vertices");
  add(r.intersecting_shells, "crossing shell pairs");
  add(r.pinched_vertices, "vertices where shells touch (each shell has its own copy in what is written)");
  if (r.inside == ht::MeshInside::Winding && r.components > 1) add(r.components, "components");
  return s;
}

int cmd_info(const std::string& scene, bool optimize) {
  const auto t0 = std::chrono::steady_clock::now();
  const ht::Tree tree = ht::load_scene(scene);
  const double load_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::string optimizer;
  if (optimize) {
    ht::OptimizeStats stats;
    ht::optimize(tree, {}, &stats);
    optimizer = ht::cli::optimizer_report(stats);
  }
  const ht::Graph& g = tree.graph();
  std::vector<std::uint8_t> seen(g.size(), 0);
  collect(g, tree.root(), seen);
  std::map<std::string, int> counts;
  std::size_t nodes = 0;
  for (ht::NodeId n = 0; n < g.size(); ++n)
    if (seen[n]) {
      ++counts[std::string(ht::kind_name(g.kind[n]))];
      ++nodes;
    }
  std::printf("scene          %s\n", scene.c_str());
  std::printf("threshold      %g\n", tree.threshold());
  std::printf("nodes          %zu (depth %d)\n", nodes, depth_of(g, tree.root()));
  for (const auto& [kind, count] : counts) std::printf("  %-13s%d\n", kind.c_str(), count);
  const ht::Aabb& box = g.support(tree.root(), false);
  if (box.empty())
    std::printf("support        empty (the field is 0 everywhere)\n");
  else if (!box.finite())
    std::printf("support        unbounded (an R-function difference is non-zero everywhere)\n");
  else
    std::printf("support        %s .. %s\n", fmt_vec(box.lo).c_str(), fmt_vec(box.hi).c_str());
  std::size_t mesh_bytes = 0;
  for (const auto& m : g.meshes) {
    const ht::MeshReport& r = m->report();
    mesh_bytes += m->bytes();
    std::printf("mesh           %s: %zu triangles, %zu vertices, %zu shell%s, inside %s%s%s\n", m->name().c_str(),
                r.triangles, r.vertices, r.components, r.components == 1 ? "" : "s",
                r.inside == ht::MeshInside::Winding ? "by winding number" : "closed",
                r.inverted ? ", faces pointed inward (flipped: same solid)" : "",
                r.reoriented_faces ? (", " + std::to_string(r.reoriented_faces) + " faces reoriented").c_str() : "");
    if (r.holes_closed)
      std::printf("               repaired: %zu holes closed with %zu triangles\n", r.holes_closed, r.triangles_added);
    if (const std::string d = defects_text(r); !d.empty()) std::printf("               defects: %s\n", d.c_str());
  }
  std::printf("tree bytes     %zu (the model: kinds, parameters, children, names)\n", g.bytes());
  std::printf("derived bytes  %zu (support boxes, curve polylines)\n", g.derived_bytes());
  if (!g.meshes.empty()) std::printf("mesh bytes     %zu (shared, loaded once per file)\n", mesh_bytes);
  try {
    const auto t1 = std::chrono::steady_clock::now();
    const ht::Tape tape = ht::compile_tape(tree.graph_ptr(), tree.root(), tree.threshold());
    const double compile_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
    std::printf("tape           %zu instructions of %zu bytes, %u registers, %zu bytes in all (compiled in %.3f s)\n",
                tape.size(), sizeof(ht::Instruction), tape.registers, tape.bytes(), compile_s);
  } catch (const ht::CompileError& e) {
    std::printf("tape           not compiled: %s\n", e.what());
  }
  std::fputs(optimizer.c_str(), stdout);
  std::printf("load time      %.3f s\n", load_s);
  return 0;
}

struct EvalArgs {
  std::string scene, points, output, engine = "tape";  // points, output: empty or "-" = stdin, stdout
  bool gradient = false;
  bool optimize = true;
  int threads = 0;
};

// One row per point: the value, then the gradient if asked. Every engine is parallel over
// points (TBB) and computes each point alone, so the table is the same at any thread count.
std::vector<double> evaluate(const ht::Tree& tree, const EvalArgs& a, std::span<const glm::dvec3> points) {
  std::vector<double> values(points.size());
  std::vector<glm::dvec3> grads;
  if (a.gradient) grads.resize(points.size());
  if (a.engine == "tape") {
    if (a.gradient)
      tree.evaluator().gradient(points, values, grads);
    else
      tree.field(points, values);
  } else {
    tree.reference(points, values);
    if (a.gradient) tree.reference_gradient(points, grads);
  }
  if (!a.gradient) return values;
  std::vector<double> table(4 * points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    table[4 * i] = values[i];
    for (int j = 0; j < 3; ++j) table[4 * i + 1 + std::size_t(j)] = grads[i][j];
  }
  return table;
}

int cmd_eval(const EvalArgs& a) {
  const ht::Tree loaded = ht::cli::load_tree(a.scene, a.optimize);
  const ht::Tree tree = ready(loaded, ht::default_precision(loaded, 0.0), a.scene);
  if (a.engine == "tape") {
    try {
      tree.evaluator();
    } catch (const ht::CompileError& e) {
      throw InputError(a.scene + ": " + e.what());
    }
  }
  const ht::npy::Points in = ht::cli::read_points(a.points);
  const std::vector<double> table = evaluate(tree, a, in.points);
  const std::size_t columns = a.gradient ? 4 : 1;
  if (ht::npy::has_npy_extension(a.output)) {
    ht::cli::write_file_atomically(a.output, ht::npy::encode(in.dtype, table, columns), "output file");
    return 0;
  }
  const std::string text = ht::cli::format_rows(table, columns);
  if (!a.output.empty() && a.output != "-") {
    ht::cli::write_file_atomically(a.output, text, "output file");
    return 0;
  }
  std::fwrite(text.data(), 1, text.size(), stdout);
  return std::fflush(stdout) == 0 ? 0 : 1;
}

struct MeshArgs {
  std::string scene, out, strategy, stats_json;  // strategy: empty = the scene's
  std::string sharp = "on", quality = "on";
  double precision = 0.0, memory_gib = 4.0;
  std::string cache;             // the on-disk node cache's folder; empty: none
  double cache_mib = 1024.0;     // its bound
  int threads = 0;
  bool optimize = true;
};

// Bytes of the in-memory level in front of --cache: jobs of one run with identical subtrees.
constexpr std::size_t kCliMemoryCache = std::size_t(256) << 20;

// Ctrl-C asks the mesh plan to stop between jobs and bricks; it then throws MeshCancelled and
// no file is written. (A lock-free atomic store is safe in a signal handler.)
std::atomic<bool> interrupted{false};
extern "C" void on_interrupt(int) { interrupted.store(true); }

// A one-line progress bar on stderr, only when stderr is a terminal.
std::function<void(double)> progress_bar() {
  if (!::isatty(STDERR_FILENO)) return {};
  return [](double f) {
    const int width = 40, filled = static_cast<int>(f * width + 0.5);
    std::fprintf(stderr, "\r[%s%s] %3d%%", std::string(std::size_t(filled), '#').c_str(),
                 std::string(std::size_t(width - filled), ' ').c_str(), static_cast<int>(f * 100 + 0.5));
    if (f >= 1.0) std::fprintf(stderr, "\n");
    std::fflush(stderr);
  };
}

// Both outputs are checked before meshing: a stats file that cannot be written must not leave
// the mesh written alone, nor a device be renamed over (meshers/mesh_io.hpp output_target).
void check_output(const std::string& file) {
  try {
    const std::filesystem::path target = ht::output_target(file);
    const std::filesystem::path dir = target.parent_path().empty() ? std::filesystem::path(".") : target.parent_path();
    if (!std::filesystem::is_directory(dir)) throw InputError(file + ": folder " + dir.string() + " does not exist");
    if (std::filesystem::is_directory(target)) throw InputError(file + ": is a folder, not a file");
  } catch (const ht::MeshWriteError& e) {
    throw InputError(e.what());
  }
}

int cmd_mesh(const MeshArgs& a) {
  if (!ht::supported_mesh_extension(a.out))
    throw InputError(a.out + ": unsupported output extension (use .ply, .obj, .off or .stl)");
  check_output(a.out);
  if (!a.stats_json.empty()) check_output(a.stats_json);
  using clock = std::chrono::steady_clock;
  const auto t0 = clock::now();
  const ht::Tree tree = ht::cli::load_tree(a.scene, a.optimize);
  const double load_s = std::chrono::duration<double>(clock::now() - t0).count();
  ht::MeshRunOptions options;
  options.precision = a.precision;
  options.strategy = a.strategy;
  options.memory_gib = a.memory_gib;
  options.sharp_features = a.sharp == "on";
  options.quality = a.quality == "on";
  options.full_checks = !a.stats_json.empty();  // the summary line needs the topology alone
  options.progress = progress_bar();
  options.cancel = &interrupted;
  std::unique_ptr<ht::DiskCache> disk;
  std::unique_ptr<ht::NodeCache> cache;
  if (!a.cache.empty()) {
    try {
      disk = std::make_unique<ht::DiskCache>(a.cache, static_cast<std::uint64_t>(a.cache_mib * double(1u << 20)));
    } catch (const ht::DiskCacheError& e) {
      throw InputError(e.what());
    }
    cache = std::make_unique<ht::NodeCache>(kCliMemoryCache, disk.get());
    options.cache = cache.get();
  }
  std::signal(SIGINT, on_interrupt);
  ht::MeshRun run;
  try {
    run = ht::run_mesh(tree, options);
  } catch (const ht::MeshCancelled&) {
    throw std::runtime_error(a.scene + ": interrupted; nothing was written");
  } catch (const ht::CompileError& e) {
    throw InputError(a.scene + ": " + e.what());
  } catch (const ht::PolygonizeError& e) {
    throw InputError(a.scene + ": " + e.what());
  } catch (const ht::MemoryBudgetError& e) {
    throw InputError(a.scene + ": " + e.what() + "; raise --memory-budget (GiB) or coarsen --precision");
  } catch (const std::bad_alloc&) {
    // A stage the budget does not foresee ran the machine out of memory; nothing was written.
    throw std::runtime_error(a.scene + ": out of memory while meshing, in a stage the memory budget does not bound; " +
                             "try a coarser --precision; nothing was written");
  }
  const ht::TriangleMesh& mesh = *run.result.mesh;
  const ht::MeshChecks& checks = run.checks;
  if (mesh.triangles.empty()) std::fprintf(stderr, "hybridtree: warning: %s: the surface is empty; writing an empty mesh\n", a.scene.c_str());
  const auto t3 = clock::now();
  ht::write_mesh(mesh, a.out);
  const double write_s = std::chrono::duration<double>(clock::now() - t3).count();
  std::printf("%s: %zu triangles, %zu vertices, precision %g, %.3f s meshing (%s at the root), %s, genus %ld\n",
              a.out.c_str(), checks.triangles, checks.vertices, run.options.precision, run.mesh_seconds,
              ht::root_strategy(run, tree.root()).c_str(), checks.watertight() ? "closed manifold" : "NOT watertight",
              checks.genus);
  // Every mesher aims at none of these; where the full checks (--stats-json) find one, say so
  // rather than let the summary line's "closed manifold" stand for a clean mesh.
  if (checks.self_intersecting_pairs > 0 || checks.folded_triangles > 0)
    std::fprintf(stderr,
                 "hybridtree: warning: %s: the mesh has %zu self-intersecting triangle pairs and %zu folded triangles "
                 "(a finer --precision may resolve the features that made them)\n",
                 a.out.c_str(), checks.self_intersecting_pairs, checks.folded_triangles);
  // Closed but not watertight: triangles of no area against the mesh's size, as a solid a
  // hundred billion times longer than thick makes (an affine scale of [1e11, 1, 1]), or as a
  // mesh leaf's own file may hold (the default strategy keeps its triangles).
  if (checks.degenerate_triangles > 0)
    std::fprintf(stderr,
                 "hybridtree: warning: %s: the mesh has %zu degenerate triangle%s (of no area against the mesh's size: "
                 "an input mesh's own, kept as they are, or made where a solid is far thinner than it is long or "
                 "the precision too coarse for its thinnest part)\n",
                 a.out.c_str(), checks.degenerate_triangles, checks.degenerate_triangles == 1 ? "" : "s");
  for (const ht::NodeReport& e : run.result.nodes)
    for (const std::string& why : e.refinements)
      std::fprintf(stderr, "hybridtree: note: node %u: the grid at %s; polygonized again with cells %g%% smaller\n", e.node,
                   why.c_str(), 100.0 * (1.0 - ht::kRefineFactor));
  if (!a.stats_json.empty())
    ht::cli::write_file_atomically(a.stats_json, ht::mesh_stats_json(tree, run, a.scene, load_s, a.out, write_s),
                                   "stats file");
  return 0;
}

// An option of two numbers into a and b.
template <class A, class B>
void add_pair(CLI::App* app, const std::string& name, A& a, B& b, const std::string& what, const std::string& type) {
  app->add_option(name, [&a, &b](const CLI::results_t& r) { return CLI::detail::lexical_cast(r.at(0), a) && CLI::detail::lexical_cast(r.at(1), b); }, what)
      ->expected(2)
      ->type_name(type);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"HybridTree: a hybrid implicit/mesh modeling kernel (Allegre et al. 2004)"};
  app.require_subcommand(1);
  std::string scene;

  auto* info = app.add_subcommand("info", "Print what a scene holds: nodes, depth, bounds, meshes, bytes, load time");
  info->add_option("scene", scene, "Scene file (JSON, SCENE_FORMAT v1)")->required();
  bool info_no_optimize = false;
  info->add_flag("--no-optimize", info_no_optimize, "Do not run the optimizer (no optimizer lines)");

  ht::cli::OptimizeArgs optimize_args;
  auto* optimize_cmd = app.add_subcommand("optimize", "Rewrite a scene into the tree that evaluates and meshes fast (same field)");
  optimize_cmd->add_option("scene", optimize_args.scene, "Scene file (JSON, SCENE_FORMAT v1)")->required();
  optimize_cmd->add_option("-o,--output", optimize_args.out, "The rewritten scene (JSON, SCENE_FORMAT v1; - for stdout)")
      ->required();

  EvalArgs eval_args;
  auto* eval = app.add_subcommand("eval", "Field values at points (x y z per line, or .npy) from --points or stdin");
  eval->add_option("scene", eval_args.scene, "Scene file (JSON, SCENE_FORMAT v1)")->required();
  eval->add_option("--points", eval_args.points,
                   "Points file: x y z per line, or FILE.npy of shape (N, 3), float32 or float64 (default: stdin)");
  eval->add_option("-o,--output", eval_args.output,
                   "Output file: FILE.npy (shape (N,), or (N, 4) with --gradient; the points' dtype, float32 for "
                   "text points), else text (default: stdout)");
  eval->add_flag("--gradient", eval_args.gradient, "Also print the gradient (three more columns)");
  eval->add_option("--engine", eval_args.engine, "Evaluator: tape (compiled, float, SIMD; default) or tree (reference, double)")
      ->check(CLI::IsMember({"tape", "tree"}));
  eval->add_option("--threads", eval_args.threads, "Worker threads (default: all cores)")->check(CLI::Range(1, 1024));
  bool eval_no_optimize = false;
  eval->add_flag("--no-optimize", eval_no_optimize, "Evaluate the tree as written, not the optimized one");

  MeshArgs mesh_args;
  auto* mesh_cmd = app.add_subcommand("mesh", "Mesh the scene's surface into a closed triangle mesh");
  mesh_cmd->add_option("scene", mesh_args.scene, "Scene file (JSON, SCENE_FORMAT v1)")->required();
  mesh_cmd->add_option("-o,--output", mesh_args.out, "Output mesh: .ply, .obj, .off or .stl")->required();
  mesh_cmd->add_option("--precision", mesh_args.precision, "Target edge length (default: the scene's, else 1/100 of its size)")
      ->check(kPositiveFinite);
  mesh_cmd->add_option("--strategy", mesh_args.strategy,
                       "auto (per node: sweep, shared leaf, warped child, global for operators), global or local "
                       "(default: the scene's mesher.strategy)")
      ->check(CLI::IsMember({"auto", "global", "local"}));
  mesh_cmd->add_option("--threads", mesh_args.threads, "Worker threads (default: all cores)")->check(CLI::Range(1, 1024));
  bool mesh_no_optimize = false;
  mesh_cmd->add_flag("--no-optimize", mesh_no_optimize, "Mesh the tree as written, not the optimized one");
  mesh_cmd->add_option("--stats-json", mesh_args.stats_json, "Write triangles, checks and seconds per stage to FILE");
  mesh_cmd->add_option("--memory-budget", mesh_args.memory_gib, "GiB the mesher may use (default 4)")->check(kPositiveFinite);
  mesh_cmd->add_option("--sharp-features", mesh_args.sharp,
                       "on: split edges along creases of min/max Booleans, crops and mesh leaves (default); off: plain "
                       "marching tetrahedra")
      ->check(CLI::IsMember({"on", "off"}));
  mesh_cmd->add_option("--quality", mesh_args.quality,
                       "on: collapse needles, flip and relax what the polygonizer extracts into well-shaped triangles "
                       "(default); off: keep the extracted triangles")
      ->check(CLI::IsMember({"on", "off"}));
  mesh_cmd->add_option("--cache", mesh_args.cache,
                       "Keep mesh jobs' results in folder DIR between runs (made if missing); unchanged subtrees "
                       "are not meshed again")
      ->type_name("DIR");
  mesh_cmd->add_option("--cache-size", mesh_args.cache_mib,
                       "MiB the --cache folder may hold after a run; least recently used files go first (default 1024)")
      ->check(CLI::NonNegativeNumber)
      ->type_name("MiB");

  ht::cli::RenderArgs render_args;
  auto* render = app.add_subcommand("render", "Draw a scene (meshed at its precision) or a closed mesh file into a PNG");
  render->add_option("input", render_args.input, "Scene file (.json) or mesh file (.ply, .obj, .off, .stl)")->required();
  render->add_option("-o,--output", render_args.out, "Output picture (.png)")->required();
  add_pair(render, "--size", render_args.width, render_args.height, "Width and height in pixels (default 800 600)", "W H");
  add_pair(render, "--view", render_args.azimuth, render_args.elevation,
           "Azimuth around +y and elevation, degrees (default 35 25)", "AZ EL");
  render->add_option("--precision", render_args.precision, "Meshing precision for a scene (default: the scene's)")
      ->check(kPositiveFinite);

  int count = 250;
  std::uint64_t seed = 1;
  std::string generator;
  auto* generate = app.add_subcommand("generate", "Write a procedural scene as JSON to stdout");
  generate->add_option("scene", generator,
                       "Which scene: snake (blended curve primitives) or scatter (small primitives of every kind as "
                       "a left-deep chain of binary blends in random order)")
      ->required()
      ->check(CLI::IsMember({"snake", "scatter"}));
  generate->add_option("--count", count, "Number of primitives (default: 250 for snake, 900 for scatter)")->check(CLI::Range(1, 1000000));
  generate->add_option("--seed", seed, "Random seed");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  try {
    eval_args.optimize = !eval_no_optimize;
    mesh_args.optimize = !mesh_no_optimize;
    if (*info) return cmd_info(scene, !info_no_optimize);
    if (*optimize_cmd) return ht::cli::cmd_optimize(optimize_args);
    if (*eval) {
      if (eval_args.threads == 0) return cmd_eval(eval_args);
      tbb::task_arena arena(eval_args.threads);
      return arena.execute([&] { return cmd_eval(eval_args); });
    }
    if (*mesh_cmd) {
      std::unique_ptr<tbb::global_control> limit;
      if (mesh_args.threads > 0)
        limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                      static_cast<std::size_t>(mesh_args.threads));
      return cmd_mesh(mesh_args);
    }
    if (*render) return ht::cli::cmd_render(render_args);
    if (*generate) {
      std::string text;
      if (generator == "snake") {
        text = ht::scenes::snake_json(count, seed);
      } else {
        ht::Builder b;
        const ht::NodeId root = ht::scenes::scatter(b, generate->count("--count") ? count : 900, seed);
        text = ht::write_scene_text(b.build(root), std::filesystem::current_path());
      }
      std::fwrite(text.data(), 1, text.size(), stdout);
      return std::fflush(stdout) == 0 ? 0 : 1;
    }
  } catch (const ht::SceneError& e) {
    std::fprintf(stderr, "hybridtree: %s\n", e.what());
    return 2;
  } catch (const InputError& e) {
    std::fprintf(stderr, "hybridtree: %s\n", e.what());
    return 2;
  } catch (const ht::npy::Error& e) {
    std::fprintf(stderr, "hybridtree: %s\n", e.what());
    return 2;
  } catch (const ht::MeshWriteError& e) {
    std::fprintf(stderr, "hybridtree: %s\n", e.what());
    return 1;
  } catch (const ht::EvalError& e) {
    std::fprintf(stderr, "hybridtree: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hybridtree: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
