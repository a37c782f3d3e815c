// OpenMesh's collapse, flip and their checks, compiled here (meshers/halfedge_ops.hpp), against
// the library's own: two copies of a mesh collapse and flip the same random edges, one with
// OpenMesh's is_collapse_ok, collapse, is_flip_ok and flip, the other with ours; before each step
// every halfedge and edge gets the same verdicts and every vertex the same valence, and after it
// every link, handle and deletion flag is the same. Closed meshes, open
// patches of them (boundary rules) and collapses down to a handful of triangles (tetrahedra,
// valence-3 corners, the two-triangle pillow a tetrahedron collapses into, triangles with two
// boundary edges) are walked.
#include "meshers/halfedge_ops.hpp"
#include "meshers/openmesh_link.hpp"
#include "meshers/polygonize.hpp"
#include "runtime/builder.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace ht {
namespace {

using HH = TriMesh::HalfedgeHandle;
using VH = TriMesh::VertexHandle;

TriMesh to_openmesh(const TriangleMesh& mesh, bool halfedge_status) {
  TriMesh m;
  m.request_vertex_status();
  m.request_edge_status();
  m.request_face_status();
  if (halfedge_status) m.request_halfedge_status();
  for (const glm::dvec3& p : mesh.positions) m.add_vertex({p.x, p.y, p.z});
  for (const glm::uvec3& t : mesh.triangles) m.add_face(VH(int(t[0])), VH(int(t[1])), VH(int(t[2])));
  return m;
}

// Every stored link and flag of the two meshes, compared.
void expect_same(const TriMesh& a, const TriMesh& b, int step) {
  ASSERT_EQ(a.n_halfedges(), b.n_halfedges());
  for (const auto h : a.all_halfedges()) {
    ASSERT_EQ(a.next_halfedge_handle(h), b.next_halfedge_handle(h)) << "step " << step << " halfedge " << h.idx();
    ASSERT_EQ(a.prev_halfedge_handle(h), b.prev_halfedge_handle(h)) << "step " << step << " halfedge " << h.idx();
    ASSERT_EQ(a.to_vertex_handle(h), b.to_vertex_handle(h)) << "step " << step << " halfedge " << h.idx();
    ASSERT_EQ(a.face_handle(h), b.face_handle(h)) << "step " << step << " halfedge " << h.idx();
    if (a.has_halfedge_status()) {
      ASSERT_EQ(a.status(h).deleted(), b.status(h).deleted());
    }
  }
  for (const auto e : a.all_edges()) ASSERT_EQ(a.status(e).deleted(), b.status(e).deleted()) << "step " << step;
  for (const auto v : a.all_vertices()) {
    ASSERT_EQ(a.halfedge_handle(v), b.halfedge_handle(v)) << "step " << step << " vertex " << v.idx();
    ASSERT_EQ(a.status(v).deleted(), b.status(v).deleted()) << "step " << step << " vertex " << v.idx();
  }
  for (const auto f : a.all_faces()) {
    ASSERT_EQ(a.halfedge_handle(f), b.halfedge_handle(f)) << "step " << step << " face " << f.idx();
    ASSERT_EQ(a.status(f).deleted(), b.status(f).deleted()) << "step " << step << " face " << f.idx();
  }
}

struct Walk {
  int collapses = 0, flips = 0, refused = 0;  // steps made; collapse verdicts "not ok" on live edges
};

// Collapses and flips random edges of `mesh` (ours in one copy, OpenMesh's in the other) until at
// most `down_to` faces are left or no edge may go, comparing verdicts and links all the way.
Walk walk(const TriangleMesh& mesh, bool halfedge_status, std::size_t down_to, test::Rng& rng) {
  TriMesh ours = to_openmesh(mesh, halfedge_status), theirs = to_openmesh(mesh, halfedge_status);
  Walk w;
  for (int step = 0;; ++step) {
    std::vector<HH> ok;
    for (const auto h : ours.all_halfedges()) {
      const bool verdict = collapse_ok(ours, h);
      EXPECT_EQ(verdict, theirs.is_collapse_ok(h)) << "step " << step << " halfedge " << h.idx();
      if (verdict) ok.push_back(h);
      else if (!ours.status(ours.edge_handle(h)).deleted()) ++w.refused;
    }
    std::vector<TriMesh::EdgeHandle> flippable;
    for (const auto e : ours.edges()) {  // the live ones
      const bool verdict = flip_ok(ours, e);
      EXPECT_EQ(verdict, theirs.is_flip_ok(e)) << "step " << step << " edge " << e.idx();
      if (verdict) flippable.push_back(e);
    }
    for (const auto v : ours.vertices()) EXPECT_EQ(valence(ours, v), theirs.valence(v)) << "step " << step;
    std::size_t faces = 0;
    for (const auto f : ours.all_faces()) faces += !ours.status(f).deleted();
    if (ok.empty() || faces <= down_to || ::testing::Test::HasFailure()) return w;
    if (!flippable.empty() && rng() % 3 == 0) {
      const TriMesh::EdgeHandle e = flippable[rng() % flippable.size()];
      flip(ours, e);
      theirs.flip(e);
      ++w.flips;
    } else {
      const HH h = ok[rng() % ok.size()];
      collapse(ours, h);
      theirs.collapse(h);
      ++w.collapses;
    }
    expect_same(ours, theirs, step);
    if (::testing::Test::HasFailure()) return w;
  }
}

TriangleMesh ball_mesh(double precision) {
  Builder b(0.5);
  const Tree t = b.build(b.blend({b.point({0, 0, 0}, {1.0}), b.point({0.7, 0.2, 0}, {0.8})}));
  PolygonizeOptions o;
  o.precision = precision;
  o.quality.enabled = false;  // marching tetrahedra's needles: many collapses the check refuses
  return polygonize(t.graph_ptr(), t.root(), 0.5, o);
}

}  // namespace

TEST(HalfedgeOps, ClosedMeshesCollapseAsOpenMeshCollapsesThem) {
  test::Rng rng = test::seeded();
  const TriangleMesh mesh = ball_mesh(0.25);
  ASSERT_GT(mesh.triangles.size(), 200u);
  for (bool halfedge_status : {false, true}) {
    const Walk w = walk(mesh, halfedge_status, 0, rng);
    EXPECT_GT(w.collapses, int(mesh.triangles.size() / 3)) << "the walk went down to a few triangles";
    EXPECT_GT(w.refused, 100) << "the link condition was met";
    EXPECT_GT(w.flips, 50);
  }
}

TEST(HalfedgeOps, OpenPatchesCollapseAsOpenMeshCollapsesThem) {
  test::Rng rng = test::seeded();
  const TriangleMesh whole = ball_mesh(0.2);
  int walks = 0, collapses = 0;
  for (int trial = 0; trial < 12; ++trial) {
    // The triangles with a corner on one side of a random plane: boundary loops, and where the
    // plane grazes the mesh, triangles with two boundary edges and bow ties OpenMesh declines.
    const glm::dvec3 c = whole.positions[rng() % whole.positions.size()];
    const glm::dvec3 n = glm::normalize(glm::dvec3(double(rng() % 200) - 100.0, double(rng() % 200) - 100.0, 50.0));
    TriangleMesh part;
    part.positions = whole.positions;
    for (const glm::uvec3& t : whole.triangles)
      if (glm::dot(whole.positions[t[0]] - c, n) < 0 || glm::dot(whole.positions[t[1]] - c, n) < 0)
        part.triangles.push_back(t);
    if (part.triangles.size() < 50) continue;
    collapses += walk(part, trial % 2 == 1, 2, rng).collapses;
    ++walks;
    if (::testing::Test::HasFailure()) return;
  }
  EXPECT_GE(walks, 8);
  EXPECT_GT(collapses, 1000);
}

}  // namespace ht
