// The on-disk level of the node-result cache (issue 15): `hybridtree mesh --cache DIR` keeps
// mesh jobs' results between runs, and the parts of global polygonizations (bricks' extractions,
// quality-pass pieces: meshers/piece_cache.hpp) with them, so that a run after an edit inside a
// globally polygonized subtree takes the bricks and pieces the edit did not reach, as a Session
// does in memory. A NodeCache (meshers/node_cache.hpp) given a DiskCache looks here on a miss in
// memory and writes every new result and part through to here.
//
// One file per entry, DIR/<key as 16 lowercase hex digits>.htc for a job's result, -b.htc for a
// brick, -q.htc for a quality piece, -c.htc for a region found free of self-intersections (an
// empty payload); little-endian:
//   header (48 bytes)  magic "HTcache\x1a", u32 layout version (kDiskCacheLayout), u32 kind
//                      (CacheKind), u64 build digest (kDiskCacheBuild: the library's sources,
//                      compiler, build type and flags; any change to them makes every file
//                      stale), u64 key, u64 payload bytes, u64 checksum (of the header's first 40
//                      bytes and the payload, runtime/subtree_hash.hpp hash_bytes)
//   payload (a job)    u64 vertices V, u64 triangles T, V x 3 doubles (bit for bit), T x 3 u32,
//                      then the NodeReport (strategy, reason, rho, fallback cause, the
//                      polygonizer's and the local strategy's statistics, edges split,
//                      refinements): numbers 8 bytes, flags and enums 1 byte, strings as u64
//                      length + bytes, lists as u64 count + items
//   payload (a part)   meshers/cache_parts.hpp's encoding, checked when read back
//
// Writes are atomic: each goes to a temporary file of its own in DIR (".tmp-PID-N-RANDOM.partial",
// O_EXCL) and is renamed over the final name, so a reader sees the old file, the new one or none,
// never part of one, with any number of processes writing at once (two writers of one key write
// the same bytes). No fsync: a file torn by a power cut fails its length or checksum test
// and is ignored like any corrupt one.
//
// A file that is not one this build wrote for its key and kind is ignored, with one warning
// naming the file and what was wrong (for stale files, the first only: after a rebuild all are),
// and the job or part is made again (it then replaces the file): bad magic, another layout or build (stale), shorter than its header or its stated
// payload (truncated), a length that disagrees with the header, a checksum mismatch, a key or
// kind that is not the name's, or contents out of range (counts past the file's end, indices past
// the vertices, unknown strategies). Nothing read from a file is trusted before it is checked
// against the file's length.
//
// trim() bounds the folder: files are least-recently used by modification time, which a hit
// refreshes; the oldest go first. Temporary files left by a killed process go after an hour.
#pragma once

#include "meshers/node_cache.hpp"

#include <array>
#include <atomic>
#include <condition_variable>
#include <deque>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <mutex>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>
#include <utility>

namespace ht {

/// The file layout's version; bump it when the layout above changes.
inline constexpr std::uint32_t kDiskCacheLayout = 8;
/// The build's digest (generated at build time from the library's sources): results written by
/// another build are stale, since any change to a mesher may change what a job makes.
extern const std::uint64_t kDiskCacheBuild;

/// What a cache file holds.
enum class CacheKind : std::uint32_t { Job = 0, Brick = 1, QualityPiece = 2, CleanRegion = 3 };
inline constexpr std::uint32_t kCacheKinds = 4;

/// Why a cache file was ignored.
enum class DiskIgnore : std::uint8_t { Magic, Stale, Truncated, Length, Checksum, Key, Contents, Unreadable };
inline constexpr std::size_t kDiskIgnoreReasons = 8;
/// "magic", "stale", "truncated", "length", "checksum", "key", "contents", "unreadable".
const char* to_string(DiskIgnore reason);

struct DiskCacheStats {
  std::size_t hits = 0, misses = 0;      ///< job results found in a file, and not (no file, or ignored)
  std::size_t written = 0, write_failures = 0;  ///< job results written; failed writes of anything
  std::size_t part_hits = 0, part_misses = 0, part_written = 0;  ///< the same for bricks and pieces
  std::size_t evicted = 0;               ///< files trim() removed
  std::array<std::size_t, kDiskIgnoreReasons> ignored{};  ///< files ignored, by DiskIgnore
  std::size_t ignored_total() const;
};
/// What `after` counted since `before` (stats of one run).
DiskCacheStats operator-(const DiskCacheStats& after, const DiskCacheStats& before);

/// Thrown when the cache folder cannot be made or is not a folder.
struct DiskCacheError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// What decode_cache_entry found wrong.
struct CacheEntryError {
  DiskIgnore reason = DiskIgnore::Contents;
  std::string detail;  ///< e.g. "checksum mismatch", "written by another build"
};

/// The file's bytes for `job` under `key`.
std::string encode_cache_entry(std::uint64_t key, const CachedJob& job);
/// A file's bytes: the header for `kind` and `key`, then `payload`.
std::string seal_cache_entry(CacheKind kind, std::uint64_t key, std::string_view payload);
/// The payload of `bytes` if they are a whole, intact entry of this build for `kind` and `key`;
/// else nullopt and *error says why. A view into `bytes`.
std::optional<std::string_view> open_cache_entry(std::string_view bytes, CacheKind kind, std::uint64_t key,
                                                 CacheEntryError* error);
/// The job in `bytes` if they are a whole, intact entry of this build for `key`; else nullopt and
/// *error says why. Reads nothing past bytes.size(); allocates only what the length allows.
std::optional<CachedJob> decode_cache_entry(std::string_view bytes, std::uint64_t key, CacheEntryError* error);
/// Recomputes an entry's checksum in place (bytes.size() >= 48): for tests that forge entries.
void reseal_cache_entry(std::string& bytes);

class DiskCache {
 public:
  /// Receives one line (no newline) per ignored file and per first failed write.
  using Warn = std::function<void(const std::string&)>;
  /// Creates `dir` (and its parents) if missing; throws DiskCacheError when it cannot. `warn`
  /// defaults to "hybridtree: warning: LINE" on stderr.
  explicit DiskCache(std::filesystem::path dir, std::uint64_t max_bytes = std::uint64_t(1) << 30, Warn warn = {});
  DiskCache(const DiskCache&) = delete;
  DiskCache& operator=(const DiskCache&) = delete;
  /// Finishes the parts' writes (flush()).
  ~DiskCache();

  /// The entry under `key`, or nullopt (no file: a miss; a bad file: a miss, a warning and a
  /// count in stats().ignored). A hit refreshes the file's modification time.
  std::optional<CachedJob> find(std::uint64_t key);
  /// Writes the entry atomically (see above). A failure (a full disk, no permission) is counted,
  /// warned about once per DiskCache and otherwise ignored.
  void store(std::uint64_t key, const CachedJob& job);
  /// Reads the part of `kind` under `key`: `decode` gets its payload (checked as an entry) and
  /// returns false, with why, when the payload is not one it wrote (the file is then ignored
  /// like any bad one). True when decode took it. Counted in part_hits / part_misses.
  bool find_part(CacheKind kind, std::uint64_t key,
                 const std::function<bool(std::string_view payload, std::string& why)>& decode);
  /// Writes a part atomically, as store() does, but on a thread of its own while the caller goes
  /// on: a cold run of a fine polygonization writes hundreds of parts, which written in place
  /// cost it about a fifth of its time. At most 256 MiB wait; past that the caller waits for
  /// room. (Where no thread can be started, the caller writes.) So the warning callback may be
  /// called from that thread until flush() returns.
  void store_part(CacheKind kind, std::uint64_t key, std::string payload);
  /// Waits until every part handed to store_part() is written (or failed).
  void flush();
  /// Removes least-recently-used entry files until those left take at most max_bytes (the blocks
  /// they hold), and
  /// temporary files older than an hour; returns the entry files removed. Flushes first.
  std::size_t trim();

  /// The counts so far, the parts' writes flushed first.
  DiskCacheStats stats();
  const std::filesystem::path& dir() const { return dir_; }
  std::uint64_t max_bytes() const { return max_bytes_; }
  /// DIR/<16 hex digits>.htc, or -b.htc, -q.htc, -c.htc for parts
  std::filesystem::path file_of(std::uint64_t key, CacheKind kind = CacheKind::Job) const;

 private:
  void ignore(const std::filesystem::path& file, const CacheEntryError& error, CacheKind kind);
  std::string temporary_name();
  // The bytes of the file of (key, kind): true when read; else counts a miss (of `kind`), after
  // ignoring an unreadable file.
  bool read_entry(std::uint64_t key, CacheKind kind, std::string& bytes);
  // The entry of (key, kind) read, checked and given to decode; a bad one ignored. Counts a hit.
  bool find_entry(CacheKind kind, std::uint64_t key,
                  const std::function<bool(std::string_view payload, std::string& why)>& decode);
  bool write_entry(const std::filesystem::path& file, std::string_view bytes);  // counts failures

  std::filesystem::path dir_;
  std::uint64_t max_bytes_;
  Warn warn_;
  mutable std::mutex mutex_;  // stats_, warned_
  DiskCacheStats stats_;
  std::set<std::string> warned_;  // files already warned about
  bool warned_write_ = false;
  bool warned_stale_ = false;  // one warning for all the files of another build
  std::atomic<std::uint64_t> counter_{0};
  // The parts waiting to be written, and the thread that writes them (started on the first).
  std::mutex queue_mutex_;
  std::condition_variable queue_wake_, queue_idle_, queue_room_;
  struct Queued {
    CacheKind kind;
    std::uint64_t key;
    std::string payload;
  };
  std::deque<Queued> queue_;
  std::size_t queued_bytes_ = 0;
  bool writing_ = false, stopping_ = false, no_writer_ = false;
  std::thread writer_;
  void write_queued();
  void write_part(CacheKind kind, std::uint64_t key, std::string_view payload);
  std::uint64_t nonce_;  // random, per DiskCache: temporary names differ across processes with one PID
};

}  // namespace ht
