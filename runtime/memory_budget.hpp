// The memory budget of one run, shared by its stages: the mesh leaves it holds, every
// polygonizer's brick grid, every quality pass's halfedge mesh and every node mesh the plan
// keeps. A stage takes its estimated bytes before it allocates them, so a run that would not
// fit stops at that stage, before the allocation, with what it needed and what was left.
//
// The amounts are estimates of what the stage holds at its peak (documented where they are
// taken), not a count of every allocation. Thread-safe: jobs running in parallel take from one
// budget.
#pragma once

#include <atomic>
#include <cstddef>
#include <stdexcept>
#include <string>

namespace ht {

/// Thrown when a stage does not fit; what() names the stage, the amount it needed, the budget
/// and what the run already held.
struct MemoryBudgetError : std::runtime_error {
  MemoryBudgetError(const std::string& what, std::size_t needed, std::size_t in_use, std::size_t limit);
  std::size_t needed = 0, in_use = 0, limit = 0;  ///< bytes
};

/// "1.25 GiB", "3.0 MiB", "512 bytes": for messages.
std::string format_bytes(double bytes);
/// "about N" for an estimated count, or "more than 10^15" past that (and for NaN): an absurd
/// precision makes estimates no integer type holds.
std::string format_estimate(double count);

class MemoryBudget {
 public:
  explicit MemoryBudget(std::size_t limit_bytes) : limit_(limit_bytes) {}
  MemoryBudget(const MemoryBudget&) = delete;
  MemoryBudget& operator=(const MemoryBudget&) = delete;

  /// Counts `bytes` as held by `stage` (a phrase such as "the quality pass on 2,000,000
  /// vertices"), or throws MemoryBudgetError when they would pass the limit.
  void take(double bytes, const std::string& stage);
  /// Returns bytes taken earlier.
  void give_back(std::size_t bytes) noexcept { in_use_.fetch_sub(bytes, std::memory_order_relaxed); }

  std::size_t limit() const { return limit_; }
  std::size_t in_use() const { return in_use_.load(std::memory_order_relaxed); }
  /// The most held at once so far.
  std::size_t peak() const { return peak_.load(std::memory_order_relaxed); }

 private:
  std::size_t limit_;
  std::atomic<std::size_t> in_use_{0}, peak_{0};
};

/// Bytes taken for the lifetime of a scope (a stage's working memory), given back at its end.
class MemoryReservation {
 public:
  MemoryReservation(MemoryBudget& budget, double bytes, const std::string& stage);
  ~MemoryReservation() { budget_.give_back(bytes_); }
  MemoryReservation(const MemoryReservation&) = delete;
  MemoryReservation& operator=(const MemoryReservation&) = delete;

 private:
  MemoryBudget& budget_;
  std::size_t bytes_;
};

}  // namespace ht
