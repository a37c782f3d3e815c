// Loading triangles into OpenMesh in bulk (meshers/openmesh_link.hpp): on manifold meshes, closed
// and open, the links are those add_face makes (the same faces, edges, rings and boundaries) and
// every halfedge is consistent; meshes that are not manifold are declined and left untouched.
#include "meshers/openmesh_link.hpp"
#include "meshers/polygonize.hpp"
#include "runtime/builder.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <vector>

namespace ht {
namespace {

using VH = TriMesh::VertexHandle;
using FH = TriMesh::FaceHandle;

void add_vertices(TriMesh& m, const TriangleMesh& mesh) {
  for (const glm::dvec3& p : mesh.positions) m.add_vertex({p.x, p.y, p.z});
}

// A face's corners, rotated to start at the smallest index.
std::vector<int> cycle(const TriMesh& m, FH f) {
  std::vector<int> c;
  for (const VH v : m.fv_range(f)) c.push_back(v.idx());
  std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());
  return c;
}

// Every halfedge's links agree with each other, and boundary halfedges are those without a face.
void expect_consistent(const TriMesh& m) {
  for (const auto h : m.halfedges()) {
    ASSERT_EQ(m.prev_halfedge_handle(m.next_halfedge_handle(h)), h);
    ASSERT_EQ(m.from_vertex_handle(m.next_halfedge_handle(h)), m.to_vertex_handle(h));
    ASSERT_EQ(m.opposite_halfedge_handle(m.opposite_halfedge_handle(h)), h);
    ASSERT_EQ(m.is_boundary(h), !m.face_handle(h).is_valid());
    if (!m.is_boundary(h)) {
      ASSERT_EQ(m.face_handle(m.next_halfedge_handle(h)), m.face_handle(h));
    }
  }
  for (const VH v : m.vertices()) {
    ASSERT_TRUE(m.is_manifold(v));
    if (m.halfedge_handle(v).is_valid()) {
      ASSERT_EQ(m.from_vertex_handle(m.halfedge_handle(v)), v);
    }
  }
}

// The same mesh through add_face and in bulk: same faces, edges, boundaries, valences and rings.
void expect_like_add_face(const TriangleMesh& mesh) {
  TriMesh slow, fast;
  add_vertices(slow, mesh);
  add_vertices(fast, mesh);
  for (const glm::uvec3& t : mesh.triangles)
    ASSERT_TRUE(slow.add_face(VH(int(t[0])), VH(int(t[1])), VH(int(t[2]))).is_valid());
  ASSERT_TRUE(link_manifold_triangles(fast, mesh.triangles));
  expect_consistent(fast);
  ASSERT_EQ(fast.n_edges(), slow.n_edges());
  ASSERT_EQ(fast.n_faces(), slow.n_faces());
  for (const FH f : slow.faces()) ASSERT_EQ(cycle(fast, f), cycle(slow, f));
  for (const auto e : slow.edges())  // numbered alike, halfedge 0 the same way
    ASSERT_EQ(fast.to_vertex_handle(fast.halfedge_handle(e, 0)), slow.to_vertex_handle(slow.halfedge_handle(e, 0)));
  for (const VH v : slow.vertices()) {
    ASSERT_EQ(fast.is_boundary(v), slow.is_boundary(v)) << v.idx();
    ASSERT_EQ(fast.valence(v), slow.valence(v)) << v.idx();
    std::set<int> a, b;
    for (const VH w : fast.vv_range(v)) a.insert(w.idx());
    for (const VH w : slow.vv_range(v)) b.insert(w.idx());
    ASSERT_EQ(a, b) << v.idx();
  }
}

// Two balls blended: a closed surface of a few thousand triangles.
TriangleMesh closed_mesh() {
  Builder b(0.5);
  const Tree t = b.build(b.blend({b.point({0, 0, 0}, {1.0}), b.point({0.7, 0.2, 0}, {0.8})}));
  PolygonizeOptions o;
  o.precision = 0.08;
  return polygonize(t.graph_ptr(), t.root(), 0.5, o);
}

}  // namespace

TEST(OpenMeshLink, ClosedAndOpenManifoldsLinkAsAddFaceLinksThem) {
  const TriangleMesh whole = closed_mesh();
  ASSERT_GT(whole.triangles.size(), 1000u);
  expect_like_add_face(whole);
  // Open patches: the triangles within random balls, kept when every vertex keeps one fan (and
  // add_face takes them in the mesh's order).
  test::Rng rng = test::seeded();
  int patches = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const glm::dvec3 c = whole.positions[rng() % whole.positions.size()];
    const double r = 0.1 + 0.5 * double(rng() % 1000) / 1000.0;
    TriangleMesh part;
    part.positions = whole.positions;
    for (const glm::uvec3& t : whole.triangles)
      if (glm::length(whole.positions[t[0]] - c) < r && glm::length(whole.positions[t[1]] - c) < r &&
          glm::length(whole.positions[t[2]] - c) < r)
        part.triangles.push_back(t);
    TriMesh probe;
    add_vertices(probe, part);
    bool manifold = true;
    for (const glm::uvec3& t : part.triangles)
      manifold = manifold && probe.add_face(VH(int(t[0])), VH(int(t[1])), VH(int(t[2]))).is_valid();
    for (const VH v : probe.vertices()) manifold = manifold && probe.is_manifold(v);
    if (!manifold) continue;
    expect_like_add_face(part);
    ++patches;
  }
  EXPECT_GT(patches, 20);
}

TEST(OpenMeshLink, WhatIsNotAManifoldIsDeclinedAndLeftAlone) {
  TriangleMesh tet;
  tet.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}, {-1, -1, -1}, {-1, 0, -1}, {0, -1, -1}};
  tet.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  struct Case {
    const char* what;
    std::vector<glm::uvec3> triangles;
  };
  const std::vector<Case> bad = {
      {"a fin: three triangles on one edge", {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}, {1, 2, 4}}},
      {"a face walked the wrong way", {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {2, 1, 3}}},
      {"two cones at one vertex", {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}, {0, 5, 6}, {0, 6, 7}, {0, 7, 5}, {5, 7, 6}}},
      {"two open fans at one vertex", {{0, 1, 2}, {0, 5, 6}}},
      {"a repeated corner", {{0, 1, 1}}},
      {"a corner past the vertices", {{0, 1, 9}}},
  };
  for (const Case& k : bad) {
    TriMesh m;
    add_vertices(m, tet);
    EXPECT_FALSE(link_manifold_triangles(m, k.triangles)) << k.what;
    EXPECT_EQ(m.n_edges(), 0u) << k.what;
    EXPECT_EQ(m.n_faces(), 0u) << k.what;
  }
  TriMesh m;  // and the tetrahedron itself is taken
  add_vertices(m, tet);
  EXPECT_TRUE(link_manifold_triangles(m, tet.triangles));
  expect_consistent(m);
}

}  // namespace ht
