#include "runtime/scene_write.hpp"

#include "nodes/mesh_leaf.hpp"
#include "nodes/primitives.hpp"
#include "nodes/warps.hpp"

#include <nlohmann/json.hpp>

namespace ht {
namespace {

using json = nlohmann::ordered_json;

json vec3(const double* v) { return json::array({v[0], v[1], v[2]}); }

const char* axis_name(double a) { return a == 0.0 ? "x" : a == 1.0 ? "y" : "z"; }

const char* hint_name(MesherHint h) {
  return h == MesherHint::Global ? "global" : h == MesherHint::Local ? "local" : "auto";
}

class Writer {
 public:
  Writer(const Graph& g, std::filesystem::path dir) : g_(g), dir_(std::move(dir)) {}

  json node(NodeId n) const {
    json j;
    const NodeKind k = g_.kind[n];
    j["type"] = std::string(kind_name(k));
    if (g_.name[n] != kNone) j["name"] = g_.names[g_.name[n]];
    const auto p = g_.params_of(n);
    switch (kind_family(k)) {
      case Family::Primitive: primitive(k, p.data(), j); break;
      case Family::Mesh: mesh(n, p.data(), j); break;
      case Family::Warp: warp(n, p.data(), j); break;
      case Family::Operator: operation(n, p.data(), j); break;
    }
    if ((kind_family(k) == Family::Operator || kind_family(k) == Family::Warp) && g_.mesher[n] != MesherHint::Auto)
      j["mesher"] = hint_name(g_.mesher[n]);
    return j;
  }

 private:
  static void primitive(NodeKind k, const double* p, json& j) {
    j["radius"] = p[kPrimR];
    j["strength"] = p[kPrimF];
    const double* s = p + kPrimSkeleton;
    switch (k) {
      case NodeKind::Point: j["center"] = vec3(s); break;
      case NodeKind::Segment: j["a"] = vec3(s), j["b"] = vec3(s + 3); break;
      case NodeKind::Circle: j["center"] = vec3(s), j["normal"] = vec3(s + 3), j["circle_radius"] = s[6]; break;
      case NodeKind::Disc: j["center"] = vec3(s), j["normal"] = vec3(s + 3), j["disc_radius"] = s[6]; break;
      case NodeKind::Triangle: j["a"] = vec3(s), j["b"] = vec3(s + 3), j["c"] = vec3(s + 6); break;
      case NodeKind::Curve: {
        json pts = json::array();
        for (int i = 0; i < static_cast<int>(s[0]); ++i) pts.push_back(vec3(s + 1 + 3 * i));
        j["points"] = std::move(pts);
        break;
      }
      case NodeKind::Box: j["min"] = vec3(s), j["max"] = vec3(s + 3); break;
      case NodeKind::Cylinder: j["a"] = vec3(s), j["b"] = vec3(s + 3), j["cylinder_radius"] = s[6]; break;
      default: j["a"] = vec3(s), j["b"] = vec3(s + 3), j["radius_a"] = s[6], j["radius_b"] = s[7]; break;
    }
  }

  void mesh(NodeId n, const double* p, json& j) const {
    const MeshLeaf& leaf = *g_.meshes[g_.mesh[n]];
    if (leaf.file().empty())
      throw SceneWriteError("mesh leaf " + g_.label(n) + " (" + leaf.name() + ") was made in memory: it has no file to name");
    std::error_code ec;
    const std::filesystem::path file = std::filesystem::absolute(leaf.file(), ec).lexically_normal();
    const std::filesystem::path dir = std::filesystem::absolute(dir_, ec).lexically_normal();
    const std::filesystem::path rel = file.lexically_relative(dir);
    j["file"] = (rel.empty() ? file : rel).generic_string();
    j["radius"] = p[0];
    j["strength"] = p[1];
    if (leaf.inside_mode() == MeshInside::Winding) j["inside"] = "winding";
    if (leaf.repair_requested()) j["repair"] = true;
  }

  void warp(NodeId n, const double* p, json& j) const {
    const NodeKind k = g_.kind[n];
    j["child"] = node(g_.children_of(n)[0]);
    switch (k) {
      case NodeKind::Affine: {
        json rows = json::array();
        for (int r = 0; r < 3; ++r) rows.push_back(json::array({p[4 * r], p[4 * r + 1], p[4 * r + 2], p[4 * r + 3]}));
        rows.push_back(json::array({0.0, 0.0, 0.0, 1.0}));
        j["matrix"] = std::move(rows);
        break;
      }
      case NodeKind::Twist: j["axis"] = axis_name(p[0]), j["center"] = vec3(p + 1), j["rate"] = p[4]; break;
      case NodeKind::Taper:
        j["axis"] = axis_name(p[0]), j["center"] = vec3(p + 1);
        j["range"] = json::array({p[4], p[5]}), j["scale"] = json::array({p[6], p[7]});
        break;
      case NodeKind::Bend:
        j["axis"] = axis_name(p[0]), j["center"] = vec3(p + 1), j["range"] = json::array({p[4], p[5]}), j["rate"] = p[6];
        break;
      default: {  // ffd: min max l m n radius strength, then the control points
        j["min"] = vec3(p), j["max"] = vec3(p + 3);
        j["dims"] = json::array({static_cast<int>(p[6]), static_cast<int>(p[7]), static_cast<int>(p[8])});
        j["radius"] = p[9], j["strength"] = p[10];
        const std::size_t count = (g_.param_count[n] - kFfdHeader) / 3;
        json pts = json::array();
        for (std::size_t i = 0; i < count; ++i) pts.push_back(vec3(p + kFfdHeader + 3 * i));
        j["points"] = std::move(pts);
      }
    }
  }

  void operation(NodeId n, const double* p, json& j) const {
    const NodeKind k = g_.kind[n];
    const auto c = g_.children_of(n);
    if (k == NodeKind::Crop) {
      j["child"] = node(c[0]);
      j["min"] = vec3(p), j["max"] = vec3(p + 3);
      return;
    }
    if (k == NodeKind::LocalBlend) {
      j["a"] = node(c[0]), j["b"] = node(c[1]), j["region"] = node(c[2]);
    } else {
      json kids = json::array();
      for (NodeId child : c) kids.push_back(node(child));
      j["children"] = std::move(kids);
    }
    if (g_.boolean[n] == BooleanMode::MinMax) j["boolean"] = "minmax";
    if (g_.boolean[n] == BooleanMode::RFunction) j["boolean"] = "rfunction";
  }

  const Graph& g_;
  std::filesystem::path dir_;
};

}  // namespace

std::string write_scene_text(const Tree& tree, const std::filesystem::path& scene_dir) {
  json doc;
  doc["hybridtree"] = 1;
  doc["threshold"] = tree.threshold();
  const MesherSettings& m = tree.mesher_settings();
  json mesher = json::object();
  if (m.precision > 0.0) mesher["precision"] = m.precision;
  if (m.strategy != MesherHint::Auto) mesher["strategy"] = hint_name(m.strategy);
  if (m.blend_overlap != MesherSettings{}.blend_overlap) mesher["blend_overlap"] = m.blend_overlap;
  if (!mesher.empty()) doc["mesher"] = std::move(mesher);
  doc["root"] = Writer(tree.graph(), scene_dir).node(tree.root());
  return doc.dump() + "\n";  // one line: indenting a chain 900 deep would take 900 spaces a line
}

}  // namespace ht
