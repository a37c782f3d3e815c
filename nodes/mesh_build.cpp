// Mesh leaves, validation: edge topology (non-manifold and open edges), consistent orientation
// per shell (BFS over edges), optional hole filling, then the Embree scene (one geometry per
// shell), outward orientation of each shell from its nesting depth and signed volume, and the
// angle-weighted pseudo-normals. The contract is in nodes/mesh_leaf.hpp.
#include "nodes/edge_keys.hpp"
#include "nodes/mesh_internal.hpp"
#include "nodes/trimesh.hpp"  // ~MeshLeaf in shared_ptr's deleter
#include "nodes/winding.hpp"
#include "meshers/self_intersections.hpp"
#include "meshers/union_find.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cstdio>
#include <numeric>
#include <tuple>
#include <unordered_map>
#include <utility>

namespace ht {

using namespace mesh_detail;

namespace mesh_detail {

Topology edge_topology(const std::vector<glm::uvec3>& tris) {
  Topology topo;
  const std::size_t nh = 3 * tris.size();
  topo.nbr.assign(nh, kNone);
  topo.open.assign(nh, 0);
  // The half-edges grouped by edge (nodes/edge_keys.hpp): in face order within an edge, so
  // messages are deterministic.
  std::uint32_t vertices = 0;
  for (const glm::uvec3& t : tris) vertices = std::max({vertices, t[0] + 1, t[1] + 1, t[2] + 1});
  const EdgeKeys e = edge_keys(tris, vertices);
  for (std::uint32_t v = 0; v < vertices; ++v)
    e.for_each_edge(v, [&](std::span<const std::uint64_t> run) {
      const std::uint32_t h0 = EdgeKeys::side(run[0]);
      if (run.size() == 1) {
        ++topo.boundary;
        topo.open[h0] = 1;
        topo.first_boundary = std::min(topo.first_boundary, h0);
      } else if (run.size() == 2) {
        const std::uint32_t h1 = EdgeKeys::side(run[1]);
        topo.nbr[h0] = h1 / 3;
        topo.nbr[h1] = h0 / 3;
      } else {
        ++topo.nonmanifold;
        topo.first_nonmanifold = std::min(topo.first_nonmanifold, h0);
      }
    });
  return topo;
}

}  // namespace mesh_detail

namespace {

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

// Breadth-first over edge adjacency; each shell keeps the orientation of its lowest-numbered
// triangle and every other triangle is made to agree with the neighbour that reached it. Not
// `strict` (winding leaves), a non-orientable shell is left as the walk made it.
Shells orient_shells(const std::string& name, std::vector<glm::uvec3>& tris, Topology& topo,
                     std::vector<std::uint8_t>& flipped, bool strict = true) {
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
        } else if (strict && !opposes(tris[g], a, b)) {
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

}  // namespace

std::shared_ptr<const MeshLeaf> MeshLeaf::from_triangles(std::vector<glm::dvec3> positions,
                                                         std::vector<glm::uvec3> triangles, std::string name,
                                                         bool repair, MeshInside inside, bool intersection_free) {
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
  return build(std::move(positions), std::move(triangles), faces, std::move(name), repair, inside, intersection_free);
}

namespace {

std::string first_edge(const std::vector<glm::uvec3>& tris, std::uint32_t h) {
  return edge_text(corner(tris[h / 3], h % 3), corner(tris[h / 3], h % 3 + 1));
}

// Boundary loops (connected sets of boundary edges) and vertices repeating an earlier one's
// position, for the report.
void count_defects(const std::vector<glm::dvec3>& pos, const std::vector<glm::uvec3>& tris, const Topology& topo,
                   MeshReport& report) {
  report.boundary_edges = topo.boundary;
  report.nonmanifold_edges = topo.nonmanifold;
  UnionFind sets(pos.size());
  std::vector<std::uint8_t> on_boundary(pos.size(), 0);
  for (std::uint32_t h = 0; h < topo.nbr.size(); ++h) {
    if (!topo.open[h]) continue;  // nbr is kNone on non-manifold edges too: not boundary loops
    const std::uint32_t a = corner(tris[h / 3], h % 3), b = corner(tris[h / 3], h % 3 + 1);
    sets.unite(a, b);
    on_boundary[a] = on_boundary[b] = 1;
  }
  report.holes = 0;
  if (topo.boundary > 0) {
    std::vector<std::uint8_t> seen(pos.size(), 0);
    for (std::uint32_t v = 0; v < pos.size(); ++v)
      if (on_boundary[v] && !seen[sets.find(v)]) seen[sets.find(v)] = 1, ++report.holes;
  }
  std::vector<std::uint32_t> order(pos.size());
  std::iota(order.begin(), order.end(), 0u);
  auto less = [&](std::uint32_t x, std::uint32_t y) {
    return std::tie(pos[x].x, pos[x].y, pos[x].z, x) < std::tie(pos[y].x, pos[y].y, pos[y].z, y);
  };
  std::sort(order.begin(), order.end(), less);
  report.duplicate_vertices = 0;
  for (std::size_t i = 1; i < order.size(); ++i) report.duplicate_vertices += pos[order[i]] == pos[order[i - 1]];
}

// Vertices where two or more fans of faces meet (shells touching at a point), on a mesh whose
// edges each join two faces: corners around a vertex linked across its edges are one fan. When
// some are found, `split` receives the triangles with each fan after a vertex's first on a vertex
// of its own, numbered from `vertices` on in the order of the fans' first corners, and `copied`
// the vertex each copies. Returns how many vertices are pinched.
std::size_t split_pinched_vertices(const std::vector<glm::uvec3>& tris, const Topology& topo, std::size_t vertices,
                                   std::vector<glm::uvec3>& split, std::vector<std::uint32_t>& copied) {
  UnionFind corners(3 * tris.size());
  auto corner_at = [&](std::uint32_t t, std::uint32_t v) {
    const glm::uvec3 c = tris[t];
    return 3 * t + (c[0] == v ? 0u : c[1] == v ? 1u : 2u);
  };
  for (std::uint32_t h = 0; h < topo.nbr.size(); ++h) {
    const std::uint32_t t = h / 3, other = topo.nbr[h];
    if (other == kNone || other < t) continue;  // each edge once
    for (const std::uint32_t v : {corner(tris[t], h % 3), corner(tris[t], h % 3 + 1)})
      corners.unite(corner_at(t, v), corner_at(other, v));
  }
  // A fan's root is its first corner: fans are met in the order of their first corners.
  std::vector<std::uint8_t> seen(vertices, 0);
  std::vector<std::uint32_t> vertex_of(3 * tris.size(), kNone);
  std::size_t pinched = 0;
  for (std::uint32_t k = 0; k < 3 * tris.size(); ++k) {
    if (corners.find(k) != k) continue;
    const std::uint32_t v = corner(tris[k / 3], k % 3);
    if (!seen[v]) {
      seen[v] = 1;
      vertex_of[k] = v;
      continue;
    }
    if (seen[v] == 1) ++pinched, seen[v] = 2;
    vertex_of[k] = std::uint32_t(vertices + copied.size());
    copied.push_back(v);
  }
  if (copied.empty()) return 0;
  split.resize(tris.size());
  for (std::uint32_t k = 0; k < 3 * tris.size(); ++k) {
    split[k / 3][static_cast<glm::length_t>(k % 3)] = vertex_of[corners.find(k)];
  }
  return pinched;
}

// A closed leaf's refusals, each naming the defect (and what would accept the mesh).
void check_closed(const std::string& name, const std::vector<glm::uvec3>& tris, const Topology& topo,
                  const MeshReport& report, bool repair, const char* after) {
  const std::string other = "; closed meshes only (or \"inside\": \"winding\")";
  if (topo.nonmanifold > 0)
    fail(name, std::to_string(topo.nonmanifold) + " non-manifold edges" + after +
                   " (an edge shared by more than two faces, first " + first_edge(tris, topo.first_nonmanifold) + ")" +
                   other);
  if (topo.boundary > 0 && !repair) {
    std::string dup;
    if (report.duplicate_vertices > 0)
      dup = ", and " + std::to_string(report.duplicate_vertices) + " vertices duplicate another's position";
    fail(name, std::to_string(topo.boundary) + " open boundary edges in " + std::to_string(report.holes) +
                   " holes (first " + first_edge(tris, topo.first_boundary) + ")" + dup +
                   "; closed meshes only (or \"repair\": true, or \"inside\": \"winding\")");
  }
}

// A winding leaf keeps each shell's majority orientation (by area): the BFS made every shell
// agree with its first triangle; where that flipped most of the shell, the shell goes back.
void keep_majority(std::vector<glm::uvec3>& tris, Topology& topo, const Shells& shells,
                   const std::vector<glm::dvec3>& pos, std::vector<std::uint8_t>& flipped) {
  std::vector<double> area(shells.count, 0.0), moved(shells.count, 0.0);
  for (std::uint32_t t = 0; t < tris.size(); ++t) {
    const double a = glm::length(glm::cross(pos[tris[t][1]] - pos[tris[t][0]], pos[tris[t][2]] - pos[tris[t][0]]));
    area[shells.of[t]] += a;
    if (flipped[t]) moved[shells.of[t]] += a;
  }
  for (std::uint32_t t = 0; t < tris.size(); ++t)
    if (moved[shells.of[t]] > 0.5 * area[shells.of[t]]) {
      flip_triangle(tris, topo, t);
      flipped[t] ^= 1u;
    }
}

// Closed leaves: a shell that encloses no volume (every triangle flat on the others, or all its
// corners at one point) bounds no solid and has no outside to orient toward; the rays and BVH
// builds behind the queries are not made for it either (an Embree builder asserted on one).
void check_volumes(const std::string& name, const std::vector<glm::dvec3>& pos, const std::vector<glm::uvec3>& tris,
                   const Shells& shells) {
  std::vector<Aabb> box(shells.count);
  for (std::uint32_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k) box[shells.of[t]].grow(pos[tris[t][k]]);
  // The signed volume against the sum of its terms' bounds (each triple product's six products
  // taken in absolute value), which bounds its rounding: a shell is flat when its volume is within
  // rounding of 0. (Against the box's diagonal cubed, an ellipsoid that an ffd stretched a million
  // times along one axis was called flat; against the sum of the terms themselves, a flat
  // parallelogram through the box's centre, every term rounding noise, was not.)
  std::vector<double> volume(shells.count, 0.0), terms(shells.count, 0.0);
  std::vector<std::size_t> count(shells.count, 0);
  for (std::uint32_t t = 0; t < tris.size(); ++t) {
    const std::uint32_t s = shells.of[t];
    const glm::dvec3 o = box[s].center(), a = pos[tris[t][0]] - o, b = pos[tris[t][1]] - o, c = pos[tris[t][2]] - o;
    const glm::dvec3 A = glm::abs(a), B = glm::abs(b), C = glm::abs(c);
    volume[s] += glm::dot(a, glm::cross(b, c)) / 6.0;
    terms[s] += (A.x * (B.y * C.z + B.z * C.y) + A.y * (B.x * C.z + B.z * C.x) + A.z * (B.x * C.y + B.y * C.x)) / 6.0;
    ++count[s];
  }
  for (std::uint32_t s = 0; s < shells.count; ++s) {
    const double size = glm::length(box[s].size());
    if (std::abs(volume[s]) > 1e-9 * terms[s]) continue;
    char across[32];
    std::snprintf(across, sizeof across, "%.3g", size);
    fail(name, (shells.count > 1 ? "shell " + std::to_string(s) + " (" : "the mesh (") + std::to_string(count[s]) +
                   " triangles, " + across + " across) encloses no volume: its triangles lie flat on each other or " +
                   "collapse to a point; remove it from the file (repair does not)");
  }
}

// Closed leaves with several shells: two shells that cross make the inside test meaningless
// (nesting by parity), so they are refused. Pairs within one shell are not looked for.
void check_crossing_shells(const std::string& name, const std::vector<glm::dvec3>& pos,
                           const std::vector<glm::uvec3>& tris, const Shells& shells, MeshReport& report) {
  if (shells.count < 2) return;
  TriangleMesh mesh;
  mesh.positions = pos;
  mesh.triangles = tris;
  const SelfIntersections found = find_self_intersections(mesh, std::numeric_limits<std::size_t>::max());
  std::vector<std::uint64_t> pairs;
  for (const auto& e : found.examples) {
    std::uint32_t s = shells.of[e[0]], g = shells.of[e[1]];
    if (s != g) pairs.push_back((static_cast<std::uint64_t>(std::min(s, g)) << 32) | std::max(s, g));
  }
  std::sort(pairs.begin(), pairs.end());
  report.intersecting_shells = static_cast<std::size_t>(std::unique(pairs.begin(), pairs.end()) - pairs.begin());
  if (report.intersecting_shells == 0) return;
  fail(name, std::to_string(report.intersecting_shells) + " pairs of shells cross each other (first shells " +
                 std::to_string(pairs[0] >> 32) + " and " + std::to_string(pairs[0] & 0xffffffffu) +
                 "): interpenetrating parts; closed meshes only (or \"inside\": \"winding\")");
}

// Outward orientation. A shell nested inside an even number of others bounds material on its
// inside (positive volume); inside an odd number it bounds a cavity (negative volume). Nesting
// is counted by ray parity against the other shells from a point on the shell's largest
// triangle; Embree's ray tests ignore orientation, so the scene stays valid across flips.
template <class Accel>  // MeshLeaf::Accel, deduced (it is private to MeshLeaf)
void orient_outward(const Accel& accel, const std::vector<glm::dvec3>& positions,
                    std::vector<glm::uvec3>& triangles, const Shells& shells, Topology& topo,
                    std::vector<std::uint8_t>& flipped, const Aabb& box) {
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
}

}  // namespace

std::shared_ptr<MeshLeaf> MeshLeaf::build(std::vector<glm::dvec3> positions,
                                                std::vector<glm::uvec3> triangles, std::size_t input_faces,
                                                std::string name, bool repair, MeshInside inside,
                                                bool intersection_free) {
  for (std::size_t v = 0; v < positions.size(); ++v)
    if (!std::isfinite(positions[v].x) || !std::isfinite(positions[v].y) || !std::isfinite(positions[v].z))
      fail(name, "vertex " + std::to_string(v) + " has a non-finite coordinate");
  for (std::size_t v = 0; v < positions.size(); ++v)
    if (largest_coordinate(positions[v]) > kMaxCoordinate)
      fail(name, "vertex " + std::to_string(v) + " lies beyond 1e18 on an axis, farther than the ray queries reach");
  if (triangles.empty()) fail(name, "no triangles");
  if (positions.size() >= kNone || triangles.size() >= kNone / 3)
    fail(name, "too many vertices or triangles");
  const bool winding = inside == MeshInside::Winding;
  if (winding && repair) fail(name, "\"repair\" and \"inside\": \"winding\" do not combine (winding takes holes as they are)");

  std::shared_ptr<MeshLeaf> leaf(new MeshLeaf());
  MeshReport& report = leaf->report_;
  report.input_faces = input_faces;
  report.inside = inside;
  const std::size_t original = triangles.size();
  std::vector<std::uint8_t> flipped(original, 0);

  Topology topo = edge_topology(triangles);
  count_defects(positions, triangles, topo, report);
  if (!winding) check_closed(name, triangles, topo, report, repair, "");
  Shells shells = orient_shells(name, triangles, topo, flipped, !winding);
  if (winding) keep_majority(triangles, topo, shells, positions, flipped);
  if (!winding && topo.boundary > 0) {
    fill_holes(name, positions, triangles, topo, report);
    topo = edge_topology(triangles);
    check_closed(name, triangles, topo, report, true, " after closing holes");
    if (topo.boundary > 0)
      fail(name, std::to_string(topo.boundary) + " open boundary edges remain after closing holes");
    flipped.resize(triangles.size(), 0);
    shells = orient_shells(name, triangles, topo, flipped);
  }
  if (!winding) check_volumes(name, positions, triangles, shells);
  // Holes closed above add triangles nobody searched.
  if (!winding && !(intersection_free && report.triangles_added == 0))
    check_crossing_shells(name, positions, triangles, shells, report);

  leaf->accel_ = std::make_unique<Accel>(name, positions, triangles, shells);
  Aabb box;
  for (const glm::uvec3& t : triangles)
    for (int k = 0; k < 3; ++k) box.grow(positions[t[k]]);
  if (!winding) orient_outward(*leaf->accel_, positions, triangles, shells, topo, flipped, box);

  // The report speaks of the input's faces only; triangles added by repair follow their shell.
  std::size_t changed = 0;
  for (std::size_t t = 0; t < original; ++t) changed += flipped[t];
  report.inverted = changed == original;
  report.reoriented_faces = report.inverted ? 0 : changed;
  report.components = shells.count;
  report.vertices = positions.size();
  report.triangles = triangles.size();

  if (!winding) {
    // Shells touching at a vertex: the queries take the mesh as it is; what is written out gives
    // each fan its own copy of the vertex (a manifold with two vertices at one point).
    std::vector<glm::uvec3> split;
    std::vector<std::uint32_t> copied;
    report.pinched_vertices = split_pinched_vertices(triangles, topo, positions.size(), split, copied);
    if (report.pinched_vertices > 0) {
      auto apart = std::make_shared<TriangleMesh>();
      apart->positions.reserve(positions.size() + copied.size());
      apart->positions = positions;
      apart->triangles = std::move(split);
      for (const std::uint32_t v : copied) apart->positions.push_back(positions[v]);
      leaf->manifold_ = std::move(apart);
    }
  }
  leaf->accel_->compute_normals(positions, triangles, std::move(topo.nbr));
  if (winding) leaf->winding_ = std::make_unique<WindingTree>(positions, triangles);
  leaf->bounds_ = box;
  leaf->surface_band_ = MeshLeaf::kSurfaceBand * std::max(leaf->accel_->scale, std::numeric_limits<double>::min());
  leaf->name_ = std::move(name);
  leaf->surface_->positions = std::move(positions);
  leaf->surface_->triangles = std::move(triangles);
  return leaf;
}

}  // namespace ht
