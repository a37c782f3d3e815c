#include "runtime/scene_write.hpp"

#include "nodes/mesh_leaf.hpp"
#include "nodes/primitives.hpp"
#include "nodes/warps.hpp"
#include "runtime/node_params.hpp"

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
      case Family::Primitive: primitive(n, j); break;
      case Family::Mesh: mesh(n, j); break;
      case Family::Warp: warp(n, p.data(), j); break;
      case Family::Operator: operation(n, j); break;
    }
    if ((kind_family(k) == Family::Operator || kind_family(k) == Family::Warp) && g_.mesher[n] != MesherHint::Auto)
      j["mesher"] = hint_name(g_.mesher[n]);
    return j;
  }

 private:
  void primitive(NodeId n, json& j) const {
    const NodeKind k = g_.kind[n];
    const params::Primitive prim = params::primitive(g_, n);
    j["radius"] = prim.R;
    j["strength"] = prim.F;
    const double* s = prim.skeleton;
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

  void mesh(NodeId n, json& j) const {
    const MeshLeaf& leaf = *g_.meshes[g_.mesh[n]];
    if (leaf.file().empty())
      throw SceneWriteError("mesh leaf " + g_.label(n) + " (" + leaf.name() + ") was made in memory: it has no file to name");
    std::error_code ec;
    const std::filesystem::path file = std::filesystem::absolute(leaf.file(), ec).lexically_normal();
    const std::filesystem::path dir = std::filesystem::absolute(dir_, ec).lexically_normal();
    const std::filesystem::path rel = file.lexically_relative(dir);
    j["file"] = (rel.empty() ? file : rel).generic_string();
    const params::MeshLeafParams m = params::mesh_leaf(g_, n);
    j["radius"] = m.R;
    j["strength"] = m.F;
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
      case NodeKind::Twist: {
        const params::Barr b = params::barr(g_, n);
        j["axis"] = axis_name(b.axis), j["center"] = vec3(&b.center.x), j["rate"] = b.rate;
        break;
      }
      case NodeKind::Taper: {
        const params::Barr b = params::barr(g_, n);
        j["axis"] = axis_name(b.axis), j["center"] = vec3(&b.center.x);
        j["range"] = json::array({b.h0, b.h1}), j["scale"] = json::array({b.s0, b.s1});
        break;
      }
      case NodeKind::Bend: {
        const params::Barr b = params::barr(g_, n);
        j["axis"] = axis_name(b.axis), j["center"] = vec3(&b.center.x);
        j["range"] = json::array({b.h0, b.h1}), j["rate"] = b.rate;
        break;
      }
      default: {
        const params::Ffd f = params::ffd(g_, n);
        j["min"] = vec3(&f.lattice.lo.x), j["max"] = vec3(&f.lattice.hi.x);
        j["dims"] = json::array({f.l, f.m, f.n});
        j["radius"] = f.R, j["strength"] = f.F;
        json pts = json::array();
        for (std::size_t i = 0; i + 2 < f.points.size(); i += 3) pts.push_back(vec3(f.points.data() + i));
        j["points"] = std::move(pts);
      }
    }
  }

  void operation(NodeId n, json& j) const {
    const NodeKind k = g_.kind[n];
    const auto c = g_.children_of(n);
    if (k == NodeKind::Crop) {
      const params::Crop crop = params::crop(g_, n);
      j["child"] = node(c[0]);
      j["min"] = vec3(&crop.box.lo.x), j["max"] = vec3(&crop.box.hi.x);
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
