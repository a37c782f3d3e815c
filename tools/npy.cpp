#include "tools/npy.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>

namespace ht::npy {

// The data are copied byte for byte into floats and doubles.
static_assert(std::endian::native == std::endian::little, "the .npy reader and writer assume a little-endian host");
static_assert(sizeof(glm::dvec3) == 3 * sizeof(double), "points are read straight into glm::dvec3 arrays");

namespace {

constexpr char kMagic[] = "\x93NUMPY";
constexpr std::size_t kMagicSize = 6;
constexpr std::size_t kAlign = 64;
constexpr std::uint32_t kMaxHeader = 1 << 16;

// One value of the header's dictionary: a string, a bool or a tuple of integers.
struct Value {
  enum Kind { String, Bool, Tuple } kind = String;
  std::string text;
  bool flag = false;
  std::vector<std::uint64_t> items;
};

// The header is a Python dict literal: {'descr': '<f4', 'fortran_order': False, 'shape': (3, 3), }
// This parses that subset of Python and nothing more.
class HeaderParser {
 public:
  HeaderParser(std::string_view text, const std::string& file) : s_(text), file_(file) {}

  std::map<std::string, Value> dict() {
    std::map<std::string, Value> out;
    expect('{');
    while (!peek('}')) {
      const std::string key = quoted();
      expect(':');
      out[key] = value();
      if (!peek('}')) expect(',');
    }
    expect('}');
    return out;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw Error(file_ + ": the .npy header does not parse (" + what + " at character " + std::to_string(at_) +
                "): " + std::string(s_));
  }
  void skip_space() {
    while (at_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[at_]))) ++at_;
  }
  bool peek(char c) {
    skip_space();
    return at_ < s_.size() && s_[at_] == c;
  }
  void expect(char c) {
    if (!peek(c)) fail(std::string("expected '") + c + "'");
    ++at_;
  }
  std::string quoted() {
    skip_space();
    if (at_ >= s_.size() || (s_[at_] != '\'' && s_[at_] != '"')) fail("expected a quoted string");
    const char q = s_[at_++];
    const std::size_t end = s_.find(q, at_);
    if (end == std::string_view::npos) fail("unterminated string");
    std::string text(s_.substr(at_, end - at_));
    at_ = end + 1;
    return text;
  }
  std::uint64_t integer() {
    skip_space();
    std::uint64_t v = 0;
    const std::size_t start = at_;
    for (; at_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[at_])); ++at_) {
      if (v > (std::numeric_limits<std::uint64_t>::max() - 9) / 10) fail("dimension too large");
      v = v * 10 + static_cast<std::uint64_t>(s_[at_] - '0');
    }
    if (at_ == start) fail("expected a non-negative integer");
    return v;
  }
  Value value() {
    Value v;
    skip_space();
    if (peek('(')) {
      ++at_;
      v.kind = Value::Tuple;
      while (!peek(')')) {
        v.items.push_back(integer());
        if (!peek(')')) expect(',');
      }
      ++at_;
    } else if (s_.substr(at_, 4) == "True" || s_.substr(at_, 5) == "False") {
      v.kind = Value::Bool;
      v.flag = s_[at_] == 'T';
      at_ += v.flag ? 4 : 5;
    } else {
      v.text = quoted();
    }
    return v;
  }

  std::string_view s_;
  const std::string& file_;
  std::size_t at_ = 0;
};

std::string shape_text(const std::vector<std::uint64_t>& shape) {
  std::string out = "(";
  for (std::size_t i = 0; i < shape.size(); ++i) {
    if (i) out += ", ";
    out += std::to_string(shape[i]);
  }
  out += shape.size() == 1 ? ",)" : ")";
  return out;
}

struct Header {
  Dtype dtype;
  std::uint64_t rows;
};

// Reads magic, version and header; leaves `in` at the first data byte.
Header read_header(std::istream& in, const std::string& file) {
  char start[kMagicSize + 2];
  if (!in.read(start, sizeof start) || std::memcmp(start, kMagic, kMagicSize) != 0)
    throw Error(file + ": not a .npy file (it does not start with the magic string \\x93NUMPY)");
  const int major = static_cast<unsigned char>(start[kMagicSize]);
  const int minor = static_cast<unsigned char>(start[kMagicSize + 1]);
  if ((major != 1 && major != 2) || minor != 0)
    throw Error(file + ": .npy format version " + std::to_string(major) + "." + std::to_string(minor) +
                " is not supported (1.0 and 2.0 are)");
  unsigned char size_bytes[4] = {};
  if (!in.read(reinterpret_cast<char*>(size_bytes), major == 1 ? 2 : 4))
    throw Error(file + ": truncated .npy header");
  const std::uint32_t size = std::uint32_t(size_bytes[0]) | std::uint32_t(size_bytes[1]) << 8 |
                             std::uint32_t(size_bytes[2]) << 16 | std::uint32_t(size_bytes[3]) << 24;
  // A bound before allocating (numpy itself refuses headers past 10,000 bytes by default).
  if (size > kMaxHeader)
    throw Error(file + ": the .npy header claims " + std::to_string(size) + " bytes (more than " +
                std::to_string(kMaxHeader) + ": not a points file)");
  std::string text(size, '\0');
  if (!in.read(text.data(), static_cast<std::streamsize>(size))) throw Error(file + ": truncated .npy header");
  // The dict ends in padding and '\n'; messages quote it without them.
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
  const auto dict = HeaderParser(text, file).dict();
  auto field = [&](const char* key, Value::Kind kind) -> const Value& {
    const auto it = dict.find(key);
    if (it == dict.end() || it->second.kind != kind)
      throw Error(file + ": the .npy header has no valid '" + key + "' entry: " + text);
    return it->second;
  };
  const std::string& d = field("descr", Value::String).text;
  if (d != "<f4" && d != "<f8")
    throw Error(file + ": unsupported dtype '" + d + "' (expected little-endian float32 '<f4' or float64 '<f8')");
  if (field("fortran_order", Value::Bool).flag)
    throw Error(file + ": fortran_order is True (only C-order arrays are read; use numpy.ascontiguousarray)");
  const auto& shape = field("shape", Value::Tuple).items;
  if (shape.size() != 2 || shape[1] != 3) throw Error(file + ": shape " + shape_text(shape) + " is not (N, 3)");
  return {d == "<f4" ? Dtype::Float32 : Dtype::Float64, shape[0]};
}

// The first non-finite coordinate, named the way numpy would index it.
void check_finite(const std::vector<glm::dvec3>& points, const std::string& file) {
  for (std::size_t i = 0; i < points.size(); ++i)
    for (int j = 0; j < 3; ++j)
      if (!std::isfinite(points[i][j])) {
        char value[32];
        std::snprintf(value, sizeof value, "%g", points[i][j]);
        throw Error(file + ": points[" + std::to_string(i) + ", " + std::to_string(j) + "] is " + value +
                    ", not a finite number");
      }
}

}  // namespace

const char* descr(Dtype dtype) { return dtype == Dtype::Float32 ? "<f4" : "<f8"; }

bool has_npy_extension(std::string_view path) {
  if (path.size() < 4) return false;
  std::string ext(path.substr(path.size() - 4));
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext == ".npy";
}

Points read_points(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw Error(file + ": cannot open the points file");
  const Header h = read_header(in, file);
  const std::size_t item = h.dtype == Dtype::Float32 ? sizeof(float) : sizeof(double);
  const std::streamoff data_start = in.tellg();
  in.seekg(0, std::ios::end);
  const auto available = static_cast<std::uint64_t>(in.tellg() - data_start);
  in.seekg(data_start);
  const std::uint64_t max_rows = std::numeric_limits<std::uint64_t>::max() / (3 * item);
  const std::uint64_t needed = h.rows <= max_rows ? h.rows * 3 * item : std::numeric_limits<std::uint64_t>::max();
  if (available < needed)
    throw Error(file + ": truncated: shape (" + std::to_string(h.rows) + ", 3) of " + descr(h.dtype) + " needs " +
                std::to_string(needed) + " bytes of data, the file holds " + std::to_string(available));
  if (available > needed)
    throw Error(file + ": " + std::to_string(available - needed) + " bytes follow the (" + std::to_string(h.rows) +
                ", 3) array (is the shape in the header right?)");
  Points out;
  out.dtype = h.dtype;
  out.points.resize(h.rows);
  bool ok;
  if (h.dtype == Dtype::Float64) {
    ok = bool(in.read(reinterpret_cast<char*>(out.points.data()), static_cast<std::streamsize>(needed)));
  } else {
    std::vector<float> raw(h.rows * 3);
    ok = bool(in.read(reinterpret_cast<char*>(raw.data()), static_cast<std::streamsize>(needed)));
    for (std::size_t i = 0; i < h.rows; ++i) out.points[i] = glm::dvec3(raw[3 * i], raw[3 * i + 1], raw[3 * i + 2]);
  }
  if (!ok) throw Error(file + ": read error");
  check_finite(out.points, file);
  return out;
}

std::string encode(Dtype dtype, std::span<const double> data, std::size_t columns) {
  if (columns == 0 || data.size() % columns != 0)
    throw std::invalid_argument("npy::encode: data.size() is not a multiple of columns");
  const std::size_t rows = data.size() / columns;
  const std::string shape = columns == 1 ? shape_text({rows}) : shape_text({rows, columns});
  std::string header = std::string("{'descr': '") + descr(dtype) + "', 'fortran_order': False, 'shape': " + shape + ", }";
  // Magic (6), version (2), length (2), then the dict padded with spaces and ended by '\n'.
  const std::size_t preamble = kMagicSize + 4;
  header.resize((preamble + header.size() + 1 + kAlign - 1) / kAlign * kAlign - preamble - 1, ' ');
  header += '\n';
  const std::size_t item = dtype == Dtype::Float32 ? sizeof(float) : sizeof(double);
  std::string out;
  out.reserve(preamble + header.size() + data.size() * item);
  out.append(kMagic, kMagicSize);
  out += '\x01';
  out += '\x00';
  out += static_cast<char>(header.size() & 0xff);
  out += static_cast<char>(header.size() >> 8);
  out += header;
  const std::size_t at = out.size();
  out.resize(at + data.size() * item);
  char* dst = out.data() + at;
  if (dtype == Dtype::Float64) {
    std::memcpy(dst, data.data(), data.size() * item);
  } else {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, data.size(), 1 << 16), [&](const auto& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        const float f = static_cast<float>(data[i]);
        std::memcpy(dst + i * item, &f, item);
      }
    });
  }
  return out;
}

}  // namespace ht::npy
