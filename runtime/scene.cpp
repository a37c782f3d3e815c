// The scene loader: walks the JSON document with its path in hand, checks every key against
// the format, and drives the Builder, which checks values. Errors from either come out as one
// SceneError "source: json.path: rule".
#include "runtime/scene.hpp"

#include "nodes/warps.hpp"
#include "runtime/builder.hpp"

#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <vector>

namespace ht {
namespace {

using json = nlohmann::json;

struct Fail {
  std::string path, rule;
};

// A JSON path of a deeply nested node runs to thousands of characters: past 8 steps (a step is
// a key with its index, ".children[0]"), the first three and the last three are kept, with the
// count of those left out between.
std::string shorten_path(const std::string& path) {
  std::vector<std::size_t> steps;  // where each step after the root begins
  for (std::size_t i = 1; i < path.size(); ++i)
    if (path[i] == '.') steps.push_back(i);
  if (steps.size() <= 8) return path;
  const std::size_t head = steps[3], tail = steps[steps.size() - 3];
  return path.substr(0, head) + "...(" + std::to_string(steps.size() - 6) + " steps)..." + path.substr(tail + 1);
}

// Where the parser stopped on a number no double holds ("1e999", 400 digits): nlohmann's
// document parser reports such a number without a place, so the text is read again through its
// SAX interface, which keeps the path of the value being read.
class OverflowPlace final : public nlohmann::json_sax<json> {
 public:
  std::string path;   ///< the JSON path of the number, as other errors name places
  std::string token;  ///< the number as written

  bool null() override { return value(); }
  bool boolean(bool) override { return value(); }
  bool number_integer(number_integer_t) override { return value(); }
  bool number_unsigned(number_unsigned_t) override { return value(); }
  bool number_float(number_float_t, const string_t&) override { return value(); }
  bool string(string_t&) override { return value(); }
  bool binary(binary_t&) override { return value(); }
  bool start_object(std::size_t) override { return value() && push(false); }
  bool key(string_t& k) override {
    frames_.back().key = k;
    return true;
  }
  bool end_object() override { return pop(); }
  bool start_array(std::size_t) override { return value() && push(true); }
  bool end_array() override { return pop(); }
  bool parse_error(std::size_t, const std::string& last_token, const nlohmann::detail::exception&) override {
    token = last_token;
    for (std::size_t i = 0; i < frames_.size(); ++i) {
      const Frame& f = frames_[i];
      if (f.array) {  // the innermost frame's failed value is the one after its last
        path += '[';
        path += std::to_string(i + 1 == frames_.size() ? f.index + 1 : f.index);
        path += ']';
      } else {
        if (!path.empty()) path += '.';
        path += f.key;
      }
    }
    return false;
  }

 private:
  struct Frame {
    bool array = false;
    std::size_t index = ~std::size_t(0);  // the array's last value read
    std::string key;                      // the object's last key read
  };
  std::vector<Frame> frames_;
  bool value() {
    if (!frames_.empty() && frames_.back().array) ++frames_.back().index;
    return true;
  }
  bool push(bool array) {
    frames_.push_back({array, ~std::size_t(0), {}});
    return true;
  }
  bool pop() {
    frames_.pop_back();
    return true;
  }
};

// "path: the number N is past the range of doubles", N shortened past 24 characters; any other
// error the parser throws past its syntax checks keeps its own words, with the path.
std::string overflow_message(const std::string& text, const json::exception& e) {
  OverflowPlace place;
  json::sax_parse(text, &place);
  // shorten_path counts keys, not indices: a path of 10,000 nested arrays is cut here.
  std::string path = shorten_path(place.path);
  if (path.size() > 160)
    path = path.substr(0, 60) + "...(" + std::to_string(path.size() - 120) + " characters)..." + path.substr(path.size() - 60);
  const std::string where = path.empty() ? std::string() : path + ": ";
  if (e.id != 406) {  // out_of_range.406 is "number overflow"; any other, should a later version throw one
    std::string why = e.what();
    const auto at = why.find("] ");
    return where + "not valid JSON: " + (at == std::string::npos ? why : why.substr(at + 2));
  }
  std::string shown = place.token;
  if (shown.size() > 24)
    shown = shown.substr(0, 12) + "..." + shown.substr(shown.size() - 6) + " (" + std::to_string(shown.size()) + " characters)";
  return where + "the number " + shown + " is past the range of doubles (every number must be finite)";
}

std::string type_name(const json& v) {
  if (v.is_number()) return "a number";
  if (v.is_string()) return "a string";
  if (v.is_boolean()) return "a boolean";
  if (v.is_array()) return "an array";
  if (v.is_object()) return "an object";
  return "null";
}

// One JSON object being read: remembers which keys were read so the rest can be reported.
class Obj {
 public:
  Obj(const json& j, std::string path) : j_(j), path_(std::move(path)) {
    if (!j.is_object()) throw Fail{path_, "must be an object, not " + type_name(j)};
  }
  std::string at(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  const std::string& path() const { return path_; }
  bool has(const std::string& key) const { return j_.contains(key); }
  const json& get(const std::string& key) {
    used_.insert(key);
    auto it = j_.find(key);
    if (it == j_.end()) throw Fail{at(key), "is required"};
    return *it;
  }
  double number(const std::string& key) { return as_number(get(key), at(key)); }
  double number(const std::string& key, double fallback) { return has(key) ? number(key) : fallback; }
  glm::dvec3 vec3(const std::string& key) { return as_vec3(get(key), at(key)); }
  glm::dvec3 vec3(const std::string& key, glm::dvec3 fallback) { return has(key) ? vec3(key) : fallback; }
  std::string string(const std::string& key) {
    const json& v = get(key);
    if (!v.is_string()) throw Fail{at(key), "must be a string, not " + type_name(v)};
    return v.get<std::string>();
  }
  bool boolean(const std::string& key, bool fallback) {
    if (!has(key)) return fallback;
    const json& v = get(key);
    if (!v.is_boolean()) throw Fail{at(key), "must be true or false, not " + type_name(v)};
    return v.get<bool>();
  }
  std::pair<double, double> pair(const std::string& key) {
    const json& v = get(key);
    if (!v.is_array() || v.size() != 2) throw Fail{at(key), "must be an array of 2 numbers"};
    return {as_number(v[0], at(key) + "[0]"), as_number(v[1], at(key) + "[1]")};
  }
  /// Every key present must have been read.
  void finish() const {
    for (auto it = j_.begin(); it != j_.end(); ++it)
      if (!used_.count(it.key())) throw Fail{at(it.key()), "unknown key"};
  }

  static double as_number(const json& v, const std::string& path) {
    if (!v.is_number()) throw Fail{path, "must be a number, not " + type_name(v)};
    const double d = v.get<double>();
    if (!std::isfinite(d)) throw Fail{path, "must be a finite number"};
    return d;
  }
  static glm::dvec3 as_vec3(const json& v, const std::string& path) {
    if (!v.is_array()) throw Fail{path, "must be a vector [x, y, z], not " + type_name(v)};
    if (v.size() != 3) throw Fail{path, "must be a vector of 3 numbers, not " + std::to_string(v.size())};
    return {as_number(v[0], path + "[0]"), as_number(v[1], path + "[1]"), as_number(v[2], path + "[2]")};
  }

 private:
  const json& j_;
  std::string path_;
  std::set<std::string> used_;
};

MesherHint parse_hint(Obj& o, const std::string& key) {
  const std::string s = o.string(key);
  if (s == "auto") return MesherHint::Auto;
  if (s == "global") return MesherHint::Global;
  if (s == "local") return MesherHint::Local;
  throw Fail{o.at(key), "must be \"auto\", \"global\" or \"local\", not \"" + s + "\""};
}

BooleanMode parse_boolean(Obj& o) {
  if (!o.has("boolean")) return BooleanMode::Auto;
  const std::string s = o.string("boolean");
  if (s == "auto") return BooleanMode::Auto;
  if (s == "minmax") return BooleanMode::MinMax;
  if (s == "rfunction") return BooleanMode::RFunction;
  throw Fail{o.at("boolean"), "must be \"auto\", \"minmax\" or \"rfunction\", not \"" + s + "\""};
}

Axis parse_axis(Obj& o) {
  if (!o.has("axis")) return Axis::Z;
  const std::string s = o.string("axis");
  if (s == "x") return Axis::X;
  if (s == "y") return Axis::Y;
  if (s == "z") return Axis::Z;
  throw Fail{o.at("axis"), "must be \"x\", \"y\" or \"z\", not \"" + s + "\""};
}

Falloff parse_falloff(Obj& o) { return {o.number("radius"), o.number("strength", 1.0)}; }

class Loader {
 public:
  explicit Loader(Builder& b) : b_(b) {}

  NodeId node(const json& j, const std::string& path, int depth) {
    if (depth > kMaxSceneDepth)
      throw Fail{path, "nests deeper than " + std::to_string(kMaxSceneDepth) + " nodes"};
    Obj o(j, path);
    const std::string type = o.string("type");
    std::string name;
    if (o.has("name")) name = o.string("name");
    NodeId id;
    try {
      id = build(o, type, depth);
    } catch (const BuildError& e) {
      throw Fail{o.at(e.key), e.what()};
    }
    o.finish();
    if (!name.empty()) b_.set_name(id, name);
    return id;
  }

 private:
  NodeId child(Obj& o, const std::string& key, int depth) { return node(o.get(key), o.at(key), depth + 1); }

  std::vector<NodeId> children(Obj& o, int depth) {
    const json& list = o.get("children");
    if (!list.is_array()) throw Fail{o.at("children"), "must be an array of nodes, not " + type_name(list)};
    if (list.empty()) throw Fail{o.at("children"), "must hold at least 1 node"};
    std::vector<NodeId> ids;
    for (std::size_t i = 0; i < list.size(); ++i)
      ids.push_back(node(list[i], o.at("children") + "[" + std::to_string(i) + "]", depth + 1));
    return ids;
  }

  std::vector<glm::dvec3> points(Obj& o) {
    const json& list = o.get("points");
    if (!list.is_array()) throw Fail{o.at("points"), "must be an array of vectors, not " + type_name(list)};
    std::vector<glm::dvec3> pts;
    for (std::size_t i = 0; i < list.size(); ++i)
      pts.push_back(Obj::as_vec3(list[i], o.at("points") + "[" + std::to_string(i) + "]"));
    return pts;
  }

  void hint(Obj& o, NodeId id) {
    if (o.has("mesher")) b_.set_mesher(id, parse_hint(o, "mesher"));
  }

  glm::dmat4 affine_matrix(Obj& o) {
    if (o.has("matrix")) {
      for (const char* k : {"scale", "rotate", "translate"})
        if (o.has(k)) throw Fail{o.at(k), "cannot be combined with matrix"};
      const json& m = o.get("matrix");
      std::vector<double> v;
      const std::string at = o.at("matrix");
      if (m.is_array() && m.size() == 4 && m[0].is_array()) {
        for (std::size_t r = 0; r < 4; ++r) {
          if (!m[r].is_array() || m[r].size() != 4) throw Fail{at + "[" + std::to_string(r) + "]", "must be a row of 4 numbers"};
          for (std::size_t c = 0; c < 4; ++c) v.push_back(Obj::as_number(m[r][c], at + "[" + std::to_string(r) + "][" + std::to_string(c) + "]"));
        }
      } else if (m.is_array() && m.size() == 16) {
        for (std::size_t i = 0; i < 16; ++i) v.push_back(Obj::as_number(m[i], at + "[" + std::to_string(i) + "]"));
      } else {
        throw Fail{at, "must be 16 numbers or 4 rows of 4 numbers (row-major)"};
      }
      glm::dmat4 out;
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) out[c][r] = v[std::size_t(4 * r + c)];
      return out;
    }
    glm::dmat4 m(1.0);
    if (o.has("translate")) m = glm::translate(m, o.vec3("translate"));
    if (o.has("rotate")) {
      Obj r(o.get("rotate"), o.at("rotate"));
      glm::dvec3 axis;
      const json& a = r.get("axis");
      if (a.is_string()) {
        const std::string s = a.get<std::string>();
        if (s == "x") axis = {1, 0, 0};
        else if (s == "y") axis = {0, 1, 0};
        else if (s == "z") axis = {0, 0, 1};
        else throw Fail{r.at("axis"), "must be \"x\", \"y\", \"z\" or a vector"};
      } else {
        axis = Obj::as_vec3(a, r.at("axis"));
        if (!(std::max({std::abs(axis.x), std::abs(axis.y), std::abs(axis.z)}) > 0.0))
          throw Fail{r.at("axis"), "must be a non-zero vector"};
      }
      const double degrees = r.number("degrees");
      r.finish();
      const double big = std::max({std::abs(axis.x), std::abs(axis.y), std::abs(axis.z)});  // as a normal's
      m = glm::rotate(m, glm::radians(degrees), glm::normalize(axis / big));
    }
    if (o.has("scale")) {
      const json& s = o.get("scale");
      const glm::dvec3 k = s.is_array() ? Obj::as_vec3(s, o.at("scale")) : glm::dvec3(Obj::as_number(s, o.at("scale")));
      if (k.x == 0.0 || k.y == 0.0 || k.z == 0.0) throw Fail{o.at("scale"), "must be non-zero (the map must be invertible)"};
      m = glm::scale(m, k);
    }
    return m;  // translate * rotate * scale: scale first, then rotate, then translate
  }

  NodeId build(Obj& o, const std::string& type, int depth) {
    if (type == "point") return b_.point(o.vec3("center"), parse_falloff(o));
    if (type == "segment") return b_.segment(o.vec3("a"), o.vec3("b"), parse_falloff(o));
    if (type == "circle") return b_.circle(o.vec3("center"), o.vec3("normal"), o.number("circle_radius"), parse_falloff(o));
    if (type == "disc") return b_.disc(o.vec3("center"), o.vec3("normal"), o.number("disc_radius"), parse_falloff(o));
    if (type == "triangle") return b_.triangle(o.vec3("a"), o.vec3("b"), o.vec3("c"), parse_falloff(o));
    if (type == "curve") {
      const auto pts = points(o);
      return b_.curve(pts, parse_falloff(o));
    }
    if (type == "box") return b_.box(o.vec3("min"), o.vec3("max"), parse_falloff(o));
    if (type == "cylinder") return b_.cylinder(o.vec3("a"), o.vec3("b"), o.number("cylinder_radius"), parse_falloff(o));
    if (type == "cone_sphere")
      return b_.cone_sphere(o.vec3("a"), o.vec3("b"), o.number("radius_a"), o.number("radius_b"), parse_falloff(o));
    if (type == "mesh") {
      const std::string file = o.string("file");
      const Falloff f = parse_falloff(o);
      const bool repair = o.boolean("repair", false);
      MeshInside inside = MeshInside::Closed;
      if (o.has("inside")) {
        const std::string s = o.string("inside");
        if (s == "winding") inside = MeshInside::Winding;
        else if (s != "closed") throw Fail{o.at("inside"), "must be \"closed\" or \"winding\", not \"" + s + "\""};
        if (inside == MeshInside::Winding && repair) throw Fail{o.at("repair"), "cannot be combined with \"inside\": \"winding\""};
      }
      return b_.mesh(file, f, repair, inside);
    }
    NodeId id;
    if (type == "blend") {
      id = b_.blend(children(o, depth));
    } else if (type == "union" || type == "intersection" || type == "difference") {
      const auto c = children(o, depth);
      const BooleanMode mode = parse_boolean(o);
      id = type == "union" ? b_.unite(c, mode) : type == "intersection" ? b_.intersect(c, mode) : b_.subtract(c, mode);
    } else if (type == "local_blend") {
      const NodeId a = child(o, "a", depth), b = child(o, "b", depth), r = child(o, "region", depth);
      id = b_.local_blend(a, b, r, parse_boolean(o));
    } else if (type == "crop") {
      const NodeId c = child(o, "child", depth);
      id = b_.crop(c, o.vec3("min"), o.vec3("max"));
    } else if (type == "affine") {
      const NodeId c = child(o, "child", depth);
      if (!o.has("matrix") && !o.has("scale") && !o.has("rotate") && !o.has("translate"))
        throw Fail{o.path(), "affine needs matrix or at least one of scale, rotate, translate"};
      const glm::dmat4 m = affine_matrix(o);
      try {
        id = b_.affine(c, m);
      } catch (const BuildError& e) {
        // Made from scale, rotate and translate, the matrix is no key of the scene's: what made
        // it singular is the scale (1e200 or 1e-200: invertible on paper, not in doubles).
        if (o.has("matrix") || e.key != "matrix") throw;
        const Fail unexplained{o.has("scale") ? o.at("scale") : o.path(), "makes the map singular in double precision (not invertible)"};
        if (!o.has("scale")) throw unexplained;
        const json& k = o.get("scale");
        const glm::dvec3 v = k.is_array() ? Obj::as_vec3(k, o.at("scale")) : glm::dvec3(Obj::as_number(k, o.at("scale")));
        // Why, from the scales' logarithms (their product may overflow on the way where the
        // determinant itself would not): the determinant past the doubles' range (1e200 cubed),
        // rounded to 0 (1e-200 cubed), or so small that its inverse is past it (1e-103 cubed);
        // else the scales lie too far apart for the builder's condition bound.
        const glm::dvec3 a = glm::abs(v);
        const double log_det = std::log10(a.x) + std::log10(a.y) + std::log10(a.z);
        const double log_ratio = std::log10(std::max({a.x, a.y, a.z})) - std::log10(std::min({a.x, a.y, a.z}));
        auto power = [](double log10_value) {
          char b[64];
          if (std::abs(log10_value) < 300)
            std::snprintf(b, sizeof b, "%.2g", std::pow(10.0, log10_value));
          else
            std::snprintf(b, sizeof b, "1e%+.0f", std::round(log10_value));
          return std::string(b);
        };
        std::string why;
        if (log_det > std::log10(std::numeric_limits<double>::max()))
          why = "its determinant, the scales' product (" + power(log_det) + "), is past the range of doubles";
        else if (log_det < std::log10(std::numeric_limits<double>::denorm_min()))
          why = "its determinant, the scales' product (" + power(log_det) + "), rounds to 0";
        else if (log_det < std::log10(std::numeric_limits<double>::min()))
          why = "its determinant, the scales' product (" + power(log_det) + "), has an inverse past the range of doubles";
        else if (log_ratio >= 12.0 - 1e-9)
          why = "its scales differ by a factor of " + power(log_ratio) + ", too far apart for doubles to invert (a condition of 1e12 or more)";
        else
          throw unexplained;  // the scales are not why (none of the above holds): said as before
        throw Fail{o.at("scale"), "makes the map singular in double precision: " + why};
      }
    } else if (type == "twist") {
      const NodeId c = child(o, "child", depth);
      id = b_.twist(c, parse_axis(o), o.vec3("center", glm::dvec3(0.0)), o.number("rate"));
    } else if (type == "taper") {
      const NodeId c = child(o, "child", depth);
      const auto [h0, h1] = o.pair("range");
      const auto [s0, s1] = o.pair("scale");
      id = b_.taper(c, parse_axis(o), o.vec3("center", glm::dvec3(0.0)), h0, h1, s0, s1);
    } else if (type == "bend") {
      const NodeId c = child(o, "child", depth);
      const auto [h0, h1] = o.pair("range");
      id = b_.bend(c, parse_axis(o), o.vec3("center", glm::dvec3(0.0)), h0, h1, o.number("rate"));
    } else if (type == "ffd") {
      const NodeId c = child(o, "child", depth);
      const json& d = o.get("dims");
      if (!d.is_array() || d.size() != 3) throw Fail{o.at("dims"), "must be [l, m, n]"};
      glm::ivec3 dims;
      for (int i = 0; i < 3; ++i) {
        const double v = Obj::as_number(d[std::size_t(i)], o.at("dims") + "[" + std::to_string(i) + "]");
        if (v != std::floor(v) || v < 1 || v > kFfdMaxDim)
          throw Fail{o.at("dims") + "[" + std::to_string(i) + "]", "must be a whole number from 1 to 64"};
        dims[i] = static_cast<int>(v);
      }
      const auto pts = points(o);
      id = b_.ffd(c, o.vec3("min"), o.vec3("max"), dims, pts, parse_falloff(o));
    } else {
      throw Fail{o.at("type"),
                 "unknown type \"" + type +
                     "\" (expected point, segment, circle, disc, triangle, curve, box, cylinder, cone_sphere, "
                     "mesh, blend, union, intersection, difference, local_blend, crop, affine, twist, taper, bend "
                     "or ffd)"};
    }
    hint(o, id);
    return id;
  }

  Builder& b_;
};

MesherSettings parse_mesher(Obj& top) {
  MesherSettings s;
  if (!top.has("mesher")) return s;
  Obj m(top.get("mesher"), "mesher");
  if (m.has("precision")) {
    s.precision = m.number("precision");
    if (!(s.precision > 0.0)) throw Fail{m.at("precision"), "must be > 0"};
  }
  if (m.has("strategy")) s.strategy = parse_hint(m, "strategy");
  if (m.has("blend_overlap")) {
    s.blend_overlap = m.number("blend_overlap");
    if (!(s.blend_overlap >= 0.0 && s.blend_overlap <= 1.0)) throw Fail{m.at("blend_overlap"), "must be in [0, 1]"};
  }
  m.finish();
  return s;
}

// The mesh files a scene's tree names, for loading them all at once before the tree is built
// (they are independent, and loading dominates a scene's set-up). A walk without recursion and
// without judgement: what it cannot read as a mesh file is left to the loader, which reports it.
std::vector<MeshFileRequest> mesh_files(const json& root) {
  std::vector<MeshFileRequest> out;
  std::vector<const json*> todo{&root};
  while (!todo.empty()) {
    const json& j = *todo.back();
    todo.pop_back();
    if (j.is_array()) {
      for (const json& e : j)
        if (e.is_object() || e.is_array()) todo.push_back(&e);  // not a curve's numbers one by one
      continue;
    }
    if (!j.is_object()) continue;
    const auto type = j.find("type"), file = j.find("file");
    if (type != j.end() && *type == "mesh" && file != j.end() && file->is_string()) {
      MeshFileRequest r{file->get<std::string>()};
      if (const auto repair = j.find("repair"); repair != j.end() && repair->is_boolean()) r.repair = repair->get<bool>();
      if (const auto inside = j.find("inside"); inside != j.end() && *inside == "winding") r.inside = MeshInside::Winding;
      out.push_back(std::move(r));
    }
    for (const auto& [key, value] : j.items())
      if (value.is_object() || value.is_array()) todo.push_back(&value);
  }
  return out;
}

}  // namespace

Tree load_scene_text(const std::string& text, const std::filesystem::path& base_dir, const std::string& source) {
  json doc;
  try {
    doc = json::parse(text);
  } catch (const json::parse_error& e) {
    // what() reads "[json.exception.parse_error.101] parse error at line 1, column 5: ...".
    std::string why = e.what();
    const auto at = why.find("parse error");
    if (at != std::string::npos) why = why.substr(at);
    throw SceneError(source, source + ": not valid JSON: " + why);
  } catch (const json::exception& e) {
    // A number too large for a double ("1e999"): the parser stops before any path is known.
    throw SceneError(source, source + ": " + overflow_message(text, e));
  }
  try {
    Obj top(doc, "");
    const json& version = top.get("hybridtree");
    if (!version.is_number() || version.get<double>() != 1.0)
      throw Fail{"hybridtree", "must be 1 (this is scene format version 1), not " + version.dump()};
    const double T = top.number("threshold", 0.5);
    if (!(T > 0.0)) throw Fail{"threshold", "must be > 0"};
    const MesherSettings settings = parse_mesher(top);
    Builder b(T);
    b.set_base_dir(base_dir);
    b.set_mesher_settings(settings);
    b.prefetch_meshes(mesh_files(top.get("root")));
    Loader loader(b);
    const NodeId root = loader.node(top.get("root"), "root", 0);
    top.finish();
    return b.build(root);
  } catch (const Fail& f) {
    throw SceneError(source, shorten_path(f.path), f.rule);
  }
}

Tree load_scene(const std::filesystem::path& file) {
  const std::string name = file.string();
  std::ifstream in(file, std::ios::binary);
  if (!in) throw SceneError(name, name + ": cannot open the scene file");
  // Read in pieces, so that a device or a stream that is no scene (/dev/zero, /dev/urandom) is
  // told apart by its first bytes or its size instead of filling memory: a scene is a JSON object.
  std::string text;
  std::vector<char> piece(std::size_t(1) << 16);
  bool looked = false;
  while (in) {
    in.read(piece.data(), std::streamsize(piece.size()));
    const std::size_t got = std::size_t(in.gcount());
    if (text.size() + got > kMaxSceneBytes)
      throw SceneError(name, name + ": is not a scene: it is larger than " + std::to_string(kMaxSceneBytes >> 20) + " MiB");
    const std::size_t from = text.size();
    text.append(piece.data(), got);
    if (looked) continue;
    // A UTF-8 byte order mark may open the file (the JSON parser skips it there only).
    const std::size_t start = text.size() >= 3 && text.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0;
    const std::size_t first = text.find_first_not_of(" \t\r\n", std::max(from, start));
    if (first == std::string::npos) continue;
    looked = true;
    if (text[first] != '{') {
      char hex[8];
      std::snprintf(hex, sizeof hex, "0x%02x", unsigned(static_cast<unsigned char>(text[first])));
      throw SceneError(name, name + ": is not a scene: a scene is a JSON object, which starts with '{', and byte " +
                                 std::to_string(first) + " is " + hex);
    }
  }
  if (in.bad()) throw SceneError(name, name + ": cannot read the scene file");
  return load_scene_text(text, file.parent_path(), name);
}

}  // namespace ht
