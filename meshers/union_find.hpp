// Disjoint sets over 0..n-1 (path halving). The smaller id of two joined sets leads, so a class's
// representative is its first member: callers use that to let earlier elements win.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <numeric>
#include <vector>

namespace ht {

struct UnionFind {
  std::vector<std::uint32_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  std::uint32_t find(std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

/// The same sets for unions made from several threads at once: a root is linked to a smaller one
/// by compare-and-swap, so each class's representative is still its smallest member, whatever
/// order the unions came in (the sets, and so every count read from them, are the same at any
/// thread count). find() halves paths as it goes; unite() and find() may run concurrently.
struct ConcurrentUnionFind {
  std::vector<std::atomic<std::uint32_t>> parent;
  explicit ConcurrentUnionFind(std::size_t n) : parent(n) {
    for (std::size_t i = 0; i < n; ++i) parent[i].store(std::uint32_t(i), std::memory_order_relaxed);
  }
  std::uint32_t find(std::uint32_t x) {
    while (true) {
      std::uint32_t p = parent[x].load(std::memory_order_acquire);
      if (p == x) return x;
      const std::uint32_t g = parent[p].load(std::memory_order_acquire);
      // Pointing x at its grandparent only shortens the path (g is an ancestor of x for good).
      if (g != p) parent[x].compare_exchange_weak(p, g, std::memory_order_acq_rel);
      x = g;
    }
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    while (true) {
      a = find(a);
      b = find(b);
      if (a == b) return;
      if (a < b) std::swap(a, b);
      std::uint32_t root = a;  // link the larger root under the smaller, if it is still a root
      if (parent[a].compare_exchange_strong(root, b, std::memory_order_acq_rel)) return;
    }
  }
};

}  // namespace ht
