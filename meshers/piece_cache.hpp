// Content-addressed results of the global polygonizer's parts, kept across runs (issue 15): a
// brick's extraction (meshers/polygonize_reuse.hpp) and a piece of the quality pass
// (meshers/quality.hpp). Each is keyed by a hash of everything it reads: its input bytes, the
// options, and the tapes of the field where it may evaluate it. A part whose key is present does
// not run; since a part is a deterministic function of what its key covers, the mesh is the same,
// byte for byte, as when every part runs.
//
// Bounded in bytes (the size each value is charged when inserted); inserting past the bound
// evicts least-recently-used entries, and a value larger than the bound is not kept. Values are
// immutable and shared: an evicted one stays alive while a run still holds it. Thread-safe: one
// mutex around the index; find() and insert() may be called from any thread at once.
//
// Values are typed: find<T>() returns null for a key stored under another type, so that two
// kinds of parts can never be confused even if their keys collide.
#pragma once

#include <cstddef>
#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <unordered_map>

namespace ht {

class DiskCache;

struct PieceCacheStats {
  std::size_t hits = 0, misses = 0, insertions = 0, evictions = 0;
  std::size_t entries = 0, bytes = 0;
};

class PieceCache {
 public:
  explicit PieceCache(std::size_t max_bytes) : max_bytes_(max_bytes) {}
  PieceCache(const PieceCache&) = delete;
  PieceCache& operator=(const PieceCache&) = delete;

  /// The value stored under `key` as a T (now most recently used), or null; counts a hit or a miss.
  template <class T>
  std::shared_ptr<const T> find(std::uint64_t key) {
    return std::static_pointer_cast<const T>(find_typed(key, type_id<T>()));
  }
  /// Stores (or replaces) `key`, charged `bytes`, then evicts until the bound holds.
  template <class T>
  void insert(std::uint64_t key, std::shared_ptr<const T> value, std::size_t bytes) {
    insert_typed(key, std::move(value), type_id<T>(), bytes);
  }

  PieceCacheStats stats() const;
  std::size_t max_bytes() const { return max_bytes_; }
  void clear();

  /// The disk level of the parts (not owned; it must outlive this cache), or null: the parts'
  /// owners read a part missing here from it and write new ones through to it
  /// (meshers/polygonize_reuse.hpp find_kept, keep; meshers/quality_pieces.cpp).
  void set_disk(DiskCache* disk) { disk_ = disk; }
  DiskCache* disk() const { return disk_; }

 private:
  template <class T>
  static const void* type_id() {
    static const char id = 0;
    return &id;
  }
  std::shared_ptr<const void> find_typed(std::uint64_t key, const void* type);
  void insert_typed(std::uint64_t key, std::shared_ptr<const void> value, const void* type, std::size_t bytes);

  struct Entry {
    std::uint64_t key;
    std::shared_ptr<const void> value;
    const void* type;
    std::size_t bytes;
  };
  std::size_t max_bytes_;
  DiskCache* disk_ = nullptr;
  mutable std::mutex mutex_;
  std::list<Entry> lru_;  // front: most recently used
  std::unordered_map<std::uint64_t, std::list<Entry>::iterator> index_;
  PieceCacheStats stats_;
};

}  // namespace ht
