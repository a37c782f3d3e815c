#include "meshers/disk_cache.hpp"

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
#include <type_traits>
#include <vector>

namespace ht {

const std::uint64_t kDiskCacheBuild = HYBRIDTREE_SOURCE_DIGEST;

namespace {

namespace fs = std::filesystem;

constexpr char kMagic[8] = {'H', 'T', 'c', 'a', 'c', 'h', 'e', '\x1a'};
constexpr std::size_t kHeaderBytes = 48;
constexpr std::size_t kSealedBytes = 40;  // the header's bytes before the checksum
constexpr std::uint64_t kChecksumSeed = 0x4854636163686521ull;  // "HTcache!"
constexpr double kStaleTemporarySeconds = 3600.0;

static_assert(std::endian::native == std::endian::little, "cache files are little-endian, written as in memory");
static_assert(sizeof(glm::dvec3) == 24 && sizeof(glm::uvec3) == 12, "positions and triangles are stored as arrays");
// A new report or statistics field must be stored by the field lists below (and
// kDiskCacheLayout bumped): these trip when one is added.
static_assert(sizeof(PolygonizeStats) == 368, "store the new PolygonizeStats field in meshers/disk_cache.cpp");
static_assert(sizeof(LocalStats) == 528, "store the new LocalStats field in meshers/disk_cache.cpp");
static_assert(sizeof(NodeReport) == 1008, "store the new NodeReport field in meshers/disk_cache.cpp");

// The field lists: one per struct, read and written through the same list (Io is Writer or
// Reader; S is const for the writer).
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

constexpr std::uint8_t enum_limit(JobStrategy) { return std::uint8_t(JobStrategy::TrimLocalBlend); }
constexpr std::uint8_t enum_limit(JobReason) { return std::uint8_t(JobReason::Fallback); }

class Writer {
 public:
  std::string out;

  template <class... T>
  void operator()(const T&... values) {
    (put(values), ...);
  }
  void word(std::uint64_t w) { bytes(&w, 8); }
  void bytes(const void* data, std::size_t count) {
    if (count) out.append(static_cast<const char*>(data), count);
  }

 private:
  template <class T>
  void put(const T& v) {
    if constexpr (std::is_same_v<T, bool> || std::is_enum_v<T>) {
      out.push_back(static_cast<char>(v));
    } else if constexpr (std::is_integral_v<T>) {
      word(static_cast<std::uint64_t>(v));
    } else if constexpr (std::is_same_v<T, double>) {
      word(std::bit_cast<std::uint64_t>(v));
    } else if constexpr (std::is_same_v<T, Aabb>) {
      for (const glm::dvec3& c : {v.lo, v.hi}) (*this)(c.x, c.y, c.z);
    } else if constexpr (std::is_same_v<T, std::string>) {
      word(v.size());
      out.append(v);
    } else {
      static_assert(std::is_same_v<T, std::vector<std::string>>);
      word(v.size());
      for (const std::string& s : v) put(s);
    }
  }
};

// Reads what Writer wrote. Every count is checked against the bytes left before anything is
// allocated for it; the first problem is kept in error() and later reads give zeros.
class Reader {
 public:
  explicit Reader(std::string_view in) : in_(in) {}

  template <class... T>
  void operator()(T&... values) {
    (get(values), ...);
  }
  std::uint64_t word() {
    std::uint64_t w = 0;
    bytes(&w, 8);
    return w;
  }
  void bytes(void* data, std::size_t count) {
    if (count > remaining()) {
      fail("the file ends inside its payload");
      return;
    }
    if (count) std::memcpy(data, in_.data() + pos_, count);
    pos_ += count;
  }
  /// False (and the error set) when `count` items of `item_bytes` each cannot fit in what is left.
  bool fits(std::uint64_t count, std::size_t item_bytes, const char* what) {
    if (count <= remaining() / item_bytes) return true;
    fail(std::to_string(count) + " " + what + " cannot fit in the " + std::to_string(remaining()) + " bytes left");
    return false;
  }
  void fail(std::string why) {
    if (error_.empty()) error_ = std::move(why);
    pos_ = in_.size();
  }
  std::size_t remaining() const { return in_.size() - pos_; }
  const std::string& error() const { return error_; }

 private:
  template <class T>
  void get(T& v) {
    if constexpr (std::is_same_v<T, bool> || std::is_enum_v<T>) {
      std::uint8_t b = 0;
      bytes(&b, 1);
      if constexpr (std::is_same_v<T, bool>) {
        if (b > 1) fail("a flag of " + std::to_string(b));
        v = b != 0;
      } else {
        if (b > enum_limit(T{})) fail("an unknown strategy or reason (" + std::to_string(b) + ")");
        v = static_cast<T>(b);
      }
    } else if constexpr (std::is_integral_v<T>) {
      const std::uint64_t w = word();
      v = static_cast<T>(w);
      if (static_cast<std::uint64_t>(v) != w) fail("a count out of range (" + std::to_string(w) + ")");
    } else if constexpr (std::is_same_v<T, double>) {
      v = std::bit_cast<double>(word());
    } else if constexpr (std::is_same_v<T, Aabb>) {
      (*this)(v.lo.x, v.lo.y, v.lo.z, v.hi.x, v.hi.y, v.hi.z);
    } else if constexpr (std::is_same_v<T, std::string>) {
      const std::uint64_t n = word();
      if (!fits(n, 1, "string bytes")) return;
      v.assign(in_.data() + pos_, n);
      pos_ += n;
    } else {
      static_assert(std::is_same_v<T, std::vector<std::string>>);
      const std::uint64_t n = word();
      if (!fits(n, 8, "strings")) return;
      v.resize(n);
      for (std::string& s : v) get(s);
    }
  }

  std::string_view in_;
  std::size_t pos_ = 0;
  std::string error_;
};

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
bool read_mesh(Reader& in, TriangleMesh& m) {
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

// "0123456789abcdef.htc"
bool is_entry_name(const std::string& name) {
  if (name.size() != 20 || !name.ends_with(".htc")) return false;
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

std::string encode_cache_entry(std::uint64_t key, const CachedJob& job) {
  static const TriangleMesh kEmpty;
  const TriangleMesh& m = job.mesh ? *job.mesh : kEmpty;
  Writer w;
  w.bytes(kMagic, sizeof kMagic);
  w.word(std::uint64_t(kDiskCacheLayout));  // u32 layout, u32 zero
  w.word(kDiskCacheBuild);
  w.word(key);
  w.word(0);  // payload bytes
  w.word(0);  // checksum
  w.word(m.positions.size());
  w.word(m.triangles.size());
  w.bytes(m.positions.data(), m.positions.size() * sizeof(glm::dvec3));
  w.bytes(m.triangles.data(), m.triangles.size() * sizeof(glm::uvec3));
  report_fields(w, job.report);
  const std::uint64_t payload = w.out.size() - kHeaderBytes;
  std::memcpy(w.out.data() + 32, &payload, 8);
  reseal_cache_entry(w.out);
  return std::move(w.out);
}

void reseal_cache_entry(std::string& bytes) {
  const std::uint64_t sum = checksum(bytes);
  std::memcpy(bytes.data() + kSealedBytes, &sum, 8);
}

std::optional<CachedJob> decode_cache_entry(std::string_view bytes, std::uint64_t key, CacheEntryError* error) {
  auto fail = [&](DiskIgnore reason, std::string detail) -> std::optional<CachedJob> {
    if (error) *error = CacheEntryError{reason, std::move(detail)};
    return std::nullopt;
  };
  if (bytes.size() < kHeaderBytes)
    return fail(DiskIgnore::Truncated, std::to_string(bytes.size()) + " bytes, shorter than the 48-byte header");
  if (std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0) return fail(DiskIgnore::Magic, "not a HybridTree cache file (bad magic)");
  const std::uint64_t layout = load_word(bytes, 8), build = load_word(bytes, 16);
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
  Reader in(bytes.substr(kHeaderBytes));
  auto mesh = std::make_shared<TriangleMesh>();
  CachedJob job;
  if (read_mesh(in, *mesh)) report_fields(in, job.report);
  if (in.error().empty() && in.remaining()) in.fail(std::to_string(in.remaining()) + " bytes after the report");
  if (!in.error().empty()) return fail(DiskIgnore::Contents, "bad contents: " + in.error());
  job.mesh = std::move(mesh);
  return job;
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

fs::path DiskCache::file_of(std::uint64_t key) const { return dir_ / (hex(key) + ".htc"); }

std::optional<CachedJob> DiskCache::find(std::uint64_t key) {
  const fs::path file = file_of(key);
  std::string bytes, why;
  const ReadStatus status = read_file(file, bytes, why);
  if (status == ReadStatus::Missing) {
    std::lock_guard lock(mutex_);
    ++stats_.misses;
    return std::nullopt;
  }
  if (status == ReadStatus::Failed) {
    ignore(file, {DiskIgnore::Unreadable, "unreadable: " + why});
    return std::nullopt;
  }
  CacheEntryError error;
  std::optional<CachedJob> job = decode_cache_entry(bytes, key, &error);
  if (!job) {
    ignore(file, error);
    return std::nullopt;
  }
  ::utimensat(AT_FDCWD, file.c_str(), nullptr, 0);  // now the most recently used (trim())
  std::lock_guard lock(mutex_);
  ++stats_.hits;
  return job;
}

void DiskCache::ignore(const fs::path& file, const CacheEntryError& error) {
  std::lock_guard lock(mutex_);
  ++stats_.misses;
  ++stats_.ignored[static_cast<std::size_t>(error.reason)];
  if (warned_.insert(file.string()).second)
    warn_("ignoring cache file " + file.string() + ": " + error.detail + "; the job runs instead");
}

std::string DiskCache::temporary_name() {
  return ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter_++) + "-" + hex(nonce_) + ".partial";
}

void DiskCache::store(std::uint64_t key, const CachedJob& job) {
  const std::string bytes = encode_cache_entry(key, job);
  const fs::path tmp = dir_ / temporary_name(), file = file_of(key);
  std::string why;
  if (write_new_file(tmp, bytes, why) && ::rename(tmp.c_str(), file.c_str()) != 0) why = std::strerror(errno);
  std::lock_guard lock(mutex_);
  if (why.empty()) {
    ++stats_.written;
    return;
  }
  ::unlink(tmp.c_str());
  ++stats_.write_failures;
  if (!warned_write_) warn_("cannot write cache file " + file.string() + ": " + why + "; results are not being kept");
  warned_write_ = true;
}

std::size_t DiskCache::trim() {
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
    entries.push_back({path, std::uint64_t(st.st_size), seconds_of(st.st_mtim)});
    total += std::uint64_t(st.st_size);
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

DiskCacheStats DiskCache::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

}  // namespace ht
