// The on-disk level of the node cache (meshers/disk_cache.hpp): a warm folder gives a fresh
// process the from-scratch mesh byte for byte, reusing every job; bad files (truncated,
// corrupt, stale, misnamed, forged) are each ignored with one warning and the run's output stays
// the same; writers at once (threads and processes) agree and leave no temporary files; trim()
// keeps the least recently used last. The parts of a global polygonization (bricks, quality
// pieces, clean regions) reused by the next process after an edit, and checked when read. The
// CLI's --cache end to end.
#include "meshers/cache_parts.hpp"
#include "meshers/disk_cache.hpp"
#include "meshers/mesh_plan.hpp"
#include "meshers/node_cache.hpp"
#include "meshers/polygonize.hpp"
#include "runtime/builder.hpp"
#include "runtime/scene.hpp"
#include "tools/scenes.hpp"
#include "tests/support/random_tree.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <fcntl.h>
#include <sys/stat.h>

#include <algorithm>
#include <cstring>
#include <ctime>
#include <functional>
#include <mutex>
#include <thread>

using namespace ht;
using glm::dvec3;
namespace fs = std::filesystem;

namespace {

constexpr double kT = 0.5;
constexpr std::size_t kBytes = std::size_t(1) << 30;

// One process's view of a cache folder: a fresh memory level over its own DiskCache.
struct Process {
  std::mutex mutex;
  std::vector<std::string> warnings;
  DiskCache disk;
  NodeCache memory;

  explicit Process(const fs::path& dir)
      : disk(dir, kBytes, [this](const std::string& line) {
          std::lock_guard lock(mutex);
          warnings.push_back(line);
        }),
        memory(kBytes, &disk) {}

  MeshResult mesh(const Tree& tree) {
    MeshOptions o = test::mesh_options(0.12);
    o.cache = &memory;
    MeshResult r = mesh_tree(tree, o);
    disk.flush();  // the parts' writer may still warn
    return r;
  }
};

// A random tree whose solid meshes (bounded, not empty), or nullopt.
std::optional<Tree> random_scene(int seed) {
  test::Rng rng(seed);
  test::RandomTreeOptions o;
  o.max_depth = 3;
  Builder b(kT);
  Tree t = b.build(test::random_tree(b, rng, o));
  try {
    if (mesh_tree(t, test::mesh_options(0.12)).mesh->triangles.empty()) return std::nullopt;
  } catch (const PolygonizeError&) {
    return std::nullopt;
  }
  return t;
}

// A blend beside a segment: five jobs, two of them trims.
Tree fixed_scene() {
  Builder b(kT);
  const NodeId ball = b.point(dvec3(0, 0, 0), {0.8, 1.0});
  const NodeId bar = b.segment(dvec3(0.3, 0, 0), dvec3(1.2, 0.2, 0), {0.4, 1.0});
  const NodeId rod = b.segment(dvec3(-1.5, -0.5, 0), dvec3(-1.5, 0.5, 0.3), {0.3, 1.0});
  return b.build(b.unite({b.blend({ball, bar}), rod}));
}

std::size_t reused(const MeshResult& r) {
  return std::size_t(std::count_if(r.nodes.begin(), r.nodes.end(), [](const NodeReport& e) { return e.reused; }));
}

// The report as the cache file stores it (every field but node, seconds and reused).
std::string stored(NodeReport r) {
  r.seconds = 0;
  return encode_cache_entry(0, CachedJob{nullptr, r});
}

std::vector<fs::path> files_in(const fs::path& dir, const std::string& ending) {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename().string().ends_with(ending)) out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

void copy_folder(const fs::path& from, const fs::path& to) {
  fs::remove_all(to);
  fs::copy(from, to);
}

// A brick's triangles index its vertices in 16 bits; a quality piece (a slab of the whole mesh)
// in 32: a piece of 70,000 vertices round-trips, a brick of as many is refused. (The brick's
// limit once reached the pieces too, and every large piece was written, refused and improved
// again on each run, with a warning.)
TEST(DiskCache, PiecesHoldMoreVerticesThanABrickCan) {
  QualityPiece piece;
  const std::uint32_t n = 70000;
  for (std::uint32_t v = 0; v < n; ++v) piece.mesh.positions.push_back({double(v), 0.0, 0.0}), piece.origin.push_back(v);
  for (std::uint32_t v = 0; v + 2 < n; v += 3) piece.mesh.triangles.push_back({v, v + 1, v + 2});
  QualityPiece back;
  std::string why;
  ASSERT_TRUE(decode_piece(encode_piece(piece), n, back, why)) << why;
  EXPECT_EQ(back.mesh.positions.size(), std::size_t(n));
  EXPECT_TRUE(back.mesh.triangles == piece.mesh.triangles);

  brick::KeptBrick brick;
  for (std::uint32_t v = 0; v < n; ++v) brick.out.vertices.push_back({std::uint64_t(v), {double(v), 0.0, 0.0}, glm::vec3(0.0f), 0});
  brick.out.triangles.push_back({0, 1, 2});
  brick::KeptBrick refused;
  EXPECT_FALSE(decode_kept(encode_kept(brick), refused, why));
  EXPECT_NE(why.find("16-bit"), std::string::npos) << why;
}

TEST(DiskCache, AWarmFolderGivesAFreshProcessTheSameBytesAndReports) {
  int compared = 0;
  for (int seed = 0; seed < 16; ++seed) {
    const std::optional<Tree> t = random_scene(900 + seed);
    if (!t) continue;
    const fs::path dir = test::temp_dir("disk-warm") / "cache";  // made by DiskCache
    const MeshResult scratch = mesh_tree(*t, test::mesh_options(0.12));
    NodeCache memory(kBytes);  // the in-memory cache's reports, for comparison
    MeshOptions o = test::mesh_options(0.12);
    o.cache = &memory;
    mesh_tree(*t, o);
    const MeshResult from_memory = mesh_tree(*t, o);
    Process cold(dir);
    const MeshResult first = cold.mesh(*t);
    EXPECT_EQ(reused(first), 0u);
    EXPECT_GE(cold.disk.stats().written, 1u);
    Process warm(dir);
    const MeshResult second = warm.mesh(*t);
    ++compared;
    ASSERT_TRUE(test::same_bytes(*scratch.mesh, *first.mesh)) << seed;
    ASSERT_TRUE(test::same_bytes(*scratch.mesh, *second.mesh)) << seed;
    EXPECT_EQ(reused(second), second.nodes.size()) << seed << ": every job was on disk";
    EXPECT_EQ(warm.disk.stats().hits, second.nodes.size());
    EXPECT_EQ(warm.disk.stats().ignored_total(), 0u);
    EXPECT_TRUE(warm.warnings.empty());
    ASSERT_EQ(second.nodes.size(), from_memory.nodes.size());
    // As from memory: the report of the job that ran (its timings too), bit for bit.
    for (std::size_t i = 0; i < second.nodes.size(); ++i) {
      EXPECT_EQ(second.nodes[i].node, from_memory.nodes[i].node);
      EXPECT_TRUE(from_memory.nodes[i].reused);
      EXPECT_EQ(second.nodes[i].strategy, from_memory.nodes[i].strategy);
      EXPECT_EQ(stored(second.nodes[i]), stored(first.nodes[i])) << seed << " node " << second.nodes[i].node;
    }
    fs::remove_all(dir.parent_path());
  }
  EXPECT_GE(compared, 6);
}

// One kind of damage done to a file of a warm folder (the other files are there too).
struct Damage {
  const char* name;
  DiskIgnore reason;
  const char* says;  // in the warning
  std::function<void(std::string& bytes, const std::string& other)> apply;
};

void patch_word(std::string& bytes, std::size_t at, std::uint64_t w) { std::memcpy(bytes.data() + at, &w, 8); }

std::vector<Damage> damages() {
  return {
      {"truncated", DiskIgnore::Truncated, "truncated", [](std::string& b, const std::string&) { b.resize(b.size() / 2); }},
      {"empty", DiskIgnore::Truncated, "0 bytes", [](std::string& b, const std::string&) { b.clear(); }},
      {"flipped byte", DiskIgnore::Checksum, "checksum mismatch",
       [](std::string& b, const std::string&) { b[b.size() - 30] = char(b[b.size() - 30] ^ 0x10); }},
      {"other layout", DiskIgnore::Stale, "stale", [](std::string& b, const std::string&) { b[8] = char(b[8] + 1); }},
      {"other build", DiskIgnore::Stale, "another build", [](std::string& b, const std::string&) { b[16] = char(b[16] ^ 1); }},
      {"bad magic", DiskIgnore::Magic, "bad magic", [](std::string& b, const std::string&) { b[0] = 'X'; }},
      {"trailing bytes", DiskIgnore::Length, "header states", [](std::string& b, const std::string&) { b += "xyz"; }},
      {"another key's entry", DiskIgnore::Key, "holds the entry of key",
       [](std::string& b, const std::string& other) { b = other; }},
      {"absurd vertex count", DiskIgnore::Contents, "cannot fit",
       [](std::string& b, const std::string&) {
         patch_word(b, 48, std::uint64_t(1) << 60);
         reseal_cache_entry(b);
       }},
      {"index past the vertices", DiskIgnore::Contents, "names vertex",
       [](std::string& b, const std::string&) {
         std::uint64_t vertices;
         std::memcpy(&vertices, b.data() + 48, 8);
         const std::uint32_t bad = 0xffffffffu;
         std::memcpy(b.data() + 64 + 24 * vertices, &bad, 4);
         reseal_cache_entry(b);
       }},
  };
}

TEST(DiskCache, BadFilesAreIgnoredWithOneWarningAndTheOutputStaysTheSame) {
  const Tree t = fixed_scene();
  const fs::path root = test::temp_dir("disk-bad");
  const MeshResult scratch = mesh_tree(t, test::mesh_options(0.12));
  ASSERT_FALSE(scratch.mesh->triangles.empty());
  {
    Process fill(root / "pristine");
    fill.mesh(t);
  }
  const std::vector<fs::path> pristine = files_in(root / "pristine", ".htc");
  ASSERT_EQ(pristine.size(), scratch.nodes.size());
  for (const Damage& d : damages()) {
    const fs::path dir = root / "case";
    copy_folder(root / "pristine", dir);
    const fs::path victim = dir / pristine[0].filename();  // any file with triangles will do
    std::string bytes = test::read_file(victim);
    d.apply(bytes, test::read_file(pristine[1]));
    test::write_file(victim, bytes);
    Process p(dir);
    const MeshResult r = p.mesh(t);
    EXPECT_TRUE(test::same_bytes(*scratch.mesh, *r.mesh)) << d.name;
    EXPECT_EQ(reused(r), r.nodes.size() - 1) << d.name << ": only the damaged file's job ran";
    ASSERT_EQ(p.warnings.size(), 1u) << d.name;
    EXPECT_NE(p.warnings[0].find(victim.string()), std::string::npos) << p.warnings[0];
    EXPECT_NE(p.warnings[0].find(d.says), std::string::npos) << d.name << ": " << p.warnings[0];
    EXPECT_EQ(p.disk.stats().ignored[std::size_t(d.reason)], 1u) << d.name;
    EXPECT_EQ(p.disk.stats().ignored_total(), 1u) << d.name;
    // The job's result replaced the bad file.
    EXPECT_EQ(test::read_file(victim), test::read_file(pristine[0])) << d.name;
  }
  fs::remove_all(root);
}

TEST(DiskCache, EveryTruncationAndEveryFlippedByteOfAnEntryIsRejected) {
  auto mesh = std::make_shared<TriangleMesh>();
  mesh->positions = {dvec3(0, 0, 0), dvec3(1, 0, 0), dvec3(0, 1, 0), dvec3(0, 0, 1)};
  mesh->triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  NodeReport report;
  report.strategy = JobStrategy::TrimBlend;
  report.reason = JobReason::Fallback;
  report.fallback_cause = "a cause";
  report.refinements = {"precision 0.1: 2 degenerate triangles"};
  report.polygonize.domain = Aabb{dvec3(-1), dvec3(2)};
  const std::string bytes = encode_cache_entry(42, CachedJob{mesh, report});
  CacheEntryError error;
  const std::optional<CachedJob> back = decode_cache_entry(bytes, 42, &error);
  ASSERT_TRUE(back) << error.detail;
  EXPECT_TRUE(test::same_bytes(*back->mesh, *mesh));
  EXPECT_EQ(stored(back->report), stored(report));
  EXPECT_FALSE(decode_cache_entry(bytes, 43, &error));
  EXPECT_EQ(error.reason, DiskIgnore::Key);
  for (std::size_t n = 0; n < bytes.size(); ++n)
    ASSERT_FALSE(decode_cache_entry(std::string_view(bytes).substr(0, n), 42, nullptr)) << "cut at " << n;
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    std::string flipped = bytes;
    flipped[i] = char(flipped[i] ^ 0x01);
    ASSERT_FALSE(decode_cache_entry(flipped, 42, nullptr)) << "byte " << i;
  }
}

TEST(DiskCache, ForgedEntriesWithAGoodChecksumAreCheckedAgainstTheirLength) {
  const std::string good = encode_cache_entry(7, CachedJob{std::make_shared<TriangleMesh>(), NodeReport{}});
  auto forged = [&](std::size_t at, std::uint64_t w) {
    std::string b = good;
    patch_word(b, at, w);
    reseal_cache_entry(b);
    CacheEntryError error;
    EXPECT_FALSE(decode_cache_entry(b, 7, &error)) << at;
    EXPECT_EQ(error.reason, DiskIgnore::Contents) << at;
    return error.detail;
  };
  EXPECT_NE(forged(48, ~std::uint64_t(0) / 8).find("vertices cannot fit"), std::string::npos);
  EXPECT_NE(forged(56, std::uint64_t(1) << 62).find("triangles cannot fit"), std::string::npos);
  // After the two counts: strategy and reason bytes, rho, then the fallback cause's length.
  std::string b = good;
  b[64] = 100;
  reseal_cache_entry(b);
  CacheEntryError error;
  EXPECT_FALSE(decode_cache_entry(b, 7, &error));
  EXPECT_NE(error.detail.find("unknown enumerator"), std::string::npos) << error.detail;
  EXPECT_NE(forged(74, std::uint64_t(1) << 40).find("string bytes cannot fit"), std::string::npos);
}

TEST(DiskCache, WritersAtOnceAgreeAndLeaveNoTemporaryFiles) {
  std::vector<Tree> trees;
  for (int seed = 0; trees.size() < 3 && seed < 20; ++seed)
    if (auto t = random_scene(1300 + seed)) trees.push_back(*t);
  trees.push_back(fixed_scene());
  const fs::path dir = test::temp_dir("disk-race");
  std::vector<MeshResult> scratch;
  for (const Tree& t : trees) scratch.push_back(mesh_tree(t, test::mesh_options(0.12)));
  constexpr int kWriters = 4;
  std::vector<std::vector<MeshResult>> got(kWriters);
  std::vector<std::thread> writers;
  for (int w = 0; w < kWriters; ++w)
    writers.emplace_back([&, w] {
      Process p(dir);
      for (const Tree& t : trees) got[std::size_t(w)].push_back(p.mesh(t));
    });
  for (std::thread& w : writers) w.join();
  for (int w = 0; w < kWriters; ++w)
    for (std::size_t i = 0; i < trees.size(); ++i)
      EXPECT_TRUE(test::same_bytes(*scratch[i].mesh, *got[std::size_t(w)][i].mesh)) << w << " " << i;
  EXPECT_TRUE(files_in(dir, ".partial").empty());
  Process after(dir);
  for (std::size_t i = 0; i < trees.size(); ++i) EXPECT_EQ(reused(after.mesh(trees[i])), scratch[i].nodes.size());
  EXPECT_TRUE(after.warnings.empty());
  fs::remove_all(dir);
}

void set_mtime(const fs::path& file, std::time_t seconds) {
  const struct timespec times[2] = {{seconds, 0}, {seconds, 0}};
  ASSERT_EQ(::utimensat(AT_FDCWD, file.c_str(), times, 0), 0);
}

TEST(DiskCache, TrimRemovesTheLeastRecentlyUsedFilesFirst) {
  const fs::path dir = test::temp_dir("disk-trim");
  auto mesh = std::make_shared<TriangleMesh>();
  mesh->positions.assign(100, dvec3(1));
  const std::string entry = encode_cache_entry(1, CachedJob{mesh, NodeReport{}});
  // The bound counts the blocks a file holds: room for two entries.
  test::write_file(dir / "probe", entry);
  struct stat probe {};
  ASSERT_EQ(::stat((dir / "probe").c_str(), &probe), 0);
  fs::remove(dir / "probe");
  const std::uint64_t held = std::max<std::uint64_t>(std::uint64_t(probe.st_blocks) * 512u, entry.size());
  DiskCache cache(dir, 2 * held, [](const std::string&) {});
  const std::time_t now = std::time(nullptr);
  for (std::uint64_t key = 1; key <= 4; ++key) {
    cache.store(key, CachedJob{mesh, NodeReport{}});
    set_mtime(cache.file_of(key), now - 1000 + std::time_t(key));  // 1 oldest, 4 newest
  }
  ASSERT_TRUE(cache.find(1));  // read: now the newest
  test::write_file(dir / ".tmp-1-0-0000000000000000.partial", "left by a killed process");
  set_mtime(dir / ".tmp-1-0-0000000000000000.partial", now - 7200);
  test::write_file(dir / ".tmp-1-1-0000000000000000.partial", "being written now");
  test::write_file(dir / "notes.txt", "not ours");
  EXPECT_EQ(cache.trim(), 2u);
  EXPECT_TRUE(fs::exists(cache.file_of(1)));
  EXPECT_FALSE(fs::exists(cache.file_of(2)));
  EXPECT_FALSE(fs::exists(cache.file_of(3)));
  EXPECT_TRUE(fs::exists(cache.file_of(4)));
  EXPECT_FALSE(fs::exists(dir / ".tmp-1-0-0000000000000000.partial"));
  EXPECT_TRUE(fs::exists(dir / ".tmp-1-1-0000000000000000.partial"));
  EXPECT_TRUE(fs::exists(dir / "notes.txt"));
  EXPECT_EQ(cache.stats().evicted, 2u);
  fs::remove_all(dir);
}

TEST(DiskCache, AFolderItCannotWriteToCostsAWarningNotTheRun) {
  const Tree t = fixed_scene();
  const fs::path dir = test::temp_dir("disk-blocked");
  const MeshResult scratch = mesh_tree(t, test::mesh_options(0.12));
  {
    Process fill(dir);
    fill.mesh(t);
  }
  // Every entry's name taken by a folder: unreadable, and renames over it fail.
  for (const fs::path& f : files_in(dir, ".htc")) {
    fs::remove(f);
    fs::create_directories(f / "x");
  }
  Process p(dir);
  const MeshResult r = p.mesh(t);
  EXPECT_TRUE(test::same_bytes(*scratch.mesh, *r.mesh));
  EXPECT_EQ(reused(r), 0u);
  EXPECT_EQ(p.disk.stats().ignored[std::size_t(DiskIgnore::Unreadable)], r.nodes.size());
  EXPECT_EQ(p.disk.stats().write_failures, r.nodes.size());
  EXPECT_EQ(p.warnings.size(), r.nodes.size() + 1) << "one per file, one for the writes";
  EXPECT_TRUE(files_in(dir, ".partial").empty());
  fs::remove_all(dir);
}

// The snake of 60 curves, and the same with curve 30's first point moved by 0.01 in x: one
// global job, most of whose bricks and pieces the edit does not reach.
std::pair<Tree, Tree> snake_and_edit() {
  const std::string text = scenes::snake_json(60, 1);
  std::size_t at = 0;
  for (int i = 0; i <= 30; ++i) at = text.find("\"points\": [[", at + 1);
  at += 12;
  char* end = nullptr;
  const double x = std::strtod(text.c_str() + at, &end);
  std::string moved = text;
  moved.replace(at, std::size_t(end - (text.c_str() + at)), std::to_string(x + 0.01));
  return {load_scene_text(text, "."), load_scene_text(moved, ".")};
}

const PolygonizeStats& global_job(const MeshResult& r) {
  for (const NodeReport& e : r.nodes)
    if (e.polygonize.bricks_active > 0) return e.polygonize;
  ADD_FAILURE() << "no global job";
  return r.nodes.front().polygonize;
}

// Every file of one kind ("-b.htc" bricks, "-q.htc" quality pieces, ".htc" alone: jobs).
std::vector<fs::path> entries(const fs::path& dir, const std::string& kind) {
  std::vector<fs::path> out;
  for (const fs::path& f : files_in(dir, ".htc"))
    if (kind == ".htc" ? f.filename().string().size() == 20 : f.filename().string().ends_with(kind)) out.push_back(f);
  return out;
}

TEST(DiskCache, AnEditInsideAGlobalJobTakesItsUnchangedPartsFromDisk) {
  const auto [before, after] = snake_and_edit();
  const MeshResult scratch = mesh_tree(after, test::mesh_options(0.12));
  const fs::path dir = test::temp_dir("disk-parts");
  {
    Process cold(dir);
    cold.mesh(before);
    EXPECT_GT(cold.disk.stats().part_written, 0u);
  }
  const std::size_t bricks = entries(dir, "-b.htc").size(), pieces = entries(dir, "-q.htc").size();
  ASSERT_GT(bricks, 0u);
  ASSERT_GT(pieces, 0u);
  {
    Process warm(dir);
    const MeshResult r = warm.mesh(after);
    EXPECT_TRUE(test::same_bytes(*scratch.mesh, *r.mesh));
    EXPECT_EQ(reused(r), 0u) << "the job itself changed";
    const PolygonizeStats& p = global_job(r);
    EXPECT_GT(p.bricks_reused, p.bricks_active / 2);
    EXPECT_LT(p.bricks_reused, p.bricks_active);
    EXPECT_GT(p.quality.pieces_reused, 0u);
    EXPECT_LT(p.quality.pieces_reused, p.quality.pieces);
    const DiskCacheStats s = warm.disk.stats();
    EXPECT_GE(s.part_hits, p.bricks_reused + p.quality.pieces_reused);
    EXPECT_TRUE(warm.warnings.empty());
  }
  // Damaged parts: a flipped byte in a brick, a truncated piece, a brick whose triangle names a
  // vertex past its own with a good checksum. Each is ignored with a warning and made again;
  // the mesh stays the same. (The jobs' files go, or the job itself would be read.)
  for (const fs::path& f : entries(dir, ".htc")) fs::remove(f);
  const std::vector<fs::path> brick_files = entries(dir, "-b.htc");
  std::string flipped = test::read_file(brick_files[0]);
  flipped[flipped.size() - 5] = char(flipped[flipped.size() - 5] ^ 0x20);
  test::write_file(brick_files[0], flipped);
  const fs::path piece = entries(dir, "-q.htc")[0];
  fs::resize_file(piece, fs::file_size(piece) / 2);
  std::string forged = test::read_file(brick_files[1]);
  std::uint64_t nv = 0, nn = 0, nt = 0;
  std::memcpy(&nv, forged.data() + 49, 8);
  std::memcpy(&nn, forged.data() + 57, 8);
  std::memcpy(&nt, forged.data() + 65, 8);
  ASSERT_GT(nt, 0u);
  const std::uint32_t past = std::uint32_t(nv);
  std::memcpy(forged.data() + 73 + 36 * nv + 16 * nn, &past, 4);
  reseal_cache_entry(forged);
  test::write_file(brick_files[1], forged);
  Process damaged(dir);
  const MeshResult r = damaged.mesh(after);
  EXPECT_TRUE(test::same_bytes(*scratch.mesh, *r.mesh));
  const DiskCacheStats s = damaged.disk.stats();
  EXPECT_EQ(s.ignored[std::size_t(DiskIgnore::Checksum)], 1u);
  EXPECT_EQ(s.ignored[std::size_t(DiskIgnore::Truncated)], 1u);
  EXPECT_EQ(s.ignored[std::size_t(DiskIgnore::Contents)], 1u);
  ASSERT_EQ(damaged.warnings.size(), 3u);
  std::string all;
  for (const std::string& w : damaged.warnings) all += w + "\n";
  EXPECT_NE(all.find(brick_files[0].string() + ": checksum mismatch (corrupt); the brick is extracted again"), std::string::npos) << all;
  EXPECT_NE(all.find(piece.string() + ": truncated"), std::string::npos) << all;
  EXPECT_NE(all.find("names vertex " + std::to_string(nv) + " of " + std::to_string(nv)), std::string::npos) << all;
  EXPECT_GT(global_job(r).bricks_reused, 0u);
  fs::remove_all(dir);
}

// The CLI: --cache twice gives the same file and disk hits; a damaged file and two processes at once.
const char* kScene = R"({"hybridtree": 1, "mesher": {"precision": 0.08}, "root": {"type": "union", "children": [
    {"type": "blend", "children": [{"type": "point", "center": [0,0,0], "radius": 0.8},
                                   {"type": "segment", "a": [0.3,0,0], "b": [1.2,0.2,0], "radius": 0.4}]},
    {"type": "segment", "a": [-1.5,-0.5,0], "b": [-1.5,0.5,0.3], "radius": 0.3}]}})";

nlohmann::json mesh_cli(const fs::path& dir, const std::string& out, const fs::path& cache, std::string* err = nullptr) {
  const fs::path stats = dir / (out + ".json");
  const auto r = test::run_cli("mesh " + (dir / "s.json").string() + " -o " + (dir / out).string() + " --cache " +
                               cache.string() + " --stats-json " + stats.string());
  EXPECT_EQ(r.code, 0) << r.err;
  if (err) *err = r.err;
  return nlohmann::json::parse(test::read_file(stats), nullptr, false);
}

TEST(DiskCache, CliMeshTwiceGivesTheSameFileWithDiskHits) {
  const fs::path dir = test::temp_dir("disk-cli");
  test::write_file(dir / "s.json", kScene);
  const fs::path cache = dir / "made" / "cache";
  const auto plain = test::run_cli("mesh " + (dir / "s.json").string() + " -o " + (dir / "plain.ply").string());
  ASSERT_EQ(plain.code, 0) << plain.err;
  const nlohmann::json first = mesh_cli(dir, "a.ply", cache);
  const nlohmann::json second = mesh_cli(dir, "b.ply", cache);
  EXPECT_EQ(test::read_file(dir / "a.ply"), test::read_file(dir / "plain.ply"));
  EXPECT_EQ(test::read_file(dir / "b.ply"), test::read_file(dir / "plain.ply"));
  const std::size_t jobs = first["nodes"].size();
  EXPECT_EQ(first["cache"]["disk"]["hits"], 0);
  EXPECT_EQ(first["cache"]["disk"]["written"], jobs);
  EXPECT_EQ(second["cache"]["disk"]["hits"], jobs);
  EXPECT_EQ(second["cache"]["disk"]["misses"], 0);
  EXPECT_EQ(second["cache"]["disk"]["written"], 0);
  EXPECT_EQ(second["cache"]["hits"], jobs);
  EXPECT_TRUE(second["cache"]["disk"]["ignored"].empty());
  EXPECT_EQ(second["cache"]["disk"]["parts"]["written"], 0) << "the jobs were read whole: no part ran";
  // A truncated file: one warning line naming it, the same output, the count in the stats.
  const fs::path victim = files_in(cache, ".htc").front();
  fs::resize_file(victim, 20);
  std::string err;
  const nlohmann::json third = mesh_cli(dir, "c.ply", cache, &err);
  EXPECT_EQ(test::read_file(dir / "c.ply"), test::read_file(dir / "plain.ply"));
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_NE(err.find("warning: ignoring cache file " + victim.string() + ": 20 bytes"), std::string::npos) << err;
  EXPECT_EQ(third["cache"]["disk"]["ignored"]["truncated"], 1);
  EXPECT_EQ(third["cache"]["disk"]["hits"], jobs - 1);
  // Not a folder: bad input.
  const auto bad = test::run_cli("mesh " + (dir / "s.json").string() + " -o " + (dir / "d.ply").string() + " --cache " +
                                 (dir / "s.json").string());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("cannot make the cache folder"), std::string::npos) << bad.err;
  fs::remove_all(dir);
}

TEST(DiskCache, CliTwoProcessesAtOnceAgree) {
  const fs::path dir = test::temp_dir("disk-cli-race");
  test::write_file(dir / "s.json", kScene);
  const fs::path cache = dir / "cache";
  std::thread other([&] { mesh_cli(dir, "one.ply", cache); });
  mesh_cli(dir, "two.ply", cache);
  other.join();
  const std::string one = test::read_file(dir / "one.ply");
  EXPECT_FALSE(one.empty());
  EXPECT_EQ(one, test::read_file(dir / "two.ply"));
  EXPECT_TRUE(files_in(cache, ".partial").empty());
  const nlohmann::json after = mesh_cli(dir, "three.ply", cache);
  EXPECT_EQ(after["cache"]["disk"]["hits"], after["nodes"].size());
  EXPECT_EQ(test::read_file(dir / "three.ply"), one);
  fs::remove_all(dir);
}

}  // namespace
