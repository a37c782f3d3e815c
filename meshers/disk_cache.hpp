// The on-disk level of the node-result cache (issue 15): `hybridtree mesh --cache DIR` keeps
// mesh jobs' results between runs. A NodeCache (meshers/node_cache.hpp) given a DiskCache looks
// here on a miss in memory and writes every new result through to here.
//
// One file per job key, DIR/<key as 16 lowercase hex digits>.htc, little-endian:
//   header (48 bytes)  magic "HTcache\x1a", u32 layout version (kDiskCacheLayout), u32 zero,
//                      u64 build digest (kDiskCacheBuild: the library's sources, compiler,
//                      build type and flags; any change to them makes every file stale), u64 key,
//                      u64 payload bytes, u64 checksum (of the header's first 40 bytes and the
//                      payload, runtime/subtree_hash.hpp hash_bytes)
//   payload            u64 vertices V, u64 triangles T, V x 3 doubles (bit for bit), T x 3 u32,
//                      then the NodeReport (strategy, reason, rho, fallback cause, the
//                      polygonizer's and the local strategy's statistics, edges split,
//                      refinements): numbers 8 bytes, flags and enums 1 byte, strings as u64
//                      length + bytes, lists as u64 count + items
//
// Writes are atomic: each goes to a temporary file of its own in DIR (".tmp-PID-N-RANDOM.partial",
// O_EXCL) and is renamed over the final name, so a reader sees the old file, the new one or none,
// never part of one, with any number of processes writing at once (two writers of one key write
// the same bytes). No fsync: a file torn by a power cut fails its length or checksum test
// and is ignored like any corrupt one.
//
// A file that is not one this build wrote for its key is ignored, with one warning naming the
// file and what was wrong, and the job runs (its result then replaces the file): bad magic,
// another layout or build (stale), shorter than its header or its stated payload (truncated), a
// length that disagrees with the header, a checksum mismatch, a key that is not the name's, or
// contents out of range (counts past the file's end, indices past the vertices, unknown
// strategies). Nothing read from a file is trusted before it is checked against the file's length.
//
// trim() bounds the folder: files are least-recently used by modification time, which a hit
// refreshes; the oldest go first. Temporary files left by a killed process go after an hour.
#pragma once

#include "meshers/node_cache.hpp"

#include <array>
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <mutex>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>

namespace ht {

/// The file layout's version; bump it when the layout above changes.
inline constexpr std::uint32_t kDiskCacheLayout = 7;
/// The build's digest (generated at build time from the library's sources): results written by
/// another build are stale, since any change to a mesher may change what a job makes.
extern const std::uint64_t kDiskCacheBuild;

/// Why a cache file was ignored.
enum class DiskIgnore : std::uint8_t { Magic, Stale, Truncated, Length, Checksum, Key, Contents, Unreadable };
inline constexpr std::size_t kDiskIgnoreReasons = 8;
/// "magic", "stale", "truncated", "length", "checksum", "key", "contents", "unreadable".
const char* to_string(DiskIgnore reason);

struct DiskCacheStats {
  std::size_t hits = 0, misses = 0;      ///< finds answered from a file, and not (no file, or ignored)
  std::size_t written = 0, write_failures = 0;
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

  /// The entry under `key`, or nullopt (no file: a miss; a bad file: a miss, a warning and a
  /// count in stats().ignored). A hit refreshes the file's modification time.
  std::optional<CachedJob> find(std::uint64_t key);
  /// Writes the entry atomically (see above). A failure (a full disk, no permission) is counted,
  /// warned about once per DiskCache and otherwise ignored.
  void store(std::uint64_t key, const CachedJob& job);
  /// Removes least-recently-used entry files until those left take at most max_bytes, and
  /// temporary files older than an hour; returns the entry files removed.
  std::size_t trim();

  DiskCacheStats stats() const;
  const std::filesystem::path& dir() const { return dir_; }
  std::uint64_t max_bytes() const { return max_bytes_; }
  /// DIR/<16 hex digits>.htc
  std::filesystem::path file_of(std::uint64_t key) const;

 private:
  void ignore(const std::filesystem::path& file, const CacheEntryError& error);
  std::string temporary_name();

  std::filesystem::path dir_;
  std::uint64_t max_bytes_;
  Warn warn_;
  mutable std::mutex mutex_;  // stats_, warned_
  DiskCacheStats stats_;
  std::set<std::string> warned_;  // files already warned about
  bool warned_write_ = false;
  std::atomic<std::uint64_t> counter_{0};
  std::uint64_t nonce_;  // random, per DiskCache: temporary names differ across processes with one PID
};

}  // namespace ht
