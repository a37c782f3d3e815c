// Mesh file text before (or instead of) OpenMesh's readers (nodes/mesh_text.hpp). Every stated
// count is compared with the least room its records can take before anything is reserved for
// it: a vertex of ASCII OFF is three numbers and a face at least its vertex count; a PLY record
// is at least one word per property (ASCII) or the bytes of its scalars and list counts
// (binary). Sums are in double: a count may be any 64-bit number.
#include "nodes/mesh_text.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <vector>

namespace ht {
namespace {

bool is_space(char ch) { return std::isspace(static_cast<unsigned char>(ch)) != 0; }

// Whitespace-separated words in text[from, end).
std::size_t words_from(std::string_view text, std::size_t from) {
  std::size_t words = 0;
  bool in_word = false;
  for (std::size_t i = from; i < text.size(); ++i) {
    const bool space = is_space(text[i]);
    if (!space && !in_word) ++words;
    in_word = !space;
  }
  return words;
}

// A count as the header writes it; false when the word is not one (the reader refuses it then).
// A count past 64 bits is the largest: it cannot fit either.
bool parse_count(const std::string& word, std::uint64_t& n) {
  if (word.empty() || !std::isdigit(static_cast<unsigned char>(word[0]))) return false;
  std::size_t used = 0;
  try {
    n = std::stoull(word, &used);
  } catch (const std::out_of_range&) {
    n = UINT64_MAX;
    return true;
  } catch (const std::invalid_argument&) {
    return false;
  }
  return used == word.size();
}

std::string truncated(const std::string& stated, const std::string& holds) {
  return "the header states " + stated + ", more than the file holds (" + holds + "; a truncated file?)";
}

// Words of a text in order, across lines, with the line each starts on.
class Words {
 public:
  explicit Words(std::string_view text) : text_(text) {}
  /// The next word, or empty at the end of the text.
  std::string_view next() {
    while (at_ < text_.size() && is_space(text_[at_])) line_ += text_[at_++] == '\n' ? 1 : 0;
    const std::size_t start = at_;
    while (at_ < text_.size() && !is_space(text_[at_])) ++at_;
    if (at_ > start) ++read_;
    return text_.substr(start, at_ - start);
  }
  /// Words returned so far.
  std::size_t read() const { return read_; }
  /// Skips what is left of the current line (an OFF record's colours, texture coordinates).
  void end_line() {
    while (at_ < text_.size() && text_[at_] != '\n') ++at_;
  }
  std::size_t line() const { return line_; }
  std::size_t at() const { return at_; }

 private:
  std::string_view text_;
  std::size_t at_ = 0, line_ = 1, read_ = 0;
};

// Built by appending: GCC 12 warns (-Wrestrict, a false positive) on "\"" + std::string(...).
std::string quoted(std::string_view word) {
  std::string out(1, '"');
  out.append(word.substr(0, 40));
  out.push_back('"');
  return out;
}

// A coordinate as OpenMesh's readers took it: a float, then widened. Empty when it reads, else
// what is wrong with it (a number past the float range, 5e-151 or 1.7e308, is no typo).
std::string parse_coordinate(std::string_view word, double& x) {
  if (word.starts_with('+')) word.remove_prefix(1);
  float f = 0;
  const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), f);
  x = f;
  if (ec == std::errc::result_out_of_range && end == word.data() + word.size()) {
    // Below the float range (noise such as 1e-50 in an exported file): the float it rounds to, 0
    // or subnormal, as a stream would read it. Above it no float holds the number.
    double d = 0;
    const auto read = std::from_chars(word.data(), word.data() + word.size(), d);
    const bool tiny = read.ec == std::errc() ? std::abs(d) < 1.0
                                             : word.find("e-") != std::string_view::npos || word.find("E-") != std::string_view::npos;
    if (tiny) {
      x = read.ec == std::errc() ? static_cast<double>(static_cast<float>(d)) : 0.0;
      return {};
    }
    return quoted(word) + " is past the float range coordinates are read in (magnitudes up to 3.4e38)";
  }
  if (ec == std::errc() && end == word.data() + word.size() && std::isfinite(f)) return {};
  return quoted(word) + " is not a finite number";
}

// The header: keyword ([ST][C][N]OFF) then the vertex and face counts (and the edge count, which
// nothing reads). Sets the counts and whether vertices carry normals (three more numbers).
std::string off_header(Words& words, std::string_view first_line, std::uint64_t& nv, std::uint64_t& nf,
                       bool& normals) {
  std::string_view keyword = words.next();
  if (keyword.starts_with("ST")) keyword.remove_prefix(2);
  if (keyword.starts_with('C')) keyword.remove_prefix(1);
  normals = keyword.starts_with('N');
  if (normals) keyword.remove_prefix(1);
  if (keyword == "4OFF" || keyword == "nOFF" || keyword == "4nOFF")
    return "vertex dimensions other than 3 (4OFF, nOFF) are not read";
  if (keyword != "OFF")
    return "the first line must be an OFF keyword ([ST][C][N]OFF), not " + quoted(first_line);
  if (first_line.find("BINARY") != std::string_view::npos)
    return "binary OFF is not read (ASCII OFF, PLY and STL are)";
  words.end_line();
  const std::string nv_word(words.next()), nf_word(words.next());
  if (nf_word.empty()) return "no vertex and face counts after the OFF keyword";
  for (const std::string& word : {nv_word, nf_word})
    if (word[0] == '-') return "the header states a negative count (" + word + ")";
  if (!parse_count(nv_word, nv) || !parse_count(nf_word, nf))
    return "the vertex and face counts are not whole numbers (" + nv_word + " " + nf_word + ")";
  words.end_line();
  return {};
}

std::string off_vertices(Words& words, std::uint64_t nv, bool normals, MeshRecords& out) {
  for (std::uint64_t v = 0; v < nv; ++v) {
    glm::dvec3 p(0.0);
    for (int k = 0; k < (normals ? 6 : 3); ++k) {
      const std::string_view word = words.next();
      const std::string where = "vertex " + std::to_string(v);
      if (word.empty()) return "the file ends in " + where + " (the header states " + std::to_string(nv) + ")";
      double x = 0;
      if (const std::string bad = parse_coordinate(word, x); !bad.empty())
        return where + ": " + bad + " (line " + std::to_string(words.line()) + ")";
      if (k < 3) p[k] = x;
    }
    words.end_line();
    out.positions.push_back(p);
  }
  return {};
}

std::string off_faces(Words& words, std::uint64_t nv, std::uint64_t nf, MeshRecords& out) {
  for (std::uint64_t f = 0; f < nf; ++f) {
    const std::string where = "face " + std::to_string(f);
    std::uint64_t n = 0;
    std::string_view word = words.next();
    if (word.empty()) return "the file ends in " + where + " (the header states " + std::to_string(nf) + ")";
    if (!parse_count(std::string(word), n))
      return where + ": " + quoted(word) + " is not a vertex count (line " + std::to_string(words.line()) + ")";
    std::vector<std::uint32_t>& face = out.faces.emplace_back();
    for (std::uint64_t i = 0; i < n; ++i) {  // each index is a word of the file: n cannot run away
      word = words.next();
      if (word.empty()) return "the file ends in " + where + " (it states " + std::to_string(n) + " vertices)";
      std::uint64_t index = 0;
      if (!parse_count(std::string(word), index))
        return where + ": " + quoted(word) + " is not a vertex index (line " + std::to_string(words.line()) + ")";
      face.push_back(index < nv ? static_cast<std::uint32_t>(index) : kNoVertex);
    }
    words.end_line();  // a colour, if any
  }
  return {};
}

struct PlyProperty {
  bool list = false;
  std::size_t count_bytes = 0;  // a list's size: its type's bytes (1, 2 or 4), and whether signed
  bool count_signed = false;
  std::size_t bytes = 0;  // a scalar's, or each list item's
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

bool ply_type_signed(const std::string& type) {
  return type == "char" || type == "short" || type == "int" || type == "int8" || type == "int16" || type == "int32";
}

std::size_t ply_type_bytes(const std::string& type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "float" || type == "int32" || type == "uint32" || type == "float32")
    return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

// The header, checked line by line: OpenMesh's header parser crashed on a property before any
// element and looped on an unreadable version (fuzz_mesh_ply), and took a count it could not read as whatever it parsed (65 s, then
// bad_alloc, for "element face FACES"). Sets the elements, the format and where the data starts.
std::string ply_header(const std::string& text, std::vector<PlyElement>& elements, bool& ascii, bool& big_endian,
                       std::size_t& at) {
  for (std::size_t line_no = 1;; ++line_no) {
    const std::size_t eol = text.find('\n', at);
    if (eol == std::string::npos) return "the header does not end (no end_header line)";
    Words line(std::string_view(text).substr(at, eol - at));
    at = eol + 1;
    const std::string where = " (header line " + std::to_string(line_no) + ")";
    const std::string_view word = line.next();
    if (line_no == 1) {
      if (word != "ply" || !line.next().empty()) return "the first line must be \"ply\"";
    } else if (word == "end_header") {
      return {};
    } else if (word == "format") {
      const std::string_view format = line.next();
      if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian")
        return "unknown format " + quoted(format) + where;
      // OpenMesh's parser loops forever on a version it cannot read (fuzz_mesh_ply: "@0.").
      if (const std::string_view version = line.next(); version != "1.0")
        return "unknown PLY version " + quoted(version) + " (1.0 is the only one)" + where;
      ascii = format == "ascii";
      big_endian = format == "binary_big_endian";
    } else if (word == "element") {
      PlyElement& e = elements.emplace_back();
      e.name = line.next();
      const std::string count(line.next());
      if (count.empty()) return "an element without a name or count" + where;
      if (count[0] == '-') return "the header states a negative count (element " + e.name + " " + count + ")";
      if (!parse_count(count, e.count))
        return "the header's count of element \"" + e.name + "\" is not a whole number (" + count + ")";
    } else if (word == "property") {
      if (elements.empty()) return "a property before any element" + where;
      std::string type(line.next());
      PlyProperty& prop = elements.back().properties.emplace_back();
      if (type == "list") {
        prop.list = true;
        type = line.next();
        prop.count_bytes = ply_type_bytes(type);
        prop.count_signed = ply_type_signed(type);
        if (prop.count_bytes == 0 || prop.count_bytes == 8 || type.starts_with("float"))
          return "a list property without a valid count type" + where;
        type = line.next();  // the items' type
      }
      prop.bytes = ply_type_bytes(type);
      if (prop.bytes == 0 || line.next().empty()) return "a property without a valid type or name" + where;
    } else if (word != "comment" && word != "obj_info" && !word.empty()) {
      return "unknown header line " + quoted(word) + where;
    }
  }
}

std::string record_text(const PlyElement& e, std::uint64_t r) {
  return "element \"" + e.name + "\" record " + std::to_string(r);
}

std::string list_too_long(const PlyElement& e, std::uint64_t r, const std::string& size) {
  return record_text(e, r) + ": a list of " + size + " items, more than the file holds";
}

// Every record of an ASCII body, word by word: a list's size must be a whole number its items
// fit behind. Each record takes at least a word, so this ends within the file.
std::string ply_ascii_records(std::string_view body, const std::vector<PlyElement>& elements) {
  Words words(body);
  const std::size_t total = words_from(body, 0);
  for (const PlyElement& e : elements)
    for (std::uint64_t r = 0; r < e.count; ++r)
      for (const PlyProperty& prop : e.properties) {
        const std::string_view word = words.next();
        if (word.empty()) return "the file ends in " + record_text(e, r) + " (the header states " + std::to_string(e.count) + ")";
        if (!prop.list) continue;
        std::uint64_t n = 0;
        if (!parse_count(std::string(word), n))
          return record_text(e, r) + ": the list size " + quoted(word) + " is not a whole number";
        if (n > total - words.read()) return list_too_long(e, r, std::string(word));
        for (std::uint64_t i = 0; i < n; ++i) words.next();
      }
  return {};
}

// Every record of a binary body, byte by byte, reading list sizes in the file's byte order.
std::string ply_binary_records(std::string_view body, const std::vector<PlyElement>& elements, bool big_endian) {
  std::size_t at = 0;
  for (const PlyElement& e : elements)
    for (std::uint64_t r = 0; r < e.count; ++r)
      for (const PlyProperty& prop : e.properties) {
        const std::size_t head = prop.list ? prop.count_bytes : prop.bytes;
        if (body.size() - at < head)
          return "the file ends in " + record_text(e, r) + " (the header states " + std::to_string(e.count) + ")";
        if (!prop.list) {
          at += head;
          continue;
        }
        std::uint64_t n = 0;
        for (std::size_t b = 0; b < head; ++b)
          n |= std::uint64_t{static_cast<unsigned char>(body[at + b])} << (8 * (big_endian ? head - 1 - b : b));
        if (prop.count_signed && (n >> (8 * head - 1)) != 0) return record_text(e, r) + ": a list of negative size";
        at += head;
        if (static_cast<double>(n) * static_cast<double>(prop.bytes) > static_cast<double>(body.size() - at))
          return list_too_long(e, r, std::to_string(n));
        at += n * prop.bytes;
      }
  return {};
}

std::string ply_counts(const std::string& text) {
  std::vector<PlyElement> elements;
  bool ascii = false, big_endian = false;
  std::size_t at = 0;
  if (std::string bad = ply_header(text, elements, ascii, big_endian, at); !bad.empty()) return bad;
  // Records of nothing cost the reader a loop each and say nothing: 2 billion of them took it
  // seconds.
  for (const PlyElement& e : elements)
    if (e.count > 0 && e.properties.empty())
      return "element \"" + e.name + "\" states " + std::to_string(e.count) + " records but no properties";
  const std::string_view body = std::string_view(text).substr(at);
  return ascii ? ply_ascii_records(body, elements) : ply_binary_records(body, elements, big_endian);
}

// One OBJ face corner ("7", "-2", "7/1", "7//3"): the vertex index before any '/', 1-based or,
// when negative, counted back from the vertices read so far. Sets kNoVertex when out of range.
bool obj_corner(std::string_view word, std::size_t vertices, std::uint32_t& index) {
  word = word.substr(0, word.find('/'));
  long long k = 0;
  const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), k);
  if (ec != std::errc() || end != word.data() + word.size() || k == 0) return false;
  const long long v = k > 0 ? k - 1 : static_cast<long long>(vertices) + k;
  index = v >= 0 && v < static_cast<long long>(kNoVertex) ? static_cast<std::uint32_t>(v) : kNoVertex;
  return true;
}

}  // namespace

std::string stated_counts_problem(const std::string& text, const std::string& ext) {
  return ext == ".ply" ? ply_counts(text) : std::string();
}

std::string read_ascii_off(const std::string& text, MeshRecords& out) {
  out = {};
  const std::string_view first_line(text.data(), std::min(text.find('\n'), text.size()));
  Words words(text);
  std::uint64_t nv = 0, nf = 0;
  bool normals = false;
  if (std::string bad = off_header(words, first_line, nv, nf, normals); !bad.empty()) return bad;
  // Counts the text cannot hold are refused before anything is reserved for them.
  const std::size_t left = words_from(text, words.at());
  if ((normals ? 6.0 : 3.0) * static_cast<double>(nv) + static_cast<double>(nf) > static_cast<double>(left))
    return truncated(std::to_string(nv) + " vertices and " + std::to_string(nf) + " faces",
                     std::to_string(left) + " numbers after the counts");
  out.positions.reserve(nv);
  out.faces.reserve(nf);
  if (std::string bad = off_vertices(words, nv, normals, out); !bad.empty()) return bad;
  return off_faces(words, nv, nf, out);
}

}  // namespace ht

namespace ht {

std::string read_obj(const std::string& text, MeshRecords& out) {
  out = {};
  std::size_t line_no = 0;
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t eol = std::min(text.find('\n', at), text.size());
    std::string_view line(text.data() + at, eol - at);
    at = eol + 1;
    ++line_no;
    line = line.substr(0, line.find('#'));
    Words words(line);
    const std::string_view keyword = words.next();
    const std::string where = " (line " + std::to_string(line_no) + ")";
    if (keyword == "v") {
      glm::dvec3 p(0.0);
      for (int k = 0; k < 3; ++k) {
        const std::string_view word = words.next();
        if (word.empty()) return "vertex " + std::to_string(out.positions.size()) + ": needs three coordinates" + where;
        if (const std::string bad = parse_coordinate(word, p[k]); !bad.empty())
          return "vertex " + std::to_string(out.positions.size()) + ": " + bad + where;
      }
      out.positions.push_back(p);
    } else if (keyword == "f") {
      std::vector<std::uint32_t>& face = out.faces.emplace_back();
      for (std::string_view word = words.next(); !word.empty(); word = words.next()) {
        std::uint32_t index = 0;
        if (!obj_corner(word, out.positions.size(), index))
          return "face " + std::to_string(out.faces.size() - 1) + ": " + quoted(word) + " is not a vertex index" + where;
        face.push_back(index);
      }
    }  // texture coordinates, normals, groups, materials, lines: not geometry of the solid
  }
  // A positive index may name a vertex listed after its face.
  for (auto& face : out.faces)
    for (std::uint32_t& v : face)
      if (v != kNoVertex && v >= out.positions.size()) v = kNoVertex;
  return {};
}

}  // namespace ht
