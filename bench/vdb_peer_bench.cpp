// The peer comparison of issue 12: the same Boolean and blend-like operations on bunny00, done by
// HybridTree (the default strategy, auto; global polygonization, with and without its crease
// step) and by OpenVDB's level sets (mesh to level set, CSG, level set to mesh), in one run, at 1
// and 2 threads. Built only where OpenVDB was found (cmake/Dependencies.cmake; Debian's
// libopenvdb-dev).
//
// The scenes (balls are point primitives, F = 1, their surface the sphere of radius r0 about the
// centre; OpenVDB gets that exact sphere):
//   csg    bunny00 united with a ball at its tail, minus a ball at its flank (min/max Booleans)
//   blend  bunny00 (R = 0.05) blended with a ball at its ear (examples/bunny_ear.json). OpenVDB
//          has no blend: its analogue is the union followed by a morphological closing (dilate,
//          then erode, by the bunny's radius of influence) of the level set masked to the ball's
//          reach (LevelSetFilter::offset with an alpha mask). A blend of positive fields only adds
//          material, in the concave junction; a closing only adds material, in concave places,
//          and leaves convex parts (the ball away from the bunny) as they were. Curvature or
//          Gaussian flow would also shrink the ball and the bunny's convex parts.
//
// Each side starts from the mesh in memory (positions and triangles, the file read beforehand)
// and ends with a triangle mesh: HybridTree builds the mesh leaf (checks, Embree BVH), the tree,
// and meshes it at precision h; OpenVDB converts the mesh to a narrow-band level set (half-width
// 3 voxels), makes the spheres, composes, and extracts the zero level set (adaptivity 0), each
// quad split along the diagonal that gives the larger smallest angle. The voxel size is searched
// once per scene, untimed, so that OpenVDB's triangle count is within a few percent of
// HybridTree's global one ("OpenVDB"), and again for the default strategy's count ("OpenVDB,
// auto's n": a coarser grid at the full precision, where auto keeps bunny00's 75k triangles and
// global makes twice as many; a finer one in quick mode, where global's mesh is the coarser):
// each HybridTree side is compared with OpenVDB at its own triangle count.
//
// Measured per benchmark: wall time (manual time, the best of three runs), peak memory of the
// same run in a fresh process (bench/peak_memory.hpp), and, once per scene and side, the mesh checks
// (self-intersecting triangle pairs, smallest angle and its first percentile) and the surface
// accuracy against the exact inputs: vertices farther than the balls' reach (Booleans: their
// surface; blend: their radius of influence) plus a margin of 3 h measured to bunny00's exact
// surface (Embree closest point), and vertices farther than the bunny's reach plus the margin to
// the exact spheres. HybridTree's benchmarks add the ratios to OpenVDB at the same thread count
// (x_time, x_mem, ...: HybridTree / OpenVDB at its triangle count), and a table of every figure and ratio goes to stderr
// at the end.
//
// Quick mode (bench/main.cpp) runs both scenes coarser (h = 0.04, two tries at the voxel size)
// and skips the peak-memory children (reported as -1): 16 s of the harness's minute with the
// machine's two cores loaded seven deep, less when it is quiet.
#include "bench/bench_util.hpp"
#include "bench/peak_memory.hpp"
#include "meshers/mesh_checks.hpp"
#include "meshers/mesh_plan.hpp"
#include "nodes/mesh_leaf.hpp"
#include "nodes/primitives.hpp"
#include "runtime/builder.hpp"

#include <benchmark/benchmark.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Clip.h>
#include <openvdb/tools/Composite.h>
#include <openvdb/tools/LevelSetFilter.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

namespace {

using namespace ht;

constexpr double kThreshold = 0.5;
constexpr float kHalfWidth = 3.0f;  // voxels, OpenVDB's default narrow band

struct Ball {
  glm::dvec3 center;
  double R;    ///< radius of influence (F = 1)
  bool carve;  ///< subtracted (csg only)
  double radius() const { return primitive_r0(R, 1.0, kThreshold); }
};

struct PeerScene {
  const char* name;
  bool blend;
  double bunny_R;
  std::vector<Ball> balls;
};

const std::vector<PeerScene>& peer_scenes() {
  // csg: balls of radius about 0.12 and 0.15 (R = r0 / 0.4542 at T = 0.5, F = 1).
  static const std::vector<PeerScene> scenes = {
      {"csg", false, 0.05, {{{0.50, -0.22, 0.06}, 0.12 / 0.4542, false}, {{0.10, -0.17, 0.44}, 0.15 / 0.4542, true}}},
      {"blend", true, 0.05, {{{-0.005, 0.5, -0.12}, 0.12, false}}},
  };
  return scenes;
}

double precision() { return bench::quick_mode ? 0.04 : 0.01; }

/// The sides: HybridTree's default strategy, global polygonization, global without the crease
/// step (PolygonizeOptions::sharp_features off), OpenVDB at global's triangle count, and OpenVDB
/// at the default strategy's.
enum Side : int { kAuto = 0, kGlobal = 1, kGlobalSmooth = 2, kVdb = 3, kVdbAtAuto = 4 };
const char* side_name(int side) {
  constexpr const char* names[] = {"HybridTree auto", "HybridTree global", "global, no creases", "OpenVDB",
                                   "OpenVDB, auto's n"};
  return names[side];
}
bool is_vdb(int side) { return side == kVdb || side == kVdbAtAuto; }
/// The OpenVDB side a HybridTree side is measured against: the one at its triangle count.
int peer_of(int side) { return side == kAuto ? kVdbAtAuto : kVdb; }

struct Input {
  std::vector<glm::dvec3> positions;
  std::vector<glm::uvec3> triangles;
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> faces;
  std::shared_ptr<const MeshLeaf> exact;  ///< bunny00 itself: distances to its surface
};

const Input& input() {
  static const Input in = [] {
    openvdb::initialize();
    Input r;
    r.exact = MeshLeaf::load(bench::cgal_mesh("bunny00.off"));
    r.positions = r.exact->positions();
    r.triangles = r.exact->triangles();
    for (const glm::dvec3& p : r.positions) r.points.emplace_back(float(p.x), float(p.y), float(p.z));
    for (const glm::uvec3& t : r.triangles) r.faces.emplace_back(t.x, t.y, t.z);
    return r;
  }();
  return in;
}

// --- HybridTree ------------------------------------------------------------------------------

struct Meshed {
  std::shared_ptr<const TriangleMesh> mesh;  ///< the result as mesh_tree hands it over (no copy)
  std::string how;  ///< the root job's strategy and reason
};

Meshed run_hybridtree(const PeerScene& s, int side, double h, const Input& in) {
  auto leaf = MeshLeaf::from_triangles(in.positions, in.triangles, "bunny00.off");
  Builder b(kThreshold);
  NodeId root = b.mesh(leaf, {s.bunny_R});
  for (const Ball& ball : s.balls) {
    const NodeId p = b.point(ball.center, {ball.R});
    root = s.blend ? b.blend({root, p}) : ball.carve ? b.subtract({root, p}) : b.unite({root, p});
  }
  const Tree tree = b.build(root);
  MeshOptions o;
  o.precision = h;
  o.strategy = side == kAuto ? MeshStrategy::Auto : MeshStrategy::Global;
  o.polygonize.sharp_features = side != kGlobalSmooth;
  MeshResult r = mesh_tree(tree, o);
  Meshed out{r.mesh, {}};
  for (const NodeReport& n : r.nodes)
    if (n.node == tree.root())
      out.how = std::string(to_string(n.strategy)) + " (" + to_string(n.reason) +
                (n.fallback_cause.empty() ? "" : ": " + n.fallback_cause) + (n.rho >= 0 ? ", rho " + std::to_string(n.rho) : "") + ")";
  return out;
}

// --- OpenVDB ---------------------------------------------------------------------------------

double smallest_angle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  const auto angle = [](const glm::dvec3& o, const glm::dvec3& p, const glm::dvec3& q) {
    const glm::dvec3 u = p - o, v = q - o;
    return std::atan2(glm::length(glm::cross(u, v)), glm::dot(u, v));
  };
  return std::min({angle(a, b, c), angle(b, c, a), angle(c, a, b)});
}

/// OpenVDB's polygons as our triangle mesh: quads split along the diagonal whose two triangles
/// have the larger smallest angle.
TriangleMesh to_triangles(const std::vector<openvdb::Vec3s>& points, const std::vector<openvdb::Vec3I>& triangles,
                          const std::vector<openvdb::Vec4I>& quads) {
  TriangleMesh m;
  m.positions.reserve(points.size());
  for (const openvdb::Vec3s& p : points) m.positions.emplace_back(p.x(), p.y(), p.z());
  m.triangles.reserve(triangles.size() + 2 * quads.size());
  // volumeToMesh winds its polygons clockwise seen from outside: reversed here.
  for (const openvdb::Vec3I& t : triangles) m.triangles.emplace_back(t.x(), t.z(), t.y());
  for (const openvdb::Vec4I& q : quads) {
    const glm::uvec4 v(q[0], q[3], q[2], q[1]);
    const auto& P = m.positions;
    const double ac = std::min(smallest_angle(P[v[0]], P[v[1]], P[v[2]]), smallest_angle(P[v[0]], P[v[2]], P[v[3]]));
    const double bd = std::min(smallest_angle(P[v[0]], P[v[1]], P[v[3]]), smallest_angle(P[v[1]], P[v[2]], P[v[3]]));
    if (ac >= bd) {
      m.triangles.emplace_back(v[0], v[1], v[2]);
      m.triangles.emplace_back(v[0], v[2], v[3]);
    } else {
      m.triangles.emplace_back(v[0], v[1], v[3]);
      m.triangles.emplace_back(v[1], v[2], v[3]);
    }
  }
  return m;
}

TriangleMesh run_openvdb(const PeerScene& s, double voxel, const Input& in) {
  using openvdb::FloatGrid;
  const auto v = float(voxel);
  const auto xform = openvdb::math::Transform::createLinearTransform(double(v));
  FloatGrid::Ptr grid = openvdb::tools::meshToLevelSet<FloatGrid>(*xform, in.points, in.faces, kHalfWidth);
  for (const Ball& ball : s.balls) {
    const openvdb::Vec3f c(float(ball.center.x), float(ball.center.y), float(ball.center.z));
    FloatGrid::Ptr sphere = openvdb::tools::createLevelSetSphere<FloatGrid>(float(ball.radius()), c, v, kHalfWidth);
    if (ball.carve)
      openvdb::tools::csgDifference(*grid, *sphere);
    else
      openvdb::tools::csgUnion(*grid, *sphere);
    if (!s.blend) continue;
    // The closing, masked to the ball's reach: alpha 1 deeper than a quarter of R inside the
    // reach, easing to 0 at its boundary (the mask is the reach sphere's signed distance). Only
    // a box about the reach is filtered (every offset step re-tracks the whole narrow band it is
    // given), then united back: the closing only adds material, and the caps the clipping makes
    // lie inside the solid, past the mask.
    const float ramp = float(0.25 * ball.R);
    FloatGrid::Ptr reach = openvdb::tools::createLevelSetSphere<FloatGrid>(float(ball.R), c, v, ramp / v + 1.0f);
    const double pad = ball.R + s.bunny_R + 4 * voxel;
    const openvdb::BBoxd box(openvdb::Vec3d(c) - openvdb::Vec3d(pad), openvdb::Vec3d(c) + openvdb::Vec3d(pad));
    FloatGrid::Ptr local = openvdb::tools::clip(*grid, box);
    openvdb::tools::LevelSetFilter<FloatGrid> filter(*local);
    filter.setMaskRange(-ramp, 0.0f);
    filter.invertMask();
    filter.offset(-float(s.bunny_R), reach.get());
    filter.offset(float(s.bunny_R), reach.get());
    openvdb::tools::csgUnion(*grid, *local);
  }
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(*grid, points, triangles, quads, 0.0, 0.0);
  return to_triangles(points, triangles, quads);
}

// --- Measures --------------------------------------------------------------------------------

struct ErrorStats {
  double max = 0, mean = 0;
  std::size_t count = 0;
  std::size_t exact = 0;  ///< within 1e-9 of the surface
};

struct Quality {
  std::size_t triangles = 0;
  MeshChecks checks;
  ErrorStats bunny;   ///< vertices away from the balls, to bunny00
  ErrorStats sphere;  ///< vertices away from the bunny, to the nearest sphere
};

Quality measure(const PeerScene& s, const TriangleMesh& mesh, double margin) {
  Quality q;
  q.triangles = mesh.triangles.size();
  q.checks = check_mesh(mesh, true);
  const Input& in = input();
  const std::size_t n = mesh.positions.size();
  // Per vertex: distance to bunny00 when away from every ball's reach, to the nearest sphere
  // when away from the bunny's; -1 where not measured.
  std::vector<double> to_bunny(n, -1), to_sphere(n, -1);
  const double bunny_reach = (s.blend ? s.bunny_R : 0.0) + margin;
  tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
    const glm::dvec3& p = mesh.positions[i];
    bool away = true;
    double sphere = 1e300;
    for (const Ball& b : s.balls) {
      const double d = glm::length(p - b.center);
      away = away && d > (s.blend ? b.R : b.radius()) + margin;
      sphere = std::min(sphere, std::abs(d - b.radius()));
    }
    const double bunny = in.exact->query(p, 1.0).distance;
    if (away) to_bunny[i] = bunny;
    if (bunny > bunny_reach) to_sphere[i] = sphere;
  });
  const auto gather = [](const std::vector<double>& e, ErrorStats& st) {
    double sum = 0;
    for (double d : e) {
      if (d < 0) continue;
      st.max = std::max(st.max, d);
      sum += d;
      ++st.count;
      st.exact += d <= 1e-9 ? 1 : 0;
    }
    st.mean = st.count ? sum / double(st.count) : 0;
  };
  gather(to_bunny, q.bunny);
  gather(to_sphere, q.sphere);
  return q;
}

struct SideResult {
  Quality quality;
  std::string how;
  double voxel = 0;  ///< OpenVDB's voxel size
};

struct Timing {
  double seconds = 0;
  double peak_bytes = -1;
};

std::map<std::pair<int, int>, SideResult>& side_results() {
  static std::map<std::pair<int, int>, SideResult> r;
  return r;
}
std::map<std::tuple<int, int, int>, Timing>& timings() {
  static std::map<std::tuple<int, int, int>, Timing> r;
  return r;
}


/// The voxel size at which OpenVDB's triangle count is closest to `target`: triangles scale as
/// 1 / voxel^2, so each try corrects the last by the square root of the counts' ratio.
double search_voxel(const PeerScene& s, std::size_t target, double area) {
  double voxel = std::sqrt(3.0 * area / double(target)), best = voxel, best_miss = 1e300;
  for (int attempt = 0; attempt < (bench::quick_mode ? 2 : 4); ++attempt) {
    const auto got = double(run_openvdb(s, voxel, input()).triangles.size());
    const double miss = std::abs(got / double(target) - 1.0);
    if (miss < best_miss) best = voxel, best_miss = miss;
    if (miss < 0.02) break;
    voxel *= std::sqrt(got / double(target));
  }
  return best;
}

/// Meshes and measures a side once per scene (untimed, both threads of the machine).
const SideResult& side_result(int scene, int side) {
  auto& cache = side_results();
  if (auto it = cache.find({scene, side}); it != cache.end()) return it->second;
  const PeerScene& s = peer_scenes()[std::size_t(scene)];
  const double margin = 3 * precision();
  SideResult r;
  if (is_vdb(side)) {
    const SideResult& target = side_result(scene, side == kVdb ? kGlobal : kAuto);
    r.voxel = search_voxel(s, target.quality.triangles, target.quality.checks.area);
    r.quality = measure(s, run_openvdb(s, r.voxel, input()), margin);
    r.how = "voxel " + std::to_string(r.voxel);
  } else {
    Meshed m = run_hybridtree(s, side, precision(), input());
    r.quality = measure(s, *m.mesh, margin);
    r.how = m.how;
  }
  return cache[{scene, side}] = std::move(r);
}

std::string peak_arg(int scene, int side, int threads, double voxel) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "%d:%d:%d:%.17g:%d", scene, side, threads, voxel, bench::quick_mode ? 1 : 0);
  return buf;
}

/// Runs a side once on `threads` threads (the mesh thrown away).
void run_side(int scene, int side, int threads, double voxel) {
  const PeerScene& s = peer_scenes()[std::size_t(scene)];
  tbb::task_arena arena(threads);
  arena.execute([&] {
    if (is_vdb(side))
      benchmark::DoNotOptimize(run_openvdb(s, voxel, input()).triangles.size());
    else
      benchmark::DoNotOptimize(run_hybridtree(s, side, precision(), input()).mesh->triangles.size());
  });
}

/// The best of three timed runs of a side (one in quick mode), with its peak memory from a child
/// process outside quick mode.
Timing timed_run(int scene, int side, int threads) {
  const double voxel = is_vdb(side) ? side_result(scene, side).voxel : 0;
  Timing t;
  t.seconds = 1e300;
  for (int run = 0; run < (bench::quick_mode ? 1 : 3); ++run) {
    const auto start = std::chrono::steady_clock::now();
    run_side(scene, side, threads, voxel);
    t.seconds = std::min(t.seconds, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  if (!bench::quick_mode) t.peak_bytes = bench::peak_bytes_in_child("vdb_peer", peak_arg(scene, side, threads, voxel)).value_or(-1);
  return timings()[{scene, side, threads}] = t;
}

const Timing& timing(int scene, int side, int threads) {
  auto& t = timings();
  if (auto it = t.find({scene, side, threads}); it != t.end()) return it->second;
  timed_run(scene, side, threads);
  return t[{scene, side, threads}];
}

// The child of peak_bytes_in_child: "scene:side:threads:voxel:quick".
const bool registered = bench::register_peak_task("vdb_peer", [](const std::string& arg) {
  int scene = 0, side = 0, threads = 1, quick = 0;
  double voxel = 0;
  if (std::sscanf(arg.c_str(), "%d:%d:%d:%lf:%d", &scene, &side, &threads, &voxel, &quick) != 5 || scene < 0 ||
      scene >= int(peer_scenes().size()) || side < kAuto || side > kVdbAtAuto || threads < 1)
    throw std::invalid_argument("bad argument " + arg);
  bench::quick_mode = quick != 0;
  input();  // read before the measure
  return std::function<void()>([scene, side, threads, voxel] { run_side(scene, side, threads, voxel); });
});

// --- Report ----------------------------------------------------------------------------------

void set_counters(benchmark::State& state, const SideResult& r, const Timing& t) {
  const Quality& q = r.quality;
  state.counters["triangles"] = double(q.triangles);
  state.counters["peak_MiB"] = t.peak_bytes < 0 ? -1 : t.peak_bytes / (1024.0 * 1024.0);
  state.counters["self_x"] = double(q.checks.self_intersecting_pairs);
  state.counters["min_angle"] = q.checks.min_angle;
  state.counters["angle_p1"] = q.checks.min_angle_p1;
  state.counters["bunny_err_max"] = q.bunny.max;
  state.counters["bunny_err_mean"] = q.bunny.mean;
  state.counters["exact_frac"] = q.bunny.count ? double(q.bunny.exact) / double(q.bunny.count) : 0;
  state.counters["sphere_err_max"] = q.sphere.max;
  state.counters["sphere_err_mean"] = q.sphere.mean;
}

double ratio(double a, double b) { return b > 0 && a >= 0 ? a / b : -1; }

// The table on stderr at the end of the run (a static's destructor: after every benchmark).
struct Summary {
  std::vector<std::string> lines;
  MeshChecks input_checks;  ///< bunny00's own angles, which the auto strategy keeps
  ~Summary() {
    if (lines.empty()) return;
    std::fprintf(stderr, "\nOpenVDB peer (bench/vdb_peer_bench.cpp), x = HybridTree / OpenVDB at the same threads\n"
                         "and triangle count (auto against \"OpenVDB, auto's n\", global against \"OpenVDB\"):\n");
    std::fprintf(stderr, "%-6s %-17s %3s %8s %8s %8s %7s %7s %7s %10s %10s %7s %10s %10s\n", "scene", "side", "thr",
                 "tris", "s", "MiB", "self_x", "min_deg", "p1_deg", "bunny_max", "bunny_mean", "exact", "sph_max",
                 "sph_mean");
    for (const std::string& l : lines) std::fputs(l.c_str(), stderr);
    std::fprintf(stderr, "(bunny00 itself: %zu triangles, smallest angle %.2f, first percentile %.2f degrees)\n",
                 input_checks.triangles, input_checks.min_angle, input_checks.min_angle_p1);
  }
} summary;

void add_line(const char* scene, int side, int threads, const SideResult& r, const Timing& t) {
  if (summary.input_checks.triangles == 0) summary.input_checks = check_mesh(*input().exact->surface(), false);
  const Quality& q = r.quality;
  const auto error = [](const ErrorStats& e, double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.2e", v);
    return e.count ? std::string(b) : std::string("-");
  };
  char mib[32] = "-";
  if (t.peak_bytes >= 0) std::snprintf(mib, sizeof mib, "%.1f", t.peak_bytes / (1024.0 * 1024.0));
  char buf[512];
  std::snprintf(buf, sizeof buf, "%-6s %-17s %3d %8zu %8.3f %8s %7zu %7.2f %7.2f %10s %10s %7.3f %10s %10s   %s\n",
                scene, side_name(side), threads, q.triangles, t.seconds, mib,
                q.checks.self_intersecting_pairs, q.checks.min_angle, q.checks.min_angle_p1,
                error(q.bunny, q.bunny.max).c_str(), error(q.bunny, q.bunny.mean).c_str(),
                q.bunny.count ? double(q.bunny.exact) / double(q.bunny.count) : 0.0, error(q.sphere, q.sphere.max).c_str(),
                error(q.sphere, q.sphere.mean).c_str(), r.how.c_str());
  summary.lines.emplace_back(buf);
}

void add_ratio_line(const char* scene, int side, int threads, const SideResult& a, const Timing& ta,
                    const SideResult& b, const Timing& tb) {
  const Quality &p = a.quality, &q = b.quality;
  char buf[512];
  std::snprintf(buf, sizeof buf, "%-6s %-17s %3d %8.2f %8.2f %8.2f %7s %7.2f %7.2f %10.2f %10.2f %7s %10.2f %10.2f\n", scene,
                (std::string("x ") + (side == kAuto ? "auto" : side == kGlobal ? "global" : "no creases")).c_str(), threads,
                ratio(double(p.triangles), double(q.triangles)), ratio(ta.seconds, tb.seconds),
                ratio(ta.peak_bytes, tb.peak_bytes),
                (std::to_string(p.checks.self_intersecting_pairs) + "/" + std::to_string(q.checks.self_intersecting_pairs)).c_str(),
                ratio(p.checks.min_angle, q.checks.min_angle), ratio(p.checks.min_angle_p1, q.checks.min_angle_p1),
                ratio(p.bunny.max, q.bunny.max), ratio(p.bunny.mean, q.bunny.mean), "", ratio(p.sphere.max, q.sphere.max),
                ratio(p.sphere.mean, q.sphere.mean));
  summary.lines.emplace_back(buf);
}

/// A benchmark's common part: the side's measures, one timed run in the loop, the counters and
/// the summary's line; nullptr (the benchmark skipped) when a side failed to mesh.
const SideResult* run_benchmark(benchmark::State& state, int scene, int side, int threads, Timing& t) {
  const SideResult* r = nullptr;
  try {
    r = &side_result(scene, side);
    if (!is_vdb(side)) side_result(scene, peer_of(side));
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return nullptr;
  }
  for (auto _ : state) {
    t = timed_run(scene, side, threads);
    state.SetIterationTime(t.seconds);
  }
  const char* name = peer_scenes()[std::size_t(scene)].name;
  state.SetLabel(std::string(name) + ", " + r->how);
  set_counters(state, *r, t);
  add_line(name, side, threads, *r, t);
  return r;
}

// Args: scene (0 csg, 1 blend), side (3 at global's triangle count, 4 at auto's), threads.
void BM_PeerOpenVDB(benchmark::State& state) {
  Timing t;
  if (const SideResult* r = run_benchmark(state, int(state.range(0)), int(state.range(1)), int(state.range(2)), t))
    state.counters["voxel"] = r->voxel;
}
BENCHMARK(BM_PeerOpenVDB)
    ->ArgsProduct({{0, 1}, {kVdb, kVdbAtAuto}, {1, 2}})
    ->ArgNames({"scene", "side", "threads"})
    ->UseManualTime()
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

// Args: scene, side (0 auto, 1 global, 2 global without the crease step), threads.
void BM_PeerHybridTree(benchmark::State& state) {
  const int scene = int(state.range(0)), side = int(state.range(1)), threads = int(state.range(2));
  Timing t;
  const SideResult* r = run_benchmark(state, scene, side, threads, t);
  if (r == nullptr) return;
  const SideResult* vdb = &side_result(scene, peer_of(side));
  const Timing& tv = timing(scene, peer_of(side), threads);
  state.counters["h"] = precision();
  state.counters["x_tris"] = ratio(double(r->quality.triangles), double(vdb->quality.triangles));
  state.counters["x_time"] = ratio(t.seconds, tv.seconds);
  state.counters["x_mem"] = ratio(t.peak_bytes, tv.peak_bytes);
  state.counters["x_angle_p1"] = ratio(r->quality.checks.min_angle_p1, vdb->quality.checks.min_angle_p1);
  state.counters["x_bunny_max"] = ratio(r->quality.bunny.max, vdb->quality.bunny.max);
  state.counters["x_bunny_mean"] = ratio(r->quality.bunny.mean, vdb->quality.bunny.mean);
  add_ratio_line(peer_scenes()[std::size_t(scene)].name, side, threads, *r, t, *vdb, tv);
}
BENCHMARK(BM_PeerHybridTree)
    ->ArgsProduct({{0, 1}, {kAuto, kGlobal, kGlobalSmooth}, {1, 2}})
    ->ArgNames({"scene", "side", "threads"})
    ->UseManualTime()
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

}  // namespace
