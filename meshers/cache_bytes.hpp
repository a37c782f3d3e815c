// Bytes of the cache files (meshers/disk_cache.hpp): little-endian words and arrays written as in
// memory, read back with every count checked against the bytes left. Internal to the caches and
// to the parts they keep (job results, bricks, quality-pass pieces).
#pragma once

#include "runtime/aabb.hpp"

#include <bit>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace ht {

static_assert(std::endian::native == std::endian::little, "cache files are little-endian, written as in memory");

/// Appends values to `out`: integers as 8-byte words, doubles bit for bit, flags and enums as one
/// byte, strings and lists of strings with their length first.
class CacheWriter {
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

/// Reads what CacheWriter wrote. Every count is checked against the bytes left before anything is
/// allocated for it; the first problem is kept in error() and later reads give zeros. An enum T
/// needs `std::uint8_t cache_enum_limit(T)` (its largest enumerator) where ADL finds it.
class CacheReader {
 public:
  explicit CacheReader(std::string_view in) : in_(in) {}

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
        if (b > cache_enum_limit(T{})) fail("an unknown enumerator (" + std::to_string(b) + ")");
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

}  // namespace ht
