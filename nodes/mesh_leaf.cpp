// Mesh leaves: reading, validation, orientation, repair, and the Embree queries behind the
// pseudo-distance field. The contract is in nodes/mesh_leaf.hpp; the field in SCENE_FORMAT.md.
//
// Loading goes: faces as the file states them -> checks on indices and coordinates -> edge
// topology (non-manifold and open edges) -> consistent orientation per shell (BFS over edges)
// -> optional hole filling -> Embree scene (one geometry per shell) -> outward orientation of
// each shell from its nesting depth and signed volume -> angle-weighted pseudo-normals.
#include "nodes/mesh_leaf.hpp"

#include "nodes/mesh_text.hpp"
#include "nodes/openmesh_io.hpp"
#include "nodes/primitives.hpp"
#include "nodes/trimesh.hpp"

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/IO/importer/ImporterT.hh>
#include <embree3/rtcore.h>
#include <glm/geometric.hpp>
#include <glm/vec4.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <cfloat>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <numeric>
#include <sstream>
#include <string_view>
#include <unordered_map>
#include <utility>

namespace ht {
namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::size_t kMaxHoleEdges = 64;
// Embree works in float and asserts (aborting the process) on a ray whose origin lies past about
// 1.8e18 (fuzz_mesh_off: a vertex at 5.5e24 put a shell's probe ray there). Meshes stay inside
// this; points beyond it are answered without Embree.
constexpr double kMaxCoordinate = 1e18;

double largest_coordinate(const glm::dvec3& p) { return std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}); }

[[noreturn]] void fail(const std::string& name, const std::string& what) {
  throw MeshError(name + ": " + what);
}

std::string edge_text(std::uint32_t a, std::uint32_t b) {
  return "between vertices " + std::to_string(a) + " and " + std::to_string(b);
}

// Every use of OpenMesh's IO holds openmesh_io_mutex() (nodes/openmesh_io.hpp) and its chatter
// is muted: our own messages say what is wrong, with the file name.
class QuietOpenMesh {
 public:
  QuietOpenMesh()
      : lock_(openmesh_io_mutex()),
        err_(::omerr().is_enabled()),
        log_(::omlog().is_enabled()),
        out_(::omout().is_enabled()) {
    ::omerr().disable();
    ::omlog().disable();
    ::omout().disable();
  }
  ~QuietOpenMesh() {
    if (err_) ::omerr().enable();
    if (log_) ::omlog().enable();
    if (out_) ::omout().enable();
  }
  QuietOpenMesh(const QuietOpenMesh&) = delete;
  QuietOpenMesh& operator=(const QuietOpenMesh&) = delete;

 private:
  std::lock_guard<std::mutex> lock_;
  bool err_, log_, out_;
};

// Records what the reader states before OpenMesh's importer gets to "fix" it: the importer
// drops faces with bad indices and duplicates the vertices of faces that would make an edge
// non-manifold, which would hide exactly the defects validation has to report.
class RecordingImporter : public OpenMesh::IO::ImporterT<TriMesh> {
  using Base = OpenMesh::IO::ImporterT<TriMesh>;

 public:
  explicit RecordingImporter(TriMesh& mesh) : Base(mesh) {}

  OpenMesh::VertexHandle add_vertex(const OpenMesh::Vec3f& p) override { return note(Base::add_vertex(p)); }
  OpenMesh::VertexHandle add_vertex(const OpenMesh::Vec3d& p) override { return note(Base::add_vertex(p)); }
  OpenMesh::VertexHandle add_vertex() override { return note(Base::add_vertex()); }

  OpenMesh::FaceHandle add_face(const VHandles& face) override {
    faces.emplace_back();
    faces.back().reserve(face.size());
    for (const auto& vh : face) {
      const int h = vh.idx();
      // A handle the reader never got from add_vertex (an index past the vertex list) maps to
      // kNone, reported below as out of range.
      faces.back().push_back(h >= 0 && static_cast<std::size_t>(h) < index_of.size()
                                 ? index_of[static_cast<std::size_t>(h)]
                                 : kNone);
    }
    return Base::add_face(face);
  }

  /// Reader handles in the order the file lists the vertices.
  std::vector<OpenMesh::VertexHandle> vertices;
  std::vector<std::vector<std::uint32_t>> faces;

 private:
  OpenMesh::VertexHandle note(OpenMesh::VertexHandle vh) {
    const auto h = static_cast<std::size_t>(vh.idx());
    if (index_of.size() <= h) index_of.resize(h + 1, kNone);
    index_of[h] = static_cast<std::uint32_t>(vertices.size());
    vertices.push_back(vh);
    return vh;
  }
  std::vector<std::uint32_t> index_of;  // mesh handle -> file vertex index
};

// OpenMesh's text readers do not report a "nan" or "inf" coordinate: the OFF reader's stream
// fails and reads zeros from there on, the OBJ reader drops the vertex (shifting every later
// index). Both would surface as some unrelated defect, so text files are searched for such a
// number first. Returns what is wrong and where, or "" when the file has none. Binary files are
// left to the check on the positions read.
std::string non_finite_number(const std::string& text, const std::string& ext) {
  auto lower = [](char ch) { return ch >= 'A' && ch <= 'Z' ? static_cast<char>(ch - 'A' + 'a') : ch; };
  bool suspect = false;  // cheap pass: most files contain neither word anywhere
  for (std::size_t i = 0; i + 2 < text.size() && !suspect; ++i) {
    const char a = lower(text[i]), b = lower(text[i + 1]), c = lower(text[i + 2]);
    suspect = (a == 'n' && b == 'a' && c == 'n') || (a == 'i' && b == 'n' && c == 'f');
  }
  if (!suspect) return {};

  auto non_finite = [&](std::string_view tok) {
    if (!tok.empty() && (tok[0] == '+' || tok[0] == '-')) tok.remove_prefix(1);
    if (tok.size() < 3) return false;
    const std::string head{lower(tok[0]), lower(tok[1]), lower(tok[2])};
    return head == "nan" || head == "inf";
  };
  std::istringstream lines(text);
  std::string line;
  std::size_t line_no = 0;
  // Vertex records: how many are still to come (OFF, PLY) and the index of the next one.
  enum class State {
    Header,
    Counts,
    Vertices,
    Free
  } state = ext == ".obj" || ext == ".stl" ? State::Free : State::Header;
  std::size_t vertices_left = 0, vertex = 0, ply_vertices = 0;
  bool ply_vertex_first = false, ply_seen_element = false;
  while (std::getline(lines, line)) {
    ++line_no;
    std::istringstream words(line);
    std::vector<std::string> tok{std::istream_iterator<std::string>(words),
                                 std::istream_iterator<std::string>()};
    tok.erase(std::find_if(tok.begin(), tok.end(), [](const std::string& t) { return t[0] == '#'; }),
              tok.end());
    if (tok.empty()) continue;
    bool is_vertex = false;
    if (ext == ".obj") {
      is_vertex = tok[0] == "v";
      if (!is_vertex) continue;
      tok.erase(tok.begin());
    } else if (ext == ".stl") {
      if (tok[0] != "vertex") continue;
      tok.erase(tok.begin());
    } else if (ext == ".off") {
      if (state == State::Header) {
        if (tok[0].find("BINARY") != std::string::npos || (tok.size() > 1 && tok[1] == "BINARY")) return {};
        state = State::Counts;
        if (tok.size() == 1) continue;
        tok.erase(tok.begin());  // counts on the keyword's line
      }
      if (state == State::Counts) {
        vertices_left = std::strtoull(tok[0].c_str(), nullptr, 10);
        state = State::Vertices;
        continue;
      }
      is_vertex = state == State::Vertices && vertices_left > 0;
    } else {  // .ply
      if (state == State::Header) {
        if (tok[0] == "format" && tok.size() > 1 && tok[1] != "ascii") return {};
        if (tok[0] == "element" && tok.size() > 2) {
          if (!ply_seen_element && tok[1] == "vertex") {
            ply_vertex_first = true;
            ply_vertices = std::strtoull(tok[2].c_str(), nullptr, 10);
          }
          ply_seen_element = true;
        }
        if (tok[0] == "end_header") {
          state = State::Vertices;
          vertices_left = ply_vertex_first ? ply_vertices : 0;
        }
        continue;
      }
      is_vertex = vertices_left > 0;
    }
    const bool bad = std::any_of(tok.begin(), tok.end(), [&](const std::string& t) { return non_finite(t); });
    if (bad && is_vertex)
      return "vertex " + std::to_string(vertex) + " has a non-finite coordinate (line " +
             std::to_string(line_no) + ")";
    if (bad) return "line " + std::to_string(line_no) + " has a non-finite number";
    if (is_vertex) {
      ++vertex;
      if (vertices_left > 0) --vertices_left;
    }
  }
  return {};
}

// OpenMesh's OFF reader takes neither comments nor the counts on the keyword's line, both of
// which the format allows; such text is rewritten into the plain layout it reads. Binary OFF is
// returned as is.
std::string plain_off(std::string text) {
  const std::size_t eol = text.find('\n');
  const std::string first = text.substr(0, eol);
  if (first.find("BINARY") != std::string::npos) return text;
  std::istringstream head(first);
  std::string keyword, more;
  const bool counts_on_keyword_line = static_cast<bool>(head >> keyword >> more) && more[0] != '#';
  if (text.find('#') == std::string::npos && !counts_on_keyword_line) return text;
  std::string out;
  out.reserve(text.size());
  std::istringstream lines(std::move(text));
  std::string line;
  bool header = true;
  while (std::getline(lines, line)) {
    line.erase(std::min(line.find('#'), line.size()));
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    if (header) {  // keyword alone on its line, counts (if any) on the next
      std::istringstream words(line);
      std::string word;
      words >> word;
      out += word + '\n';
      line.erase(0, line.find(word) + word.size());
      header = false;
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    }
    out += line;
    out += '\n';
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Edge topology. Half-edge h = 3t + k runs from tri[t][k] to tri[t][(k+1)%3]; nbr[h] is the
// triangle across it (kNone on a boundary).

struct Topology {
  std::vector<std::uint32_t> nbr;
  std::size_t boundary = 0, nonmanifold = 0;
  std::uint32_t first_boundary = kNone, first_nonmanifold = kNone;  // a half-edge, face order
};

std::uint32_t corner(const glm::uvec3& t, std::uint32_t k) { return t[static_cast<glm::length_t>(k % 3)]; }

Topology edge_topology(const std::vector<glm::uvec3>& tris) {
  Topology topo;
  const std::size_t nh = 3 * tris.size();
  topo.nbr.assign(nh, kNone);
  // Sorting (undirected edge, half-edge) pairs groups the faces of each edge without a hash
  // map, and the order within a group stays the face order, so messages are deterministic.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(nh);
  for (std::uint32_t h = 0; h < nh; ++h) {
    const std::uint32_t a = corner(tris[h / 3], h % 3), b = corner(tris[h / 3], h % 3 + 1);
    keyed[h] = {(static_cast<std::uint64_t>(std::min(a, b)) << 32) | std::max(a, b), h};
  }
  std::sort(keyed.begin(), keyed.end());
  for (std::size_t i = 0; i < nh;) {
    std::size_t j = i + 1;
    while (j < nh && keyed[j].first == keyed[i].first) ++j;
    const std::uint32_t h0 = keyed[i].second;
    if (j - i == 1) {
      ++topo.boundary;
      topo.first_boundary = std::min(topo.first_boundary, h0);
    } else if (j - i == 2) {
      const std::uint32_t h1 = keyed[i + 1].second;
      topo.nbr[h0] = h1 / 3;
      topo.nbr[h1] = h0 / 3;
    } else {
      ++topo.nonmanifold;
      topo.first_nonmanifold = std::min(topo.first_nonmanifold, h0);
    }
    i = j;
  }
  return topo;
}

// Reverses triangle t, keeping the neighbour table valid: after swapping corners 1 and 2 the
// half-edges 0 and 2 trade places (and all three run backwards).
void flip_triangle(std::vector<glm::uvec3>& tris, Topology& topo, std::uint32_t t) {
  std::swap(tris[t][1], tris[t][2]);
  std::swap(topo.nbr[3 * t], topo.nbr[3 * t + 2]);
}

// Does triangle g run edge a->b backwards (b->a), as a consistently oriented neighbour must?
bool opposes(const glm::uvec3& g, std::uint32_t a, std::uint32_t b) {
  for (std::uint32_t i = 0; i < 3; ++i)
    if (corner(g, i) == a) return corner(g, i + 2) == b;
  return false;
}

struct Shells {
  std::vector<std::uint32_t> of;  // shell of each triangle
  std::uint32_t count = 0;
};

// Breadth-first over edge adjacency; each shell keeps the orientation of its lowest-numbered
// triangle and every other triangle is made to agree with the neighbour that reached it.
Shells orient_shells(const std::string& name, std::vector<glm::uvec3>& tris, Topology& topo,
                     std::vector<std::uint8_t>& flipped) {
  Shells shells;
  shells.of.assign(tris.size(), kNone);
  std::vector<std::uint32_t> queue;
  for (std::uint32_t seed = 0; seed < tris.size(); ++seed) {
    if (shells.of[seed] != kNone) continue;
    const std::uint32_t s = shells.count++;
    shells.of[seed] = s;
    queue.assign(1, seed);
    for (std::size_t qi = 0; qi < queue.size(); ++qi) {
      const std::uint32_t t = queue[qi];
      for (std::uint32_t k = 0; k < 3; ++k) {
        const std::uint32_t g = topo.nbr[3 * t + k];
        if (g == kNone) continue;
        const std::uint32_t a = corner(tris[t], k), b = corner(tris[t], k + 1);
        if (shells.of[g] == kNone) {
          if (!opposes(tris[g], a, b)) {
            flip_triangle(tris, topo, g);
            flipped[g] ^= 1u;
          }
          shells.of[g] = s;
          queue.push_back(g);
        } else if (!opposes(tris[g], a, b)) {
          fail(name, "the faces cannot be oriented consistently (a non-orientable surface; edge " +
                         edge_text(a, b) + ")");
        }
      }
    }
  }
  return shells;
}

// Closes every boundary loop with a fan around its centroid (a single triangle for three
// edges). Loops are walked along the reversed boundary half-edges, which are exactly the edges
// the filling triangles need, and split wherever the walk revisits a vertex, so a loop never
// passes a vertex twice (which would make the fan's spokes non-manifold).
void fill_holes(const std::string& name, std::vector<glm::dvec3>& pos, std::vector<glm::uvec3>& tris,
                const Topology& topo, MeshReport& report) {
  struct Edge {
    std::uint32_t from, to;
  };
  std::vector<Edge> edges;
  for (std::uint32_t h = 0; h < topo.nbr.size(); ++h)
    if (topo.nbr[h] == kNone) edges.push_back({corner(tris[h / 3], h % 3 + 1), corner(tris[h / 3], h % 3)});
  std::vector<std::uint32_t> by_from(edges.size());
  std::iota(by_from.begin(), by_from.end(), 0u);
  std::stable_sort(by_from.begin(), by_from.end(),
                   [&](std::uint32_t x, std::uint32_t y) { return edges[x].from < edges[y].from; });
  std::vector<std::uint8_t> used(edges.size(), 0);
  auto next_from = [&](std::uint32_t v) -> std::uint32_t {
    auto it = std::lower_bound(by_from.begin(), by_from.end(), v,
                               [&](std::uint32_t e, std::uint32_t x) { return edges[e].from < x; });
    for (; it != by_from.end() && edges[*it].from == v; ++it)
      if (!used[*it]) return *it;
    return kNone;
  };

  auto close_loop = [&](const std::vector<std::uint32_t>& loop) {  // loop: vertices in order
    const std::size_t m = loop.size();
    if (m > kMaxHoleEdges)
      fail(name, "a hole of " + std::to_string(m) + " boundary edges (first " + edge_text(loop[0], loop[1]) +
                     ") is larger than the " + std::to_string(kMaxHoleEdges) + " edges \"repair\" closes");
    ++report.holes_closed;
    if (m == 3) {
      tris.emplace_back(loop[0], loop[1], loop[2]);
      ++report.triangles_added;
      return;
    }
    glm::dvec3 c(0.0);
    for (std::uint32_t v : loop) c += pos[v];
    const auto centre = static_cast<std::uint32_t>(pos.size());
    pos.push_back(c / static_cast<double>(m));
    for (std::size_t i = 0; i < m; ++i) tris.emplace_back(loop[i], loop[(i + 1) % m], centre);
    report.triangles_added += m;
  };

  std::vector<std::uint32_t> path;                    // vertices walked, path[0] is the start
  std::unordered_map<std::uint32_t, std::size_t> at;  // vertex -> position in path
  for (std::uint32_t e0 = 0; e0 < edges.size(); ++e0) {
    if (used[e0]) continue;
    path.assign(1, edges[e0].from);
    at.clear();
    at[edges[e0].from] = 0;
    std::uint32_t e = e0;
    while (true) {
      used[e] = 1;
      const std::uint32_t w = edges[e].to;
      if (auto it = at.find(w); it != at.end()) {
        const std::size_t p = it->second;
        std::vector<std::uint32_t> loop(path.begin() + static_cast<std::ptrdiff_t>(p), path.end());
        for (std::size_t i = p + 1; i < path.size(); ++i) at.erase(path[i]);
        path.resize(p + 1);
        close_loop(loop);
        if (p == 0) break;  // back at the start: this walk is done
      } else {
        at[w] = path.size();
        path.push_back(w);
      }
      e = next_from(path.back());
      // In a consistently oriented surface every boundary vertex has as many boundary edges
      // leaving as entering, so the walk cannot get stuck; guard anyway.
      if (e == kNone)
        fail(name, "cannot trace the boundary loop through vertex " + std::to_string(path.back()));
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Geometry in double.

// Closest points on triangles come from nodes/primitives.hpp, with the feature they lie on.
using Nearest = TrianglePoint;
constexpr int kFace = kTriangleFace, kEdge = kTriangleEdge, kVertex = kTriangleVertex;

glm::dvec3 unit_or_zero(const glm::dvec3& v) {
  const double l = glm::length(v);
  return l > 0 && std::isfinite(l) ? v / l : glm::dvec3(0.0);
}

// Fixed, non-axis-aligned ray directions for the parity vote: meshes are often built on axis
// planes and diagonals, where rays would graze edges.
constexpr std::array<std::array<float, 3>, 3> kRayDirs = {
    {{0.5219f, 0.7231f, 0.4527f}, {-0.6873f, 0.2129f, 0.6946f}, {0.3197f, -0.8141f, 0.4847f}}};

}  // namespace

// ---------------------------------------------------------------------------------------------
// Acceleration: Embree scene over float copies of the vertices (geometry s = shell s), and the
// pseudo-normals, in double, of the final orientation.

namespace {
struct DeviceRelease {
  void operator()(RTCDevice d) const { rtcReleaseDevice(d); }
};
struct SceneRelease {
  void operator()(RTCScene s) const { rtcReleaseScene(s); }
};
// What a point query reads of each triangle, stored in Embree's (shell, primID) order, which
// follows a Morton curve: a query's visits then touch neighbouring records instead of five
// scattered arrays (those cache misses were most of a query's time).
struct TriRecord {
  glm::dvec3 a, b, c;
  glm::dvec3 centre;  // centroid; with reach, a bounding sphere that rejects far triangles early
  double reach;
  std::uint32_t tri;  // index into triangles_
};

}  // namespace

struct MeshLeaf::Accel {
  // Embree reference-counts the device, so the scene may be released after or before it.
  std::unique_ptr<RTCDeviceTy, DeviceRelease> device;
  std::unique_ptr<RTCSceneTy, SceneRelease> scene;
  std::vector<float> vertices;            // xyz per vertex, plus padding Embree reads past the end
  std::vector<std::uint32_t> order;       // triangles grouped by shell: global index of (shell, primID)
  std::vector<std::uint32_t> offset;      // start of each shell in `order`
  std::vector<glm::dvec3> face_normal;    // unit, zero for degenerate triangles
  std::vector<glm::dvec3> vertex_normal;  // angle-weighted sum of incident face normals
  std::vector<std::uint8_t> complex_vertex;  // several fans meet there (see compute_normals)
  std::vector<std::uint32_t> nbr;         // triangle across each half-edge: edge normal = sum of two
  std::vector<TriRecord> records;        // Embree's (shell, primID) order, see TriRecord
  double scale = 0;                       // largest coordinate magnitude, for float slack

  // Orders each shell's triangles along a Morton curve of their centroids (10 bits per axis
  // over the mesh's box), so that triangles near in space are near in memory.
  void morton_sort_shells(const std::vector<glm::dvec3>& pos, const std::vector<glm::uvec3>& tris) {
    glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    for (const auto& v : pos) {
      lo = glm::min(lo, v);
      hi = glm::max(hi, v);
    }
    const glm::dvec3 scale3 = 1023.0 / glm::max(hi - lo, glm::dvec3(1e-300));
    auto spread = [](std::uint64_t x) {  // 10 bits -> every third bit of 30
      x &= 0x3ff;
      x = (x | (x << 16)) & 0x30000ff;
      x = (x | (x << 8)) & 0x300f00f;
      x = (x | (x << 4)) & 0x30c30c3;
      x = (x | (x << 2)) & 0x9249249;
      return x;
    };
    std::vector<std::uint64_t> code(tris.size());
    for (std::size_t t = 0; t < tris.size(); ++t) {
      const glm::dvec3 c = (pos[tris[t][0]] + pos[tris[t][1]] + pos[tris[t][2]]) / 3.0;
      const glm::dvec3 q = glm::clamp((c - lo) * scale3, glm::dvec3(0.0), glm::dvec3(1023.0));
      code[t] = spread(static_cast<std::uint64_t>(q.x)) | (spread(static_cast<std::uint64_t>(q.y)) << 1) |
                (spread(static_cast<std::uint64_t>(q.z)) << 2);
    }
    for (std::size_t s = 0; s + 1 < offset.size(); ++s)
      std::stable_sort(order.begin() + offset[s], order.begin() + offset[s + 1],
                       [&](std::uint32_t x, std::uint32_t y) { return code[x] < code[y]; });
  }

  Accel(const std::string& name, const std::vector<glm::dvec3>& pos, const std::vector<glm::uvec3>& tris,
        const Shells& shells) {
    device.reset(rtcNewDevice(nullptr));
    if (!device) fail(name, "cannot create an Embree device");
    vertices.resize(3 * pos.size() + 1);  // the extra float: Embree loads vertices as 16 bytes
    for (std::size_t v = 0; v < pos.size(); ++v)
      for (int i = 0; i < 3; ++i) {
        vertices[3 * v + static_cast<std::size_t>(i)] = static_cast<float>(pos[v][i]);
        scale = std::max(scale, std::abs(pos[v][i]));
      }
    offset.assign(shells.count + 1, 0);
    for (std::uint32_t s : shells.of) ++offset[s + 1];
    std::partial_sum(offset.begin(), offset.end(), offset.begin());
    order.resize(tris.size());
    std::vector<std::uint32_t> fill(offset.begin(), offset.end() - 1);
    for (std::uint32_t t = 0; t < tris.size(); ++t) order[fill[shells.of[t]]++] = t;
    morton_sort_shells(pos, tris);

    scene.reset(rtcNewScene(device.get()));
    if (!scene) fail(name, "cannot create an Embree scene");
    // Robust traversal does not lose hits on shared edges, which the parity counts rely on;
    // high quality spends build time once for the many queries a mesher makes.
    rtcSetSceneFlags(scene.get(), RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene.get(), RTC_BUILD_QUALITY_HIGH);
    for (std::uint32_t s = 0; s < shells.count; ++s) {
      RTCGeometry geom = rtcNewGeometry(device.get(), RTC_GEOMETRY_TYPE_TRIANGLE);
      if (!geom) fail(name, "cannot create an Embree geometry");
      rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, vertices.data(), 0,
                                 3 * sizeof(float), pos.size());
      const std::size_t n = offset[s + 1] - offset[s];
      auto* idx = static_cast<std::uint32_t*>(rtcSetNewGeometryBuffer(
          geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(std::uint32_t), n));
      if (!idx) {
        rtcReleaseGeometry(geom);
        fail(name, "Embree could not allocate its index buffer");
      }
      for (std::size_t i = 0; i < n; ++i)
        for (std::uint32_t k = 0; k < 3; ++k) idx[3 * i + k] = corner(tris[order[offset[s] + i]], k);
      rtcCommitGeometry(geom);
      rtcAttachGeometryByID(scene.get(), geom, s);
      rtcReleaseGeometry(geom);  // the scene holds it now
    }
    rtcCommitScene(scene.get());
    if (rtcGetDeviceError(device.get()) != RTC_ERROR_NONE) fail(name, "Embree could not build its BVH");
  }

  // Calls visit(geomID) for every surface crossing along the ray from p. Each call restarts
  // just past the previous hit, so hits of the two triangles of an edge at the same t count once.
  template <class Visit>
  void crossings(const glm::dvec3& p, const std::array<float, 3>& dir, Visit&& visit) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh{};
    rh.ray.org_x = static_cast<float>(p.x);
    rh.ray.org_y = static_cast<float>(p.y);
    rh.ray.org_z = static_cast<float>(p.z);
    rh.ray.dir_x = dir[0];
    rh.ray.dir_y = dir[1];
    rh.ray.dir_z = dir[2];
    rh.ray.tnear = 0.0f;
    rh.ray.mask = ~0u;
    for (std::size_t guard = 0; guard <= order.size(); ++guard) {
      rh.ray.tfar = std::numeric_limits<float>::infinity();
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(scene.get(), &ctx, &rh);
      if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return;
      visit(rh.hit.geomID);
      rh.ray.tnear = std::nextafter(rh.ray.tfar, std::numeric_limits<float>::infinity());
    }
  }

  void compute_normals(const std::vector<glm::dvec3>& pos, const std::vector<glm::uvec3>& tris,
                       std::vector<std::uint32_t> neighbours) {
    nbr = std::move(neighbours);
    // Built from the final, oriented triangles, so that a mesh and its flipped twin answer alike
    // to the last bit.
    records.resize(tris.size());
    for (std::size_t slot = 0; slot < order.size(); ++slot) {
      const glm::uvec3 t = tris[order[slot]];
      TriRecord& r = records[slot];
      r.a = pos[t[0]];
      r.b = pos[t[1]];
      r.c = pos[t[2]];
      r.centre = (r.a + r.b + r.c) / 3.0;
      r.reach = std::max({glm::length(r.a - r.centre), glm::length(r.b - r.centre), glm::length(r.c - r.centre)});
      r.tri = order[slot];
    }
    face_normal.resize(tris.size());
    vertex_normal.assign(pos.size(), glm::dvec3(0.0));
    for (std::size_t t = 0; t < tris.size(); ++t) {
      const glm::dvec3 p[3] = {pos[tris[t][0]], pos[tris[t][1]], pos[tris[t][2]]};
      const glm::dvec3 n = unit_or_zero(glm::cross(p[1] - p[0], p[2] - p[0]));
      face_normal[t] = n;
      for (int k = 0; k < 3; ++k) {
        const glm::dvec3 e1 = p[(k + 1) % 3] - p[k], e2 = p[(k + 2) % 3] - p[k];
        const double angle = std::atan2(glm::length(glm::cross(e1, e2)), glm::dot(e1, e2));
        vertex_normal[tris[t][k]] += angle * n;
      }
    }
    // A vertex where shells (or two cones of one shell) touch has several fans of triangles; its
    // summed pseudo-normal means nothing, so queries nearest to it use the ray-parity test.
    std::vector<std::uint32_t> incident(pos.size(), 0), first(pos.size(), kNone);
    for (std::uint32_t t = 0; t < tris.size(); ++t)
      for (std::uint32_t k = 0; k < 3; ++k) {
        ++incident[tris[t][k]];
        if (first[tris[t][k]] == kNone) first[tris[t][k]] = t;
      }
    complex_vertex.assign(pos.size(), 0);
    for (std::uint32_t v = 0; v < pos.size(); ++v) {
      if (first[v] == kNone) continue;
      std::uint32_t t = first[v], steps = 0;
      do {  // turn about v across the edge leaving it
        const std::uint32_t k = tris[t][0] == v ? 0u : tris[t][1] == v ? 1u : 2u;
        t = nbr[3 * t + k];
        ++steps;
      } while (t != first[v] && t != kNone && steps <= incident[v]);
      complex_vertex[v] = steps != incident[v] ? 1 : 0;
    }
  }

  // True when the closest point is (within rounding) a vertex where several fans meet: the
  // closest feature may then be reported as an edge or face of either fan, and only parity
  // tells inside from outside.
  bool needs_parity(std::uint32_t t, int feature, const glm::dvec3& closest, const std::vector<glm::dvec3>& pos,
                    const std::vector<glm::uvec3>& tris) const {
    if (feature >= kVertex) return complex_vertex[tris[t][feature - kVertex]] != 0;
    for (std::uint32_t k = 0; k < 3; ++k) {
      const std::uint32_t v = tris[t][k];
      if (complex_vertex[v] && glm::length(pos[v] - closest) <= 1e-9 * std::max(1.0, scale)) return true;
    }
    return false;
  }

  glm::dvec3 pseudo_normal(std::uint32_t t, int feature, const std::vector<glm::uvec3>& tris) const {
    if (feature == kFace) return face_normal[t];
    if (feature < kVertex) {
      const std::uint32_t g = nbr[3 * t + static_cast<std::uint32_t>(feature - kEdge)];
      return g == kNone ? face_normal[t] : face_normal[t] + face_normal[g];
    }
    return vertex_normal[tris[t][feature - kVertex]];
  }

  std::size_t bytes() const {
    return vertices.capacity() * sizeof(float) + (order.capacity() + offset.capacity() + nbr.capacity()) * 4 +
           (face_normal.capacity() + vertex_normal.capacity()) * sizeof(glm::dvec3) + records.capacity() * sizeof(TriRecord) +
           // Embree's own memory is not exposed: its index buffers (12 bytes per triangle) plus
           // a BVH estimate of 64 bytes per triangle (high-quality builds with spatial splits
           // measure around 40-80).
           order.size() * (12 + 64);
  }
};

namespace {

// State of one point query, on the caller's stack: queries share nothing mutable.
struct PointQueryState {
  const TriRecord* records;     // Accel::records and Accel::offset: (shell, primID) -> record
  const std::uint32_t* offset;
  glm::dvec3 p;
  float slack;
  double best2 = kInf;
  double best = kInf;  // sqrt(best2)
  std::uint32_t tri = kNone;
  int feature = 0;
  glm::dvec3 closest{0.0};
};

}  // namespace

// ---------------------------------------------------------------------------------------------

namespace {

// OFF and OBJ are read here (nodes/mesh_text.hpp says why OpenMesh's readers are not used).
MeshRecords text_records(const std::string& name, std::string text, const std::string& ext) {
  MeshRecords records;
  const std::string bad = ext == ".off" ? read_ascii_off(plain_off(std::move(text)), records) : read_obj(text, records);
  if (!bad.empty()) fail(name, bad);
  return records;
}

// PLY and STL through OpenMesh, recording what the file states (RecordingImporter).
MeshRecords openmesh_records(const std::string& name, const std::filesystem::path& file, const std::string& ext,
                             std::string text) {
  if (const std::string bad = stated_counts_problem(text, ext); !bad.empty()) fail(name, bad);
  text.clear();
  text.shrink_to_fit();
  TriMesh scratch;
  RecordingImporter importer(scratch);
  {
    QuietOpenMesh quiet;
    OpenMesh::IO::Options options;
    const bool ok = OpenMesh::IO::IOManager().read(file.string(), importer, options);
    std::string format = ext.substr(1);
    std::transform(format.begin(), format.end(), format.begin(),
                   [](unsigned char ch) { return static_cast<char>(std::toupper(ch)); });
    if (!ok) fail(name, "cannot read it as " + format + " (unreadable or malformed)");
  }
  MeshRecords records;
  records.positions.resize(importer.vertices.size());
  for (std::size_t v = 0; v < records.positions.size(); ++v) {
    const auto& q = scratch.point(importer.vertices[v]);
    records.positions[v] = glm::dvec3(q[0], q[1], q[2]);
  }
  records.faces = std::move(importer.faces);
  return records;
}

// A vertex a face names twice, or kNone. Large faces are sorted, so a polygon of thousands of
// vertices costs no quadratic search (30000 vertices would take seconds).
std::uint32_t repeated_vertex(const std::vector<std::uint32_t>& face) {
  if (face.size() <= 16) {
    for (std::size_t i = 1; i < face.size(); ++i)
      for (std::size_t j = 0; j < i; ++j)
        if (face[i] == face[j]) return face[i];
    return kNone;
  }
  std::vector<std::uint32_t> sorted = face;
  std::sort(sorted.begin(), sorted.end());
  const auto twice = std::adjacent_find(sorted.begin(), sorted.end());
  return twice == sorted.end() ? kNone : *twice;
}

}  // namespace

std::shared_ptr<const MeshLeaf> MeshLeaf::load(const std::filesystem::path& file, bool repair) {
  const std::string name = file.string();
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  if (ext != ".off" && ext != ".obj" && ext != ".ply" && ext != ".stl")
    fail(name, "cannot read files of type '" + ext + "' (OFF, OBJ, PLY or STL)");
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) fail(name, "cannot read it: no such file");

  std::string text;
  {
    std::ifstream in(file, std::ios::binary);
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    if (!in && !in.eof()) fail(name, "cannot read it: the file cannot be opened");
  }
  if (const std::string bad = non_finite_number(text, ext); !bad.empty()) fail(name, bad);

  MeshRecords records = ext == ".off" || ext == ".obj" ? text_records(name, std::move(text), ext)
                                                      : openmesh_records(name, file, ext, std::move(text));
  std::vector<glm::uvec3> triangles;
  triangles.reserve(records.faces.size());
  for (std::size_t f = 0; f < records.faces.size(); ++f) {
    const auto& face = records.faces[f];
    const std::string where = "face " + std::to_string(f);
    if (face.size() < 3) fail(name, where + " has only " + std::to_string(face.size()) + " vertices");
    if (std::find(face.begin(), face.end(), kNoVertex) != face.end())
      fail(name, where + " has an out-of-range vertex index");
    if (const std::uint32_t v = repeated_vertex(face); v != kNone)
      fail(name, where + " repeats vertex " + std::to_string(v));
    for (std::size_t i = 1; i + 1 < face.size(); ++i) triangles.emplace_back(face[0], face[i], face[i + 1]);
  }
  return build(std::move(records.positions), std::move(triangles), records.faces.size(), name, repair);
}

std::shared_ptr<const MeshLeaf> MeshLeaf::from_triangles(std::vector<glm::dvec3> positions,
                                                         std::vector<glm::uvec3> triangles, std::string name,
                                                         bool repair) {
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    const glm::uvec3& t = triangles[f];
    const std::string where = "face " + std::to_string(f);
    for (int k = 0; k < 3; ++k)
      if (t[k] >= positions.size())
        fail(name, where + " has an out-of-range vertex index (" + std::to_string(t[k]) + ", with " +
                       std::to_string(positions.size()) + " vertices)");
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
      fail(name, where + " repeats vertex " + std::to_string(t[0] == t[1] || t[0] == t[2] ? t[0] : t[1]));
  }
  const std::size_t faces = triangles.size();
  return build(std::move(positions), std::move(triangles), faces, std::move(name), repair);
}

std::shared_ptr<const MeshLeaf> MeshLeaf::build(std::vector<glm::dvec3> positions,
                                                std::vector<glm::uvec3> triangles, std::size_t input_faces,
                                                std::string name, bool repair) {
  for (std::size_t v = 0; v < positions.size(); ++v)
    if (!std::isfinite(positions[v].x) || !std::isfinite(positions[v].y) || !std::isfinite(positions[v].z))
      fail(name, "vertex " + std::to_string(v) + " has a non-finite coordinate");
  for (std::size_t v = 0; v < positions.size(); ++v)
    if (largest_coordinate(positions[v]) > kMaxCoordinate)
      fail(name, "vertex " + std::to_string(v) + " lies beyond 1e18 on an axis, farther than the ray queries reach");
  if (triangles.empty()) fail(name, "no triangles");
  if (positions.size() >= kNone || triangles.size() >= kNone / 3)
    fail(name, "too many vertices or triangles");

  std::shared_ptr<MeshLeaf> leaf(new MeshLeaf());
  MeshReport& report = leaf->report_;
  report.input_faces = input_faces;
  const std::size_t original = triangles.size();
  std::vector<std::uint8_t> flipped(original, 0);

  auto check_edges = [&](const Topology& topo, const char* after) {
    if (topo.nonmanifold > 0) {
      const std::uint32_t h = topo.first_nonmanifold;
      fail(name, std::to_string(topo.nonmanifold) + " non-manifold edges" + after +
                     " (an edge shared by more than two faces, first " +
                     edge_text(corner(triangles[h / 3], h % 3), corner(triangles[h / 3], h % 3 + 1)) + ")");
    }
  };
  Topology topo = edge_topology(triangles);
  check_edges(topo, "");
  if (topo.boundary > 0 && !repair) {
    const std::uint32_t h = topo.first_boundary;
    fail(name, std::to_string(topo.boundary) + " open boundary edges (first " +
                   edge_text(corner(triangles[h / 3], h % 3), corner(triangles[h / 3], h % 3 + 1)) +
                   "); closed meshes only (or \"repair\": true)");
  }
  Shells shells = orient_shells(name, triangles, topo, flipped);
  if (topo.boundary > 0) {
    fill_holes(name, positions, triangles, topo, report);
    topo = edge_topology(triangles);
    check_edges(topo, " after closing holes");
    if (topo.boundary > 0)
      fail(name, std::to_string(topo.boundary) + " open boundary edges remain after closing holes");
    flipped.resize(triangles.size(), 0);
    shells = orient_shells(name, triangles, topo, flipped);
  }

  leaf->accel_ = std::make_unique<Accel>(name, positions, triangles, shells);
  const Accel& accel = *leaf->accel_;

  // Outward orientation. A shell nested inside an even number of others bounds material on its
  // inside (positive volume); inside an odd number it bounds a cavity (negative volume). Nesting
  // is counted by ray parity against the other shells from a point on the shell's largest
  // triangle; Embree's ray tests ignore orientation, so the scene stays valid across flips.
  Aabb box;
  for (const glm::uvec3& t : triangles)
    for (int k = 0; k < 3; ++k) box.grow(positions[t[k]]);
  const glm::dvec3 o = box.center();
  std::vector<double> volume(shells.count, 0.0), largest(shells.count, -1.0);
  std::vector<glm::dvec3> probe(shells.count);
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    const glm::dvec3 a = positions[triangles[t][0]] - o, b = positions[triangles[t][1]] - o,
                     c = positions[triangles[t][2]] - o;
    const std::uint32_t s = shells.of[t];
    volume[s] += glm::dot(a, glm::cross(b, c)) / 6.0;
    const double twice_area = glm::length(glm::cross(b - a, c - a));
    if (twice_area > largest[s]) largest[s] = twice_area, probe[s] = o + (a + b + c) / 3.0;
  }
  std::vector<std::uint32_t> depth(shells.count, 0);
  if (shells.count > 1) {
    // Per shell s: parity of every other shell along three rays, majority per shell. Only the
    // shells a ray crosses are touched, so many small shells cost no quadratic sweep.
    std::vector<std::uint32_t> crossings(shells.count, 0), votes(shells.count, 0);
    std::vector<std::uint32_t> crossed, voted;
    for (std::uint32_t s = 0; s < shells.count; ++s) {
      for (const auto& dir : kRayDirs) {
        accel.crossings(probe[s], dir, [&](unsigned g) {
          if (g == s) return;
          if (crossings[g] == 0) crossed.push_back(g);
          ++crossings[g];
        });
        for (std::uint32_t g : crossed) {
          if (crossings[g] % 2 == 1) {
            if (votes[g] == 0) voted.push_back(g);
            ++votes[g];
          }
          crossings[g] = 0;
        }
        crossed.clear();
      }
      for (std::uint32_t g : voted) {
        depth[s] += votes[g] >= 2 ? 1u : 0u;
        votes[g] = 0;
      }
      voted.clear();
    }
  }
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    const std::uint32_t s = shells.of[t];
    const bool cavity = depth[s] % 2 == 1;
    if (cavity ? volume[s] > 0 : volume[s] < 0) {
      flip_triangle(triangles, topo, t);
      flipped[t] ^= 1u;
    }
  }

  // The report speaks of the input's faces only; triangles added by repair follow their shell.
  std::size_t changed = 0;
  for (std::size_t t = 0; t < original; ++t) changed += flipped[t];
  report.inverted = changed == original;
  report.reoriented_faces = report.inverted ? 0 : changed;
  report.components = shells.count;
  report.vertices = positions.size();
  report.triangles = triangles.size();

  leaf->accel_->compute_normals(positions, triangles, std::move(topo.nbr));
  leaf->bounds_ = box;
  leaf->name_ = std::move(name);
  leaf->surface_->positions = std::move(positions);
  leaf->surface_->triangles = std::move(triangles);
  return leaf;
}

MeshLeaf::~MeshLeaf() = default;

namespace {
bool point_query_visit(RTCPointQueryFunctionArguments* args) {
  auto* st = static_cast<PointQueryState*>(args->userPtr);
  const TriRecord& rec = st->records[st->offset[args->geomID] + args->primID];
  // Most triangles Embree hands over are far: their bounding sphere rejects them before the
  // exact (and costlier) closest-point computation.
  const glm::dvec3 to_centre = st->p - rec.centre;
  const double reach = rec.reach + st->best;
  if (glm::dot(to_centre, to_centre) >= reach * reach) return false;
  const std::uint32_t t = rec.tri;
  const Nearest n = closest_on_triangle(st->p, rec.a, rec.b, rec.c);
  const glm::dvec3 d = st->p - n.point;
  const double d2 = glm::dot(d, d);
  if (!(d2 < st->best2)) return false;
  st->best2 = d2;
  st->best = std::sqrt(d2);
  st->tri = t;
  st->feature = n.feature;
  st->closest = n.point;
  // Embree culls with float boxes of float vertices; the slack keeps a triangle whose double
  // distance is barely below the current best from being culled by rounding.
  const float r = static_cast<float>(st->best) + st->slack;
  if (r < args->query->radius) {
    args->query->radius = r;
    return true;
  }
  return false;
}
}  // namespace

MeshLeaf::Closest MeshLeaf::query(const glm::dvec3& p, double radius) const {
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return {kInf, false, p};
  if (largest_coordinate(p) > kMaxCoordinate) return far_query(p, radius);
  const double mag = std::max({accel_->scale, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
  PointQueryState st{accel_->records.data(),
                     accel_->offset.data(),
                     p,
                     static_cast<float>(8 * FLT_EPSILON * mag)};
  RTCPointQuery q;
  q.x = static_cast<float>(p.x);
  q.y = static_cast<float>(p.y);
  q.z = static_cast<float>(p.z);
  q.time = 0.0f;
  // Embree already visits near nodes first (measured: starting from the nearest vertex's
  // distance saves under 15% of the triangle visits), so the query starts at the full radius.
  q.radius = radius >= static_cast<double>(FLT_MAX) ? std::numeric_limits<float>::infinity()
                                                    : static_cast<float>(std::max(radius, 0.0)) + st.slack;
  // Embree hands over every triangle of each leaf it reaches, near or not: only those within the
  // (slackened) radius may become the closest, or a far triangle's pseudo-normal would decide.
  st.best = static_cast<double>(q.radius);
  st.best2 = st.best * st.best;
  RTCPointQueryContext ctx;
  rtcInitPointQueryContext(&ctx);
  rtcPointQuery(accel_->scene.get(), &q, &ctx, point_query_visit, &st);
  if (st.tri == kNone) return {kInf, inside(p), p};
  const double dist = std::sqrt(st.best2);
  // Baerentzen & Aanaes: p is inside iff p - closest points against the closest feature's
  // angle-weighted pseudo-normal. On the surface itself (dist 0) either answer gives the same
  // field value, so "outside" is fine there.
  const bool in = dist > 0 && (accel_->needs_parity(st.tri, st.feature, st.closest, surface_->positions, surface_->triangles)
                                   ? inside(p)
                                   : glm::dot(p - st.closest, accel_->pseudo_normal(st.tri, st.feature, surface_->triangles)) < 0);
  return {dist <= radius ? dist : kInf, in, st.closest};
}

// A point beyond kMaxCoordinate, where Embree cannot go: outside the mesh (which lies within
// it), at least 0 away from it; the nearest triangle by a walk over all of them, needed only
// when the radius reaches that far.
MeshLeaf::Closest MeshLeaf::far_query(const glm::dvec3& p, double radius) const {
  const glm::dvec3 out = glm::max(glm::max(bounds_.lo - p, p - bounds_.hi), glm::dvec3(0.0));
  const double gap = std::hypot(out.x, out.y, out.z);  // no overflow, however far
  if (!(gap <= radius)) return {kInf, false, p};
  Closest best{kInf, false, p};
  const auto& pos = surface_->positions;
  for (const glm::uvec3& t : surface_->triangles) {
    const glm::dvec3 q = closest_on_triangle(p, pos[t[0]], pos[t[1]], pos[t[2]]).point;
    const glm::dvec3 d = p - q;
    if (const double dist = std::hypot(d.x, d.y, d.z); dist < best.distance) best = {dist, false, q};
  }
  if (!(best.distance <= radius)) best.distance = kInf;
  return best;
}

bool MeshLeaf::inside(const glm::dvec3& p) const {
  if (!bounds_.contains(p)) return false;
  int odd_rays = 0;
  for (const auto& dir : kRayDirs) {
    std::size_t hits = 0;
    accel_->crossings(p, dir, [&](unsigned) { ++hits; });
    odd_rays += static_cast<int>(hits % 2);
  }
  return odd_rays >= 2;
}

void MeshLeaf::query_batch(const float* xs, const float* ys, const float* zs, std::size_t n, float radius,
                           float* distance, std::uint8_t* inside) const {
  for (std::size_t i = 0; i < n; ++i) {
    const Closest c = query(glm::dvec3(xs[i], ys[i], zs[i]), static_cast<double>(radius));
    distance[i] =
        std::isfinite(c.distance) ? static_cast<float>(c.distance) : std::numeric_limits<float>::infinity();
    inside[i] = c.inside ? 1 : 0;
  }
}

std::size_t MeshLeaf::bytes() const {
  return sizeof(MeshLeaf) + name_.capacity() + surface_->positions.capacity() * sizeof(glm::dvec3) +
         surface_->triangles.capacity() * sizeof(glm::uvec3) + (accel_ ? accel_->bytes() : 0);
}

const TriMeshHolder& MeshLeaf::openmesh() const {
  std::call_once(openmesh_once_, [this] {
    auto holder = std::make_unique<TriMeshHolder>();
    TriMesh& m = holder->mesh;
    m.reserve(positions().size(), 3 * triangles().size() / 2, triangles().size());
    for (const glm::dvec3& p : positions()) m.add_vertex(TriMesh::Point(p.x, p.y, p.z));
    // Through OpenMesh's importer, so a vertex where two shells touch (which a half-edge mesh
    // cannot represent) gets duplicated instead of losing the face.
    QuietOpenMesh quiet;
    OpenMesh::IO::ImporterT<TriMesh> importer(m);
    std::vector<OpenMesh::VertexHandle> face(3);
    for (const glm::uvec3& t : triangles()) {
      for (int k = 0; k < 3; ++k)
        face[static_cast<std::size_t>(k)] = OpenMesh::VertexHandle(static_cast<int>(t[k]));
      importer.add_face(face);
    }
    openmesh_ = std::move(holder);
  });
  return *openmesh_;
}

// ---------------------------------------------------------------------------------------------

MeshFieldParams mesh_field_params(double R, double F, double T) {
  if (!(R > 0) || !std::isfinite(R))
    throw std::invalid_argument("mesh field: radius must be positive and finite");
  if (!(T > 0)) throw std::invalid_argument("mesh field: the threshold must be positive");
  if (!(std::abs(F) > T) || !std::isfinite(F))
    throw std::invalid_argument("mesh field: |strength| must be greater than the threshold");
  MeshFieldParams m;
  m.R = R;
  m.F = F;
  m.T = T;
  const double c = std::sqrt(1.0 - std::cbrt(T / std::abs(F)));
  m.kernel_radius = R / (1.0 - c);
  m.r0 = c * m.kernel_radius;
  m.query_radius = std::max(R, m.r0);
  return m;
}

double mesh_field(const MeshLeaf& mesh, const MeshFieldParams& params, const glm::dvec3& p) {
  const MeshLeaf::Closest q = mesh.query(p, params.query_radius);
  if (!std::isfinite(q.distance)) return q.inside ? params.F : 0.0;
  double d;
  if (!q.inside)
    d = q.distance + params.r0;
  else if (q.distance < params.r0)
    d = params.r0 - q.distance;
  else
    return params.F;
  if (d >= params.kernel_radius) return 0.0;
  const double u = 1.0 - (d * d) / (params.kernel_radius * params.kernel_radius);
  return params.F * u * u * u;
}

std::shared_ptr<const MeshLeaf> MeshCache::get(const std::filesystem::path& file, bool repair) {
  std::error_code ec;
  std::filesystem::path key_path = std::filesystem::weakly_canonical(std::filesystem::absolute(file), ec);
  if (ec) key_path = std::filesystem::absolute(file).lexically_normal();
  const std::string key = key_path.string() + (repair ? "\n+repair" : "\n");
  if (auto it = meshes_.find(key); it != meshes_.end()) return it->second;
  auto leaf = MeshLeaf::load(file, repair);
  meshes_.emplace(key, leaf);
  return leaf;
}

}  // namespace ht
