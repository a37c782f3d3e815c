// The node-result cache of incremental re-meshing (issue 15): a mesh job's output mesh and
// report, keyed by the job's content key (meshers/mesh_plan.cpp: the subtree hash of
// runtime/subtree_hash.hpp, the job's strategy and reason, its inputs' keys, and every mesh
// option that changes output). A job whose key is present does not run; its result is reused.
//
// Bounded in bytes (24 per vertex + 12 per triangle of the cached meshes, plus a fixed entry
// overhead); inserting past the bound evicts least-recently-used entries (an entry larger than
// the bound is not kept). Thread-safe: one mutex; find() and insert() may be called from any
// job of any run at once. Meshes are shared, immutable (shared_ptr<const>): an evicted entry
// stays alive while a run still holds it.
//
// Given a DiskCache (meshers/disk_cache.hpp), it is the first of two levels: a miss in memory
// looks on disk (a hit there enters memory), and every insert is written through to disk.
#pragma once

#include "meshers/mesh_plan.hpp"

#include <cstdint>
#include <list>
#include <mutex>
#include <optional>
#include <unordered_map>

namespace ht {

/// The hash of every MeshOptions field that changes a job's output: precision, strategy,
/// blend_overlap, remesh_seams and the polygonizer's refinement, snapping, sharp-feature,
/// quality and clip settings (not its budget, progress or cancel, which change whether a run
/// ends, not what it makes). Bit for bit on doubles.
std::uint64_t mesh_options_hash(const MeshOptions& options);

struct CachedJob {
  std::shared_ptr<const TriangleMesh> mesh;
  NodeReport report;
};

struct NodeCacheStats {
  std::size_t hits = 0, misses = 0, insertions = 0, evictions = 0;
  std::size_t entries = 0, bytes = 0;
};

class DiskCache;

class NodeCache {
 public:
  /// `disk`, when given, is the second level (not owned; it must outlive this cache).
  explicit NodeCache(std::size_t max_bytes, DiskCache* disk = nullptr) : max_bytes_(max_bytes), disk_(disk) {}
  NodeCache(const NodeCache&) = delete;
  NodeCache& operator=(const NodeCache&) = delete;

  /// The entry under `key`, now most recently used; counts a hit or a miss (in memory). On a
  /// miss, the disk level's entry if it has one, now in memory too (the disk counts that hit).
  std::optional<CachedJob> find(std::uint64_t key);
  /// Stores (or refreshes) `key`, then evicts LRU entries until the bound holds; writes it to
  /// the disk level too (even an entry larger than the bound, which memory does not keep).
  void insert(std::uint64_t key, CachedJob value);
  NodeCacheStats stats() const;
  std::size_t max_bytes() const { return max_bytes_; }
  DiskCache* disk() const { return disk_; }
  /// Empties memory (not the disk level).
  void clear();

  /// The bytes an entry is charged.
  static std::size_t entry_bytes(const CachedJob& value);

 private:
  struct Entry {
    std::uint64_t key;
    CachedJob value;
    std::size_t bytes;
  };
  void keep(std::uint64_t key, CachedJob value);
  void evict_locked();

  std::size_t max_bytes_;
  DiskCache* disk_;
  mutable std::mutex mutex_;
  std::list<Entry> lru_;  // front: most recently used
  std::unordered_map<std::uint64_t, std::list<Entry>::iterator> index_;
  NodeCacheStats stats_;
};

}  // namespace ht
