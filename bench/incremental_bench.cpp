// Incremental re-meshing (issue 15): a first meshing into an empty node cache
// (meshers/node_cache.hpp), then one edit meshed with the same cache. Counters: first_s, edit_s,
// ratio = edit_s / first_s (the targets: <= 0.10 for the 250-curve character after
// moving one curve, <= 0.25 for the winged bunny after changing the wing crop box), and the
// jobs reused / run by the edited meshing, and inside the global polygonizations the bricks and
// quality-pass slabs and bands taken from the cache (bricks_reused of bricks, pieces_reused of pieces).
//   Snake        tools/scenes.hpp snake(): one n-ary blend of 250 curves, moved: curve 100's
//                first point by 0.01 in x
//   SnakeDisk    the same edit through the disk level (`hybridtree mesh --cache DIR`): the edit
//                meshed by a fresh cache over the folder the first meshing filled;
//                ratio = edit_s / cold_s, cold_s the first meshing without any cache
//   WingedBunny  examples/winged_bunny.json, the crop box's max y 0.42 -> 0.43
// Quick mode meshes at twice the scenes' precision (coarser).
#include "bench/bench_util.hpp"
#include "meshers/mesh_plan.hpp"
#include "meshers/disk_cache.hpp"
#include "meshers/mesh_run.hpp"
#include "meshers/node_cache.hpp"
#include "runtime/scene.hpp"
#include "tools/scenes.hpp"

#include <benchmark/benchmark.h>

#include <array>
#include <chrono>
#include <filesystem>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace {

using namespace ht;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Replaces the number that starts at text[at] with f(number).
std::string edit_number(std::string text, std::size_t at, double (*f)(double)) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str() + at, &end);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", f(v));
  return text.replace(at, std::size_t(end - (text.c_str() + at)), buf);
}

void run(benchmark::State& state, const Tree& before, const Tree& after) {
  MeshOptions o;
  o.precision = default_precision(before, 0.0) * (bench::quick_mode ? 2.0 : 1.0);
  o.blend_overlap = before.mesher_settings().blend_overlap;
  double first = 0, edit = 0;
  std::size_t reused = 0, jobs = 0, bricks = 0, active = 0, pieces = 0, pieces_reused = 0;
  std::array<double, 5> stage{};  // the edited run's polygonizations: seconds by stage
  for (auto _ : state) {
    NodeCache cache(std::size_t(2) << 30);
    o.cache = &cache;
    auto t0 = std::chrono::steady_clock::now();
    const MeshResult a = mesh_tree(before, o);
    first = seconds_since(t0);
    t0 = std::chrono::steady_clock::now();
    const MeshResult b = mesh_tree(after, o);
    edit = seconds_since(t0);
    reused = jobs = bricks = active = pieces = pieces_reused = 0;
    stage = {};
    for (const NodeReport& r : b.nodes) {
      reused += r.reused, ++jobs;
      bricks += r.polygonize.bricks_reused, active += r.polygonize.bricks_active;
      pieces += r.polygonize.quality.pieces, pieces_reused += r.polygonize.quality.pieces_reused;
      const PolygonizeStats& p = r.polygonize;
      stage[0] += p.seconds_classify, stage[1] += p.seconds_sample, stage[2] += p.seconds_extract;
      stage[3] += p.seconds_merge + p.seconds_features, stage[4] += p.quality.seconds;
    }
    benchmark::DoNotOptimize(a.mesh->triangles.size() + b.mesh->triangles.size());
  }
  state.counters["first_s"] = first;
  state.counters["edit_s"] = edit;
  state.counters["ratio"] = edit / first;
  state.counters["jobs_reused"] = double(reused);
  state.counters["jobs"] = double(jobs);
  state.counters["bricks_reused"] = double(bricks);
  state.counters["bricks"] = double(active);
  state.counters["pieces_reused"] = double(pieces_reused);
  state.counters["pieces"] = double(pieces);
  const char* names[] = {"classify_s", "sample_s", "extract_s", "merge_s", "quality_s"};
  for (int i = 0; i < 5; ++i) state.counters[names[i]] = stage[i];
}

void BM_IncrementalSnake(benchmark::State& state) {
  const std::string text = scenes::snake_json(250, 1);
  std::size_t at = 0;
  for (int i = 0; i <= 100; ++i) at = text.find("\"points\": [[", at + 1);
  const std::string moved = edit_number(text, at + 12, [](double x) { return x + 0.01; });
  run(state, load_scene_text(text, "."), load_scene_text(moved, "."));
}
BENCHMARK(BM_IncrementalSnake)->Iterations(1)->UseRealTime()->Unit(benchmark::kSecond);

// The snake's edit as `hybridtree mesh --cache DIR` runs it: the first meshing writes into an empty
// folder, the edit is meshed by a fresh memory level over a fresh DiskCache of that folder (a new
// process), so every brick and piece it takes comes from a file. Counters as above, plus
// cold_s: the first meshing without any cache, and the parts read and written by the edit.
void BM_IncrementalSnakeDisk(benchmark::State& state) {
  const std::string text = scenes::snake_json(250, 1);
  std::size_t at = 0;
  for (int i = 0; i <= 100; ++i) at = text.find("\"points\": [[", at + 1);
  const Tree before = load_scene_text(text, ".");
  const Tree after = load_scene_text(edit_number(text, at + 12, [](double x) { return x + 0.01; }), ".");
  MeshOptions o;
  o.precision = default_precision(before, 0.0) * (bench::quick_mode ? 2.0 : 1.0);
  o.blend_overlap = before.mesher_settings().blend_overlap;
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "hybridtree-bench-disk-cache";
  double plain = 0, first = 0, edit = 0;
  DiskCacheStats parts;
  std::size_t bricks = 0, active = 0;
  for (auto _ : state) {
    std::filesystem::remove_all(dir);
    auto t0 = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(mesh_tree(before, o).mesh->triangles.size());
    plain = seconds_since(t0);
    {
      DiskCache disk(dir);
      NodeCache cache(std::size_t(2) << 30, &disk);
      o.cache = &cache;
      t0 = std::chrono::steady_clock::now();
      benchmark::DoNotOptimize(mesh_tree(before, o).mesh->triangles.size());
      disk.flush();
      first = seconds_since(t0);
    }
    DiskCache disk(dir);
    NodeCache cache(std::size_t(2) << 30, &disk);
    o.cache = &cache;
    t0 = std::chrono::steady_clock::now();
    const MeshResult b = mesh_tree(after, o);
    disk.flush();
    edit = seconds_since(t0);
    parts = disk.stats();
    bricks = active = 0;
    for (const NodeReport& r : b.nodes) bricks += r.polygonize.bricks_reused, active += r.polygonize.bricks_active;
    o.cache = nullptr;
  }
  std::filesystem::remove_all(dir);
  state.counters["cold_s"] = plain;
  state.counters["first_s"] = first;
  state.counters["edit_s"] = edit;
  state.counters["ratio"] = edit / plain;
  state.counters["bricks_reused"] = double(bricks);
  state.counters["bricks"] = double(active);
  state.counters["parts_read"] = double(parts.part_hits);
  state.counters["parts_written"] = double(parts.part_written);
}
BENCHMARK(BM_IncrementalSnakeDisk)->Iterations(1)->UseRealTime()->Unit(benchmark::kSecond);

void BM_IncrementalWingedBunny(benchmark::State& state) {
  const std::filesystem::path file = std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / "examples/winged_bunny.json";
  std::ifstream in(file);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  const std::size_t at = text.find("\"max\": [1, 0.42");
  if (at == std::string::npos) throw std::runtime_error("winged_bunny.json: no wing crop box");
  const std::string edited = edit_number(text, at + 11, [](double y) { return y + 0.01; });
  run(state, load_scene_text(text, file.parent_path()), load_scene_text(edited, file.parent_path()));
}
BENCHMARK(BM_IncrementalWingedBunny)->Iterations(1)->UseRealTime()->Unit(benchmark::kSecond);

}  // namespace
