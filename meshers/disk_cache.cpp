#include "meshers/disk_cache.hpp"

#include "meshers/cache_bytes.hpp"
#include "meshers/disk_cache_build.hpp"  // generated: HYBRIDTREE_SOURCE_DIGEST (cmake/SourceDigest.cmake)
#include "runtime/subtree_hash.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <random>
#include <system_error>
#include <type_traits>
#include <vector>

namespace ht {

const std::uint64_t kDiskCacheBuild = HYBRIDTREE_SOURCE_DIGEST;

// The largest enumerators a report may hold (CacheReader rejects more).
constexpr std::uint8_t cache_enum_limit(JobStrategy) { return std::uint8_t(JobStrategy::Empty); }
constexpr std::uint8_t cache_enum_limit(JobReason) { return std::uint8_t(JobReason::UnboundedOperand); }

namespace {

namespace fs = std::filesystem;

constexpr char kMagic[8] = {'H', 'T', 'c', 'a', 'c', 'h', 'e', '\x1a'};
constexpr std::size_t kHeaderBytes = 48;
constexpr std::size_t kSealedBytes = 40;  // the header's bytes before the checksum
constexpr std::uint64_t kChecksumSeed = 0x4854636163686521ull;  // "HTcache!"
constexpr double kStaleTemporarySeconds = 3600.0;
constexpr std::size_t kMaxQueuedBytes = std::size_t(256) << 20;  // parts waiting for the writer thread

static_assert(sizeof(glm::dvec3) == 24 && sizeof(glm::uvec3) == 12, "positions and triangles are stored as arrays");
// A new report or statistics field must be stored by the field lists below (and
// kDiskCacheLayout bumped): these trip when one is added.
static_assert(sizeof(PolygonizeStats) == 368, "store the new PolygonizeStats field in meshers/disk_cache.cpp");
static_assert(sizeof(LocalStats) == 528, "store the new LocalStats field in meshers/disk_cache.cpp");
static_assert(sizeof(NodeReport) == 1008, "store the new NodeReport field in meshers/disk_cache.cpp");

// The field lists: one per struct, read and written through the same list (Io is CacheWriter or
// CacheReader; S is const for the writer).
template <class Io, class S>
void polygonize_fields(Io& io, S& p) {
  io(p.bricks_total, p.bricks_active, p.points_evaluated, p.crease_edges, p.corner_vertices, p.crease_candidates,
     p.crease_spread, p.crease_intersections, p.quality_intersections, p.bricks_reused, p.refine_evaluations);
  io(p.unfold.pairs_before, p.unfold.pairs_after, p.unfold.collapses, p.unfold.rounds, p.unfold.seconds);
  io(p.folds.pairs_before, p.folds.pairs_after, p.folds.collapses, p.folds.rounds, p.folds.seconds);
  io(p.snap.merged_vertices, p.snap.removed_triangles, p.snap.skipped_points, p.snap.crease_points);
  io(p.quality.collapses, p.quality.flips, p.quality.splits, p.quality.moved, p.quality.reverted, p.quality.skipped,
     p.quality.seconds, p.quality.pieces, p.quality.pieces_reused, p.quality.retries);
  io(p.seconds_classify, p.seconds_sample, p.seconds_extract, p.seconds_merge, p.seconds_features, p.domain);
}

template <class Io, class S>
void local_fields(Io& io, S& l) {
  io(l.operand_triangles, l.kept_triangles, l.patch_triangles, l.patched, l.patch_precision);
  polygonize_fields(io, l.patch);
  io(l.self_intersections);
  io(l.stitch.boundary_vertices, l.stitch.welded, l.stitch.inserted, l.stitch.fans, l.stitch.left_open,
     l.stitch.largest_gap);
  io(l.bridge.loops, l.bridge.band_triangles, l.bridge.widest, l.bridge.holes_closed);
  io(l.remesh.splits, l.remesh.collapses, l.remesh.flips, l.remesh.sliver_fixes);
}

// Not stored: node (the reusing job's own) and reused (set by the plan).
template <class Io, class R>
void report_fields(Io& io, R& r) {
  io(r.strategy, r.reason, r.rho, r.fallback_cause, r.triangles, r.seconds, r.polygonized);
  polygonize_fields(io, r.polygonize);
  local_fields(io, r.local);
  io(r.edges_split, r.refinements);
}


std::uint64_t load_word(std::string_view bytes, std::size_t at) {
  std::uint64_t w;
  std::memcpy(&w, bytes.data() + at, 8);
  return w;
}

std::uint64_t checksum(std::string_view entry) {
  const std::uint64_t h = hash_bytes(kChecksumSeed, entry.data(), kSealedBytes);
  return hash_bytes(h, entry.data() + kHeaderBytes, entry.size() - kHeaderBytes);
}

std::string hex(std::uint64_t v) {
  char text[17];
  std::snprintf(text, sizeof text, "%016" PRIx64, v);
  return text;
}

// The mesh, its indices checked against its vertices.
bool read_mesh(CacheReader& in, TriangleMesh& m) {
  const std::uint64_t vertices = in.word(), triangles = in.word();
  if (!in.fits(vertices, sizeof(glm::dvec3), "vertices")) return false;
  m.positions.resize(vertices);
  in.bytes(m.positions.data(), vertices * sizeof(glm::dvec3));
  if (!in.fits(triangles, sizeof(glm::uvec3), "triangles")) return false;
  m.triangles.resize(triangles);
  in.bytes(m.triangles.data(), triangles * sizeof(glm::uvec3));
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (int c = 0; c < 3; ++c)
      if (m.triangles[t][c] >= vertices) {
        in.fail("triangle " + std::to_string(t) + " names vertex " + std::to_string(m.triangles[t][c]) + " of " +
                std::to_string(vertices));
        return false;
      }
  return in.error().empty();
}

enum class ReadStatus { Ok, Missing, Failed };

// The whole file into `bytes`; Missing when there is none, Failed with `why` for any other error.
ReadStatus read_file(const fs::path& file, std::string& bytes, std::string& why) {
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    if (errno == ENOENT) return ReadStatus::Missing;
    why = std::strerror(errno);
    return ReadStatus::Failed;
  }
  struct stat st {};
  ReadStatus status = ReadStatus::Ok;
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    why = "not a regular file";
    status = ReadStatus::Failed;
  } else {
    bytes.resize(static_cast<std::size_t>(st.st_size));
    std::size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = ::read(fd, bytes.data() + done, bytes.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) {
        why = std::strerror(errno);
        status = ReadStatus::Failed;
      }
      if (n <= 0) break;
      done += std::size_t(n);
    }
    bytes.resize(done);  // a shorter file than fstat said reads as truncated
  }
  ::close(fd);
  return status;
}

// Creates `file` (which must not exist) with `bytes`; false with `why` on any error.
bool write_new_file(const fs::path& file, std::string_view bytes, std::string& why) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) {
    why = std::strerror(errno);
    return false;
  }
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    done += std::size_t(n);
  }
  if (done < bytes.size()) why = std::strerror(errno ? errno : EIO);
  if (::close(fd) != 0 && why.empty()) why = std::strerror(errno);
  return why.empty();
}

// "0123456789abcdef.htc", or with -b, -q or -c before ".htc"
bool is_entry_name(const std::string& name) {
  if (!name.ends_with(".htc")) return false;
  if (name.size() == 22 && !(name[16] == '-' && (name[17] == 'b' || name[17] == 'q' || name[17] == 'c'))) return false;
  if (name.size() != 20 && name.size() != 22) return false;
  return std::all_of(name.begin(), name.begin() + 16, [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

bool is_temporary_name(const std::string& name) { return name.starts_with(".tmp-") && name.ends_with(".partial"); }

double seconds_of(const struct timespec& t) { return double(t.tv_sec) + 1e-9 * double(t.tv_nsec); }

}  // namespace

const char* to_string(DiskIgnore reason) {
  static constexpr const char* kNames[kDiskIgnoreReasons] = {"magic",    "stale", "truncated", "length",
                                                             "checksum", "key",   "contents",  "unreadable"};
  return kNames[static_cast<std::size_t>(reason)];
}

std::string seal_cache_entry(CacheKind kind, std::uint64_t key, std::string_view payload) {
  CacheWriter w;
  w.bytes(kMagic, sizeof kMagic);
  w.word(std::uint64_t(kDiskCacheLayout) | std::uint64_t(kind) << 32);  // u32 layout, u32 kind
  w.word(kDiskCacheBuild);
  w.word(key);
  w.word(payload.size());
  w.word(0);  // checksum
  w.bytes(payload.data(), payload.size());
  reseal_cache_entry(w.out);
  return std::move(w.out);
}

std::string encode_cache_entry(std::uint64_t key, const CachedJob& job) {
  static const TriangleMesh kEmpty;
  const TriangleMesh& m = job.mesh ? *job.mesh : kEmpty;
  CacheWriter w;
  w.word(m.positions.size());
  w.word(m.triangles.size());
  w.bytes(m.positions.data(), m.positions.size() * sizeof(glm::dvec3));
  w.bytes(m.triangles.data(), m.triangles.size() * sizeof(glm::uvec3));
  report_fields(w, job.report);
  return seal_cache_entry(CacheKind::Job, key, w.out);
}

void reseal_cache_entry(std::string& bytes) {
  const std::uint64_t sum = checksum(bytes);
  std::memcpy(bytes.data() + kSealedBytes, &sum, 8);
}

std::optional<std::string_view> open_cache_entry(std::string_view bytes, CacheKind kind, std::uint64_t key,
                                                 CacheEntryError* error) {
  auto fail = [&](DiskIgnore reason, std::string detail) -> std::optional<std::string_view> {
    if (error) *error = CacheEntryError{reason, std::move(detail)};
    return std::nullopt;
  };
  if (bytes.size() < kHeaderBytes)
    return fail(DiskIgnore::Truncated, std::to_string(bytes.size()) + " bytes, shorter than the 48-byte header");
  if (std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0) return fail(DiskIgnore::Magic, "not a HybridTree cache file (bad magic)");
  const std::uint64_t layout = load_word(bytes, 8) & 0xffffffffu, build = load_word(bytes, 16);
  if (layout != kDiskCacheLayout || build != kDiskCacheBuild)
    return fail(DiskIgnore::Stale, "stale: written by another build (layout " + std::to_string(layout) + ", build " +
                                       hex(build) + "; this is layout " + std::to_string(kDiskCacheLayout) + ", build " +
                                       hex(kDiskCacheBuild) + ")");
  const std::uint64_t payload = load_word(bytes, 32), held = bytes.size() - kHeaderBytes;
  if (payload > held)
    return fail(DiskIgnore::Truncated, "truncated: " + std::to_string(held) + " payload bytes of the " +
                                           std::to_string(payload) + " its header states");
  if (payload < held)
    return fail(DiskIgnore::Length, std::to_string(held) + " payload bytes where its header states " + std::to_string(payload));
  if (checksum(bytes) != load_word(bytes, kSealedBytes)) return fail(DiskIgnore::Checksum, "checksum mismatch (corrupt)");
  if (load_word(bytes, 24) != key) return fail(DiskIgnore::Key, "holds the entry of key " + hex(load_word(bytes, 24)));
  const std::uint64_t held_kind = load_word(bytes, 8) >> 32;
  if (held_kind != std::uint64_t(kind))
    return fail(DiskIgnore::Key, "holds an entry of kind " + std::to_string(held_kind) + ", not " +
                                     std::to_string(std::uint32_t(kind)));
  return bytes.substr(kHeaderBytes);
}

namespace {

// A job's payload: its mesh and report, checked; false with why.
bool decode_job(std::string_view payload, CachedJob& job, std::string& why) {
  CacheReader in(payload);
  auto mesh = std::make_shared<TriangleMesh>();
  if (read_mesh(in, *mesh)) report_fields(in, job.report);
  if (in.error().empty() && in.remaining()) in.fail(std::to_string(in.remaining()) + " bytes after the report");
  why = in.error();
  if (!why.empty()) return false;
  job.mesh = std::move(mesh);
  return true;
}

}  // namespace

std::optional<CachedJob> decode_cache_entry(std::string_view bytes, std::uint64_t key, CacheEntryError* error) {
  const std::optional<std::string_view> payload = open_cache_entry(bytes, CacheKind::Job, key, error);
  if (!payload) return std::nullopt;
  CachedJob job;
  std::string why;
  if (decode_job(*payload, job, why)) return job;
  if (error) *error = CacheEntryError{DiskIgnore::Contents, "bad contents: " + why};
  return std::nullopt;
}

std::size_t DiskCacheStats::ignored_total() const {
  std::size_t n = 0;
  for (std::size_t c : ignored) n += c;
  return n;
}

DiskCacheStats operator-(const DiskCacheStats& a, const DiskCacheStats& b) {
  DiskCacheStats d;
  d.hits = a.hits - b.hits;
  d.misses = a.misses - b.misses;
  d.written = a.written - b.written;
  d.part_hits = a.part_hits - b.part_hits;
  d.part_misses = a.part_misses - b.part_misses;
  d.part_written = a.part_written - b.part_written;
  d.write_failures = a.write_failures - b.write_failures;
  d.evicted = a.evicted - b.evicted;
  for (std::size_t i = 0; i < kDiskIgnoreReasons; ++i) d.ignored[i] = a.ignored[i] - b.ignored[i];
  return d;
}

DiskCache::DiskCache(fs::path dir, std::uint64_t max_bytes, Warn warn)
    : dir_(std::move(dir)), max_bytes_(max_bytes), warn_(std::move(warn)), nonce_(std::random_device{}()) {
  if (!warn_) warn_ = [](const std::string& line) { std::fprintf(stderr, "hybridtree: warning: %s\n", line.c_str()); };
  std::error_code ec, ec_dir;
  fs::create_directories(dir_, ec);
  if (!fs::is_directory(dir_, ec_dir))
    throw DiskCacheError(dir_.string() + ": cannot make the cache folder" + (ec ? ": " + ec.message() : ""));
}

fs::path DiskCache::file_of(std::uint64_t key, CacheKind kind) const {
  static constexpr const char* kSuffix[kCacheKinds] = {".htc", "-b.htc", "-q.htc", "-c.htc"};
  return dir_ / (hex(key) + kSuffix[static_cast<std::size_t>(kind)]);
}

bool DiskCache::read_entry(std::uint64_t key, CacheKind kind, std::string& bytes) {
  const fs::path file = file_of(key, kind);
  std::string why;
  const ReadStatus status = read_file(file, bytes, why);
  if (status == ReadStatus::Ok) return true;
  if (status == ReadStatus::Failed) {
    ignore(file, {DiskIgnore::Unreadable, "unreadable: " + why}, kind);
    return false;
  }
  std::lock_guard lock(mutex_);
  ++(kind == CacheKind::Job ? stats_.misses : stats_.part_misses);
  return false;
}

std::optional<CachedJob> DiskCache::find(std::uint64_t key) {
  CachedJob job;
  if (!find_entry(CacheKind::Job, key, [&](std::string_view payload, std::string& why) { return decode_job(payload, job, why); }))
    return std::nullopt;
  return job;
}

bool DiskCache::find_part(CacheKind kind, std::uint64_t key,
                          const std::function<bool(std::string_view payload, std::string& why)>& decode) {
  return find_entry(kind, key, decode);
}

bool DiskCache::find_entry(CacheKind kind, std::uint64_t key,
                           const std::function<bool(std::string_view payload, std::string& why)>& decode) {
  std::string bytes;
  if (!read_entry(key, kind, bytes)) return false;
  const fs::path file = file_of(key, kind);
  CacheEntryError error;
  const std::optional<std::string_view> payload = open_cache_entry(bytes, kind, key, &error);
  std::string why;
  if (!payload || !decode(*payload, why)) {
    ignore(file, payload ? CacheEntryError{DiskIgnore::Contents, "bad contents: " + why} : error, kind);
    return false;
  }
  ::utimensat(AT_FDCWD, file.c_str(), nullptr, 0);  // now the most recently used (trim())
  std::lock_guard lock(mutex_);
  ++(kind == CacheKind::Job ? stats_.hits : stats_.part_hits);
  return true;
}

void DiskCache::ignore(const fs::path& file, const CacheEntryError& error, CacheKind kind) {
  static constexpr const char* kAfter[kCacheKinds] = {"the job runs instead", "the brick is extracted again",
                                                      "the quality piece is improved again",
                                                      "the region is searched again"};
  std::lock_guard lock(mutex_);
  ++(kind == CacheKind::Job ? stats_.misses : stats_.part_misses);
  ++stats_.ignored[static_cast<std::size_t>(error.reason)];
  // After a rebuild every file is stale: the first is named, the rest are counted only.
  if (error.reason == DiskIgnore::Stale && warned_stale_) return;
  if (!warned_.insert(file.string()).second) return;
  std::string line = "ignoring cache file " + file.string() + ": " + error.detail + "; " + kAfter[static_cast<std::size_t>(kind)];
  if (error.reason == DiskIgnore::Stale) line += " (other stale files are ignored without a warning)";
  warned_stale_ |= error.reason == DiskIgnore::Stale;
  warn_(line);
}

std::string DiskCache::temporary_name() {
  return ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter_++) + "-" + hex(nonce_) + ".partial";
}

bool DiskCache::write_entry(const fs::path& file, std::string_view bytes) {
  const fs::path tmp = dir_ / temporary_name();
  std::string why;
  if (write_new_file(tmp, bytes, why) && ::rename(tmp.c_str(), file.c_str()) != 0) why = std::strerror(errno);
  if (why.empty()) return true;
  ::unlink(tmp.c_str());
  std::lock_guard lock(mutex_);
  ++stats_.write_failures;
  if (!warned_write_) warn_("cannot write cache file " + file.string() + ": " + why + "; results are not being kept");
  warned_write_ = true;
  return false;
}

void DiskCache::store(std::uint64_t key, const CachedJob& job) {
  if (!write_entry(file_of(key), encode_cache_entry(key, job))) return;
  std::lock_guard lock(mutex_);
  ++stats_.written;
}

void DiskCache::store_part(CacheKind kind, std::uint64_t key, std::string payload) {
  {
    std::unique_lock lock(queue_mutex_);
    if (!writer_.joinable() && !no_writer_) {
      try {
        writer_ = std::thread([this] { write_queued(); });
      } catch (const std::system_error&) {
        no_writer_ = true;  // no thread to be had: the callers write
      }
    }
    if (writer_.joinable()) {
      // Past the bound the caller waits for room: writing itself could put a part on disk before
      // an older one of its key still queued.
      queue_room_.wait(lock, [&] { return queued_bytes_ == 0 || queued_bytes_ + payload.size() <= kMaxQueuedBytes; });
      queued_bytes_ += payload.size();
      queue_.push_back({kind, key, std::move(payload)});
      queue_wake_.notify_one();
      return;
    }
  }
  write_part(kind, key, payload);
}

void DiskCache::write_part(CacheKind kind, std::uint64_t key, std::string_view payload) {
  if (!write_entry(file_of(key, kind), seal_cache_entry(kind, key, payload))) return;
  std::lock_guard lock(mutex_);
  ++stats_.part_written;
}

void DiskCache::write_queued() {
  std::unique_lock lock(queue_mutex_);
  for (;;) {
    queue_wake_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
    if (queue_.empty()) return;  // stopping, all written
    Queued next = std::move(queue_.front());
    queue_.pop_front();
    writing_ = true;
    lock.unlock();
    try {
      write_part(next.kind, next.key, next.payload);
    } catch (...) {  // out of memory, or a warning callback that threw: the part is not kept
      std::lock_guard counts(mutex_);
      ++stats_.write_failures;
    }
    lock.lock();
    queued_bytes_ -= next.payload.size();
    writing_ = false;
    queue_room_.notify_all();
    if (queue_.empty()) queue_idle_.notify_all();
  }
}

void DiskCache::flush() {
  std::unique_lock lock(queue_mutex_);
  queue_idle_.wait(lock, [this] { return queue_.empty() && !writing_; });
}

DiskCache::~DiskCache() {
  {
    std::lock_guard lock(queue_mutex_);
    stopping_ = true;
  }
  queue_wake_.notify_all();
  if (writer_.joinable()) writer_.join();
}

std::size_t DiskCache::trim() {
  flush();
  struct Entry {
    fs::path file;
    std::uint64_t bytes;
    double mtime;
  };
  std::vector<Entry> entries;
  std::uint64_t total = 0;
  const double now = double(std::time(nullptr));
  std::error_code ec;
  for (fs::directory_iterator it(dir_, ec), end; !ec && it != end; it.increment(ec)) {
    const fs::path& path = it->path();
    const std::string name = path.filename().string();
    struct stat st {};
    if (::lstat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) continue;
    if (is_temporary_name(name) && now - seconds_of(st.st_mtim) > kStaleTemporarySeconds) ::unlink(path.c_str());
    if (!is_entry_name(name)) continue;
    // Blocks held, not bytes: most parts are smaller than a block.
    const std::uint64_t held = std::max<std::uint64_t>(std::uint64_t(st.st_blocks) * 512u, std::uint64_t(st.st_size));
    entries.push_back({path, held, seconds_of(st.st_mtim)});
    total += held;
  }
  std::sort(entries.begin(), entries.end(),
            [](const Entry& a, const Entry& b) { return a.mtime != b.mtime ? a.mtime < b.mtime : a.file < b.file; });
  std::size_t removed = 0;
  for (const Entry& e : entries) {
    if (total <= max_bytes_) break;
    if (::unlink(e.file.c_str()) == 0) ++removed;
    total -= e.bytes;  // gone either way (another process may have removed it)
  }
  std::lock_guard lock(mutex_);
  stats_.evicted += removed;
  return removed;
}

DiskCacheStats DiskCache::stats() {
  flush();
  std::lock_guard lock(mutex_);
  return stats_;
}

}  // namespace ht
