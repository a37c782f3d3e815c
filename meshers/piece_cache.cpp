#include "meshers/piece_cache.hpp"

namespace ht {

std::shared_ptr<const void> PieceCache::find_typed(std::uint64_t key, const void* type) {
  const std::lock_guard lock(mutex_);
  const auto it = index_.find(key);
  if (it == index_.end() || it->second->type != type) {
    ++stats_.misses;
    return nullptr;
  }
  ++stats_.hits;
  lru_.splice(lru_.begin(), lru_, it->second);
  return it->second->value;
}

void PieceCache::insert_typed(std::uint64_t key, std::shared_ptr<const void> value, const void* type, std::size_t bytes) {
  const std::lock_guard lock(mutex_);
  if (const auto it = index_.find(key); it != index_.end()) {
    stats_.bytes -= it->second->bytes;
    lru_.erase(it->second);
    index_.erase(it);
  }
  if (bytes > max_bytes_) return;
  lru_.push_front(Entry{key, std::move(value), type, bytes});
  index_[key] = lru_.begin();
  stats_.bytes += bytes;
  ++stats_.insertions;
  while (stats_.bytes > max_bytes_ && !lru_.empty()) {
    stats_.bytes -= lru_.back().bytes;
    index_.erase(lru_.back().key);
    lru_.pop_back();
    ++stats_.evictions;
  }
}

PieceCacheStats PieceCache::stats() const {
  const std::lock_guard lock(mutex_);
  PieceCacheStats s = stats_;
  s.entries = lru_.size();
  return s;
}

void PieceCache::clear() {
  const std::lock_guard lock(mutex_);
  lru_.clear();
  index_.clear();
  stats_.bytes = 0;
}

}  // namespace ht
