// Mesh file bytes before OpenMesh's readers (nodes/mesh_text.hpp). Every count is compared with
// the least room its records can take: a vertex of ASCII OFF is three numbers and a face at least
// its vertex count; a PLY record is at least one word per property (ASCII) or the bytes of its
// scalars and list counts (binary). Sums are in double: a count may be any 64-bit number.
#include "nodes/mesh_text.hpp"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <vector>

namespace ht {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

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

// The word starting at or after `at`, which moves past it; empty at the end of the text.
std::string_view next_word(std::string_view text, std::size_t& at) {
  while (at < text.size() && is_space(text[at])) ++at;
  const std::size_t start = at;
  while (at < text.size() && !is_space(text[at])) ++at;
  return text.substr(start, at - start);
}

std::string truncated(const std::string& stated, const std::string& holds) {
  return "the header states " + stated + ", more than the file holds (" + holds + "; a truncated file?)";
}

// The OFF keyword's optional prefixes, in order ([ST][C][N][4][n]OFF); false when `word` is not
// one. `dimension` is set for nOFF, whose counts follow the vertex dimension.
bool off_keyword(std::string_view word, bool& dimension) {
  for (const std::string_view prefix : {"ST", "C", "N", "4"})
    if (word.starts_with(prefix)) word.remove_prefix(prefix.size());
  dimension = word.starts_with('n');
  if (dimension) word.remove_prefix(1);
  return word == "OFF";
}

// Binary OFF: the counts as three 32-bit integers after the keyword's line, then 3 floats per
// vertex and at least a 32-bit size per face. The byte order is the reader's business, so the
// counts must fit in either order.
std::string binary_off_counts(std::string_view text, std::size_t body) {
  if (text.size() < body + 12) return "binary OFF without its vertex and face counts";
  double need = kInfinity;
  for (const bool big_endian : {false, true}) {
    std::uint32_t count[2] = {0, 0};
    for (int c = 0; c < 2; ++c)
      for (int b = 0; b < 4; ++b) {
        const auto byte = static_cast<std::uint32_t>(static_cast<unsigned char>(text[body + 4 * c + b]));
        count[c] |= byte << (8 * (big_endian ? 3 - b : b));
      }
    need = std::min(need, 12.0 * count[0] + 4.0 * count[1]);
  }
  const std::size_t have = text.size() - body - 12;
  if (need <= static_cast<double>(have)) return {};
  return truncated("vertex and face counts needing " + std::to_string(static_cast<std::uint64_t>(need)) + " bytes",
                   std::to_string(have) + " bytes after them");
}

std::string off_counts(const std::string& text) {
  const std::string_view first(text.data(), std::min(text.find('\n'), text.size()));
  // Given a stream, OpenMesh's OFF reader reads the header without checking it: with no counts
  // ("", "OFF", "4OFF2") it reserved room for whatever its variables held (3 to 14 GB), and with
  // a first line "BINARYF" it read faces for 11 s and more.
  std::size_t at = 0;
  const std::string_view keyword = next_word(text, at);
  bool dimension = false;
  if (!off_keyword(keyword, dimension))
    return "the first line must be an OFF keyword ([ST][C][N][4][n]OFF), not \"" +
           std::string(first.substr(0, 40)) + "\"";
  if (first.find("BINARY") != std::string_view::npos) return binary_off_counts(text, first.size() + 1);
  if (dimension && next_word(text, at).empty()) return "no vertex dimension after the nOFF keyword";
  const std::string nv_word(next_word(text, at)), nf_word(next_word(text, at));
  if (nf_word.empty()) return "no vertex and face counts after the OFF keyword";
  for (const std::string& word : {nv_word, nf_word})
    if (word[0] == '-') return "the header states a negative count (" + word + ")";
  std::uint64_t nv = 0, nf = 0;
  if (!parse_count(nv_word, nv) || !parse_count(nf_word, nf))
    return "the vertex and face counts are not whole numbers (" + nv_word + " " + nf_word + ")";
  // Then the edge count (which nothing reads, so it is counted in), three numbers per vertex (one
  // for nOFF, whose dimension may be anything) and at least one, its size, per face.
  const std::size_t words = words_from(text, at);
  const double per_vertex = dimension ? 1.0 : 3.0;
  if (per_vertex * static_cast<double>(nv) + static_cast<double>(nf) <= static_cast<double>(words)) return {};
  return truncated(std::to_string(nv) + " vertices and " + std::to_string(nf) + " faces",
                   std::to_string(words) + " numbers after the vertex and face counts");
}

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::size_t properties = 0;  // each at least one ASCII word
  std::size_t bytes = 0;       // least binary bytes of one record
};

std::size_t ply_type_bytes(const std::string& type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "float" || type == "int32" || type == "uint32" || type == "float32")
    return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

std::string ply_counts(const std::string& text) {
  std::vector<PlyElement> elements;
  bool ascii = false;
  std::size_t at = 0;
  while (true) {  // header lines up to end_header
    const std::size_t eol = text.find('\n', at);
    if (eol == std::string::npos) return {};
    std::istringstream line(text.substr(at, eol - at));
    at = eol + 1;
    std::string word;
    if (!(line >> word)) continue;
    if (word == "end_header") break;
    if (word == "format") {
      line >> word;
      ascii = word == "ascii";
    } else if (word == "element") {
      PlyElement e;
      // OpenMesh's reader took a count it could not read as whatever it parsed (65 s, then
      // bad_alloc, for "element face FACES").
      if (!(line >> e.name >> word)) return "an element line of the header has no name or count";
      if (word[0] == '-') return "the header states a negative count (element " + e.name + " " + word + ")";
      if (!parse_count(word, e.count))
        return "the header's count of element \"" + e.name + "\" is not a whole number (" + word + ")";
      elements.push_back(e);
    } else if (word == "property" && !elements.empty()) {
      std::string type;
      line >> type;
      if (type == "list") line >> type;  // the count's type: an empty list is that alone
      const std::size_t bytes = ply_type_bytes(type);
      if (bytes == 0) return {};
      ++elements.back().properties;
      elements.back().bytes += bytes;
    }
  }
  double need = 0;
  std::string stated;
  for (const PlyElement& e : elements) {
    // Records of nothing cost the reader a loop each and say nothing: 2 billion of them took it
    // seconds.
    if (e.count > 0 && e.properties == 0)
      return "element \"" + e.name + "\" states " + std::to_string(e.count) + " records but no properties";
    need += static_cast<double>(e.count) * static_cast<double>(ascii ? e.properties : e.bytes);
    stated += (stated.empty() ? "" : ", ") + std::to_string(e.count) + " " + e.name;
  }
  const std::size_t have = ascii ? words_from(text, at) : text.size() - at;
  if (need <= static_cast<double>(have)) return {};
  return truncated(stated, std::to_string(have) + (ascii ? " words" : " bytes") + " after the header");
}

}  // namespace

std::string without_material_libraries(std::string text) {
  if (text.find("mtllib") == std::string::npos) return text;
  std::string out;
  out.reserve(text.size());
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t eol = text.find('\n', at);
    const std::size_t end = eol == std::string::npos ? text.size() : eol + 1;
    const std::size_t first = text.find_first_not_of(" \t\r\v\f", at);
    if (!(first < end && text.compare(first, 6, "mtllib") == 0)) out.append(text, at, end - at);
    at = end;
  }
  return out;
}

std::string stated_counts_problem(const std::string& text, const std::string& ext) {
  if (ext == ".off") return off_counts(text);
  if (ext == ".ply") return ply_counts(text);
  return {};
}

}  // namespace ht
