// The node-result cache of incremental re-meshing (issue 15): a mesh job's output mesh and
// report, keyed by the job's content key (meshers/mesh_plan.cpp: the subtree hash of
// runtime/subtree_hash.hpp, the job's strategy and reason, its inputs' keys, and every mesh
// option that changes output). A job whose key is present does not run; its result is reused.
//
// Bounded in bytes: half the bound for job results (24 per vertex + 12 per triangle of the
// cached meshes, plus a fixed entry overhead), half for the parts of global polygonizations
// (pieces(), meshers/piece_cache.hpp); each half evicts its least-recently-used entries (an
// entry larger than its half is not kept). Thread-safe: find() and insert() may be called from
// any job of any run at once. Meshes are shared, immutable (shared_ptr<const>): an evicted entry
// stays alive while a run still holds it.
//
// Given a DiskCache (meshers/disk_cache.hpp), it is the first of two levels: a miss in memory
// looks on disk (a hit there enters memory), and every insert is written through to disk; the
// parts of polygonizations too (pieces()).
#pragma once

#include "meshers/mesh_plan.hpp"
#include "meshers/piece_cache.hpp"

#include <cstdint>
#include <optional>

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

/// Hits, misses, insertions, evictions, entries and bytes, as a PieceCache counts them.
using NodeCacheStats = PieceCacheStats;

class DiskCache;

/// Job results in one least-recently-used store, parts of polygonizations in another.
class NodeCache {
 public:
  /// Half of `max_bytes` holds job results, half the parts of polygonizations (pieces()).
  /// `disk`, when given, is the second level of job results and parts (not owned; it must outlive
  /// this cache).
  explicit NodeCache(std::size_t max_bytes, DiskCache* disk = nullptr)
      : jobs_(max_bytes - max_bytes / 2), pieces_(max_bytes / 2), disk_(disk) {
    pieces_.set_disk(disk);
  }
  NodeCache(const NodeCache&) = delete;
  NodeCache& operator=(const NodeCache&) = delete;

  /// The entry under `key`, now most recently used; counts a hit or a miss (in memory). On a
  /// miss, the disk level's entry if it has one, now in memory too (the disk counts that hit).
  std::optional<CachedJob> find(std::uint64_t key);
  /// Stores (or refreshes) `key`, then evicts LRU entries until the bound holds; writes it to
  /// the disk level too (even an entry larger than the bound, which memory does not keep).
  void insert(std::uint64_t key, CachedJob value);
  /// The job results' store, in memory (pieces() counts its own).
  NodeCacheStats stats() const { return jobs_.stats(); }
  std::size_t max_bytes() const { return jobs_.max_bytes() + pieces_.max_bytes(); }
  DiskCache* disk() const { return disk_; }
  /// Empties memory (not the disk level).
  void clear();

  /// The bytes an entry is charged.
  static std::size_t entry_bytes(const CachedJob& value);

  /// Bricks and quality-pass pieces of the global polygonizations the jobs ran
  /// (PolygonizeOptions::pieces): a job whose subtree changed re-runs, but its polygonization
  /// takes what did not change from here. Thread-safe as the node cache is.
  PieceCache& pieces() { return pieces_; }
  const PieceCache& pieces() const { return pieces_; }

 private:
  void keep(std::uint64_t key, CachedJob value);  // into memory only
  PieceCache jobs_, pieces_;
  DiskCache* disk_;
};

}  // namespace ht
