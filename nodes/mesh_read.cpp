// Mesh leaves, reading: OFF, OBJ, PLY and STL through OpenMesh, with the checks OpenMesh's
// readers skip (non-finite numbers, faces as the file states them), the OpenMesh form of a
// loaded mesh, and the cache that loads each file once. Validation is in nodes/mesh_build.cpp.
#include "nodes/mesh_internal.hpp"
#include "nodes/mesh_text.hpp"
#include "nodes/openmesh_io.hpp"
#include "nodes/trimesh.hpp"

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/IO/importer/ImporterT.hh>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string_view>
#include <unordered_set>
#include <vector>

namespace ht {

using namespace mesh_detail;

namespace {

// Records what the reader states before OpenMesh's importer gets to "fix" it: the importer
// drops faces with bad indices and duplicates the vertices of faces that would make an edge
// non-manifold, which would hide exactly the defects validation has to report. Only the points
// of the scratch mesh are read afterwards, so a face is not linked into it: it gets a face
// handle of its own (the reader may store per-face properties under it) and no halfedges.
// Linking cost 2,800 instructions a face in Debian's OpenMesh, built with assertions on.
class RecordingImporter : public OpenMesh::IO::ImporterT<TriMesh> {
  using Base = OpenMesh::IO::ImporterT<TriMesh>;

 public:
  explicit RecordingImporter(TriMesh& mesh) : Base(mesh), mesh_(mesh) {}

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
    return face.size() > 2 ? mesh_.new_face() : OpenMesh::FaceHandle();
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
  TriMesh& mesh_;
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
    const char a = lower(text[i]);
    if (a != 'n' && a != 'i') continue;  // the rest only where a word could start (numbers: none)
    const char b = lower(text[i + 1]), c = lower(text[i + 2]);
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

std::shared_ptr<const MeshLeaf> MeshLeaf::load(const std::filesystem::path& file, bool repair, MeshInside inside) {
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
  auto leaf = build(std::move(records.positions), std::move(triangles), records.faces.size(), name, repair, inside);
  leaf->file_ = file;
  leaf->repair_requested_ = repair;
  return leaf;
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

std::string MeshCache::key(const std::filesystem::path& file, bool repair, MeshInside inside) {
  std::error_code ec;
  std::filesystem::path key_path = std::filesystem::weakly_canonical(std::filesystem::absolute(file), ec);
  if (ec) key_path = std::filesystem::absolute(file).lexically_normal();
  return key_path.string() + (repair ? "\n+repair" : "\n") + to_string(inside);
}

std::shared_ptr<const MeshLeaf> MeshCache::get(const std::filesystem::path& file, bool repair, MeshInside inside) {
  const std::string k = key(file, repair, inside);
  if (auto it = meshes_.find(k); it != meshes_.end()) return it->second;
  auto leaf = MeshLeaf::load(file, repair, inside);
  meshes_.emplace(k, leaf);
  return leaf;
}

void MeshCache::prefetch(std::span<const MeshFileRequest> requests) {
  std::vector<std::string> keys;
  std::vector<const MeshFileRequest*> todo;
  std::unordered_set<std::string> asked;
  for (const MeshFileRequest& r : requests) {
    std::string k = key(r.file, r.repair, r.inside);
    if (meshes_.count(k) || !asked.insert(k).second) continue;
    keys.push_back(std::move(k));
    todo.push_back(&r);
  }
  if (todo.size() < 2) return;  // one file: get() loads it as soon
  std::vector<std::shared_ptr<const MeshLeaf>> loaded(todo.size());
  tbb::parallel_for(std::size_t(0), todo.size(), [&](std::size_t i) {
    try {
      loaded[i] = MeshLeaf::load(todo[i]->file, todo[i]->repair, todo[i]->inside);
    } catch (const std::exception&) {
      // get() says what is wrong, with where the scene names the file.
    }
  });
  for (std::size_t i = 0; i < todo.size(); ++i)
    if (loaded[i]) meshes_.emplace(keys[i], std::move(loaded[i]));
}

}  // namespace ht
