#include "runtime/memory_budget.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace ht {

std::string format_bytes(double bytes) {
  char buf[64];
  if (!(bytes < 1e15 * double(1u << 30))) return "more than 10^15 GiB";  // NaN too
  if (bytes >= double(1u << 30))
    std::snprintf(buf, sizeof buf, "%.2f GiB", bytes / double(1u << 30));
  else if (bytes >= double(1u << 20))
    std::snprintf(buf, sizeof buf, "%.1f MiB", bytes / double(1u << 20));
  else
    std::snprintf(buf, sizeof buf, "%.0f bytes", bytes);
  return buf;
}

std::string format_estimate(double count) {
  if (!(count < 1e15)) return "more than 10^15";
  return "about " + std::to_string(std::llround(std::max(count, 0.0)));
}

MemoryBudgetError::MemoryBudgetError(const std::string& what, std::size_t needed_bytes, std::size_t in_use_bytes,
                                     std::size_t limit_bytes)
    : std::runtime_error(what), needed(needed_bytes), in_use(in_use_bytes), limit(limit_bytes) {}

void MemoryBudget::take(double bytes, const std::string& stage) {
  // A NaN or an amount past size_t (an absurd precision) does not fit any budget.
  const bool representable = bytes >= 0.0 && bytes < 1.8e19;
  const std::size_t want = representable ? static_cast<std::size_t>(std::ceil(bytes)) : std::numeric_limits<std::size_t>::max();
  std::size_t held = in_use_.load(std::memory_order_relaxed);
  for (;;) {
    if (!representable || want > limit_ || held > limit_ - want) {
      std::string why = stage + " needs " + format_bytes(bytes) + ", over the memory budget of " + format_bytes(double(limit_));
      if (held > 0) why += " (" + format_bytes(double(held)) + " of it already held by this run)";
      throw MemoryBudgetError(why, want, held, limit_);
    }
    if (in_use_.compare_exchange_weak(held, held + want, std::memory_order_relaxed)) break;
  }
  std::size_t peak = peak_.load(std::memory_order_relaxed);
  while (held + want > peak && !peak_.compare_exchange_weak(peak, held + want, std::memory_order_relaxed)) {
  }
}

MemoryReservation::MemoryReservation(MemoryBudget& budget, double bytes, const std::string& stage)
    : budget_(budget), bytes_(0) {
  budget.take(bytes, stage);
  bytes_ = static_cast<std::size_t>(std::ceil(bytes));
}

}  // namespace ht
