#include "meshers/stitch.hpp"

#include "meshers/edges.hpp"
#include "meshers/union_find.hpp"

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <string>
#include <unordered_map>
#include <vector>

namespace ht {
namespace {

constexpr std::uint32_t kNo = ~0u;

// All pieces in one mesh; vertex ids are global, earlier pieces first.
struct Soup : TriangleMesh {
  std::vector<std::uint32_t> piece;  // per vertex
};

Soup concatenate(std::span<const TriangleMesh* const> pieces) {
  Soup s;
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    append(s, *pieces[k]);
    s.piece.resize(s.positions.size(), std::uint32_t(k));
  }
  return s;
}

// The same from pieces the soup may take: each is freed once appended, so the pieces and their
// concatenation are not all held at once.
Soup concatenate(std::vector<TriangleMesh>&& pieces) {
  Soup s;
  std::size_t vertices = 0, triangles = 0;
  for (const TriangleMesh& p : pieces) vertices += p.positions.size(), triangles += p.triangles.size();
  s.positions.reserve(vertices);
  s.triangles.reserve(triangles);
  s.piece.reserve(vertices);
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    append(s, pieces[k]);
    s.piece.resize(s.positions.size(), std::uint32_t(k));
    pieces[k] = TriangleMesh();
  }
  return s;
}

// Directed boundary edges (used by one triangle), each with its triangle and slot.
struct Boundary {
  std::vector<std::uint32_t> from, to, slot;  // slot = 3 * triangle + corner of `from`
  std::vector<std::uint32_t> edge_of_slot;     // per triangle slot: its boundary edge or kNo
  std::vector<std::uint32_t> out_edge, in_edge;  // per vertex
  std::vector<double> scale;                   // per vertex: its shorter boundary edge
};

Boundary find_boundary(const Soup& s) {
  Boundary b;
  b.edge_of_slot.assign(3 * s.triangles.size(), kNo);
  b.out_edge.assign(s.positions.size(), kNo);
  b.in_edge.assign(s.positions.size(), kNo);
  b.scale.assign(s.positions.size(), std::numeric_limits<double>::infinity());
  for (const BoundaryEdge& be : boundary_edges(s)) {
    const std::uint32_t e = std::uint32_t(b.from.size());
    if (b.out_edge[be.from] != kNo || b.in_edge[be.to] != kNo)
      throw StitchError("a piece's boundary touches itself at a vertex (a pinched boundary)");
    b.from.push_back(be.from);
    b.to.push_back(be.to);
    b.slot.push_back(be.slot);
    b.edge_of_slot[be.slot] = e;
    b.out_edge[be.from] = e;
    b.in_edge[be.to] = e;
    const double len = glm::length(s.positions[be.to] - s.positions[be.from]);
    b.scale[be.from] = std::min(b.scale[be.from], len);
    b.scale[be.to] = std::min(b.scale[be.to], len);
  }
  return b;
}

// The nearest point on another piece's boundary, for every boundary vertex.
struct Partner {
  std::uint32_t edge = kNo;
  double t = 0, distance = std::numeric_limits<double>::infinity();
};

struct CellHash {
  std::size_t operator()(const glm::i64vec3& c) const {
    return std::size_t(c.x * 73856093 ^ c.y * 19349663 ^ c.z * 83492791);
  }
};

std::vector<Partner> find_partners(const Soup& s, const Boundary& b, double cell) {
  std::unordered_map<glm::i64vec3, std::vector<std::uint32_t>, CellHash> grid;
  auto cell_of = [&](const glm::dvec3& p) { return glm::i64vec3(glm::floor(p / cell)); };
  for (std::uint32_t e = 0; e < b.from.size(); ++e) {
    const glm::dvec3 p = s.positions[b.from[e]], q = s.positions[b.to[e]];
    const glm::i64vec3 lo = cell_of(glm::min(p, q)), hi = cell_of(glm::max(p, q));
    for (auto z = lo.z; z <= hi.z; ++z)
      for (auto y = lo.y; y <= hi.y; ++y)
        for (auto x = lo.x; x <= hi.x; ++x) grid[{x, y, z}].push_back(e);
  }
  std::vector<Partner> partner(s.positions.size());
  tbb::parallel_for(std::size_t(0), s.positions.size(), [&](std::size_t v) {
    if (b.out_edge[v] == kNo) return;
    const glm::dvec3 p = s.positions[v];
    const glm::i64vec3 c = cell_of(p);
    Partner best;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const auto it = grid.find(c + glm::i64vec3(dx, dy, dz));
          if (it == grid.end()) continue;
          for (std::uint32_t e : it->second) {
            if (s.piece[b.from[e]] == s.piece[v]) continue;
            const glm::dvec3 a = s.positions[b.from[e]], d = s.positions[b.to[e]] - a;
            const double dd = glm::dot(d, d);
            const double t = dd > 0 ? std::clamp(glm::dot(p - a, d) / dd, 0.0, 1.0) : 0.0;
            const double dist = glm::length(a + t * d - p);
            if (dist < best.distance || (dist == best.distance && e < best.edge)) best = {e, t, dist};
          }
        }
    partner[v] = best;
  });
  return partner;
}

// How far a boundary vertex may lie from its partner edge: max_gap, or more along a long edge,
// whose chord may cut a curved seam short by a fraction of its length.
double gap_allowed(const Soup& s, const Boundary& b, std::uint32_t e, const StitchOptions& o) {
  return std::max(o.max_gap, o.chord_fraction * glm::length(s.positions[b.to[e]] - s.positions[b.from[e]]));
}

struct Insertion {
  double t;
  std::uint32_t vertex;
};

// Welds and insertions from the partners; throws when a piece cannot find its counterpart.
void match(const Soup& s, const Boundary& b, const std::vector<Partner>& partner, const StitchOptions& o,
           UnionFind& uf, std::vector<std::vector<Insertion>>& inserted, StitchStats& st) {
  struct Weld {
    double distance;
    std::uint32_t v, w;
  };
  std::vector<Weld> welds;
  std::vector<std::uint8_t> open(s.positions.size(), 0);
  for (std::uint32_t v = 0; v < s.positions.size(); ++v) {
    if (b.out_edge[v] == kNo) continue;
    ++st.boundary_vertices;
    const Partner& p = partner[v];
    const glm::dvec3 x = s.positions[v];
    if ((p.edge == kNo || p.distance > gap_allowed(s, b, p.edge, o)) && o.allow_open) {
      open[v] = 1;
      ++st.left_open;
      continue;
    }
    if (p.edge == kNo || p.distance > gap_allowed(s, b, p.edge, o))
      throw StitchError("a boundary vertex at (" + std::to_string(x.x) + ", " + std::to_string(x.y) + ", " +
                        std::to_string(x.z) + ") has no other piece within " + std::to_string(o.max_gap));
    st.largest_gap = std::max(st.largest_gap, p.distance);
    // Distances along the partner edge: a vertex beside a partner vertex welds to it however
    // far beside it lies (within the gap), or it would be inserted on top of it.
    const std::uint32_t ends[2] = {b.from[p.edge], b.to[p.edge]};
    const double len = glm::length(s.positions[ends[1]] - s.positions[ends[0]]);
    const double along[2] = {p.t * len, (1.0 - p.t) * len};
    for (int k = 0; k < 2; ++k) {
      const std::uint32_t w = ends[k];
      if (along[k] <= o.weld_fraction * std::min(b.scale[v], b.scale[w]) || along[k] == 0.0)
        welds.push_back({along[k], std::min(v, w), std::max(v, w)});
    }
  }
  // Nearest pairs first; a weld that would put two vertices of one piece in one class is
  // skipped (that piece would fold onto itself).
  std::sort(welds.begin(), welds.end(), [](const Weld& x, const Weld& y) {
    return x.distance != y.distance ? x.distance < y.distance : x.v != y.v ? x.v < y.v : x.w < y.w;
  });
  std::vector<std::uint64_t> pieces_in(s.positions.size(), 0);
  for (std::uint32_t v = 0; v < s.positions.size(); ++v) pieces_in[v] = std::uint64_t(1) << s.piece[v];
  for (const Weld& w : welds) {
    const std::uint32_t a = uf.find(w.v), c = uf.find(w.w);
    if (a == c || (pieces_in[a] & pieces_in[c])) continue;
    uf.unite(a, c);
    pieces_in[uf.find(a)] = pieces_in[a] | pieces_in[c];
    ++st.welded;
  }
  for (std::uint32_t v = 0; v < s.positions.size(); ++v) {
    if (b.out_edge[v] == kNo || open[v]) continue;
    const Partner& p = partner[v];
    const std::uint32_t r = uf.find(v);
    if (r == uf.find(b.from[p.edge]) || r == uf.find(b.to[p.edge])) continue;
    if (p.t <= 0.0 || p.t >= 1.0) throw StitchError("a boundary vertex faces a partner vertex it cannot weld to");
    inserted[p.edge].push_back({p.t, v});
  }
  for (auto& list : inserted) {
    std::sort(list.begin(), list.end(), [](const Insertion& x, const Insertion& y) { return x.t != y.t ? x.t < y.t : x.vertex < y.vertex; });
    list.erase(std::unique(list.begin(), list.end(),
                           [&](const Insertion& x, const Insertion& y) { return uf.find(x.vertex) == uf.find(y.vertex); }),
               list.end());
    st.inserted += list.size();
  }
}

TriangleMesh stitch_soup(Soup s, const StitchOptions& o, StitchStats* stats, std::vector<std::uint8_t>* seam) {
  StitchStats st;
  const Boundary b = find_boundary(s);
  UnionFind uf(s.positions.size());
  std::vector<std::vector<Insertion>> inserted(b.from.size());
  if (!b.from.empty()) {
    if (!(o.max_gap > 0)) throw StitchError("stitching open pieces needs a max_gap > 0");
    double longest = 0;
    for (std::uint32_t e = 0; e < b.from.size(); ++e) longest = std::max(longest, gap_allowed(s, b, e, o));
    const auto partner = find_partners(s, b, longest);
    match(s, b, partner, o, uf, inserted, st);
    // A vertex inserted into an earlier piece's edge moves onto it: the seam is the earlier
    // piece's polyline exactly, so two nearly tangent pieces cannot zigzag across each other.
    // Every move is found from the positions before any (an edge's ends may be inserted
    // vertices too), then made.
    std::vector<std::pair<std::uint32_t, glm::dvec3>> moves;
    for (std::uint32_t e = 0; e < inserted.size(); ++e)
      for (const Insertion& in : inserted[e])
        if (o.onto_earlier && s.piece[b.from[e]] < s.piece[in.vertex]) {
          const glm::dvec3 a = s.positions[b.from[e]], d = s.positions[b.to[e]] - a;
          moves.emplace_back(in.vertex, a + in.t * d);
        }
    for (const auto& [v, p] : moves) s.positions[v] = p;
  }

  // Output vertices: one per weld class, in order of the class's first id.
  TriangleMesh out;
  out.positions.reserve(s.positions.size());
  out.triangles.reserve(s.triangles.size() + 2 * st.inserted);  // a fan adds a triangle an insertion
  std::vector<std::uint32_t> index(s.positions.size(), kNo);
  for (std::uint32_t v = 0; v < s.positions.size(); ++v) {
    const std::uint32_t r = uf.find(v);
    if (index[r] == kNo) {
      index[r] = std::uint32_t(out.positions.size());
      out.positions.push_back(s.positions[r]);
      if (seam) seam->push_back(b.out_edge[r] != kNo);
    }
    index[v] = index[r];
  }
  std::vector<std::uint32_t> ring;
  for (std::uint32_t t = 0; t < s.triangles.size(); ++t) {
    const glm::uvec3 tri = s.triangles[t];
    int split_edges = 0, split_slot = 0;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t e = b.edge_of_slot[3 * t + std::uint32_t(k)];
      if (e != kNo && !inserted[e].empty()) ++split_edges, split_slot = k;
    }
    const glm::uvec3 m(index[tri[0]], index[tri[1]], index[tri[2]]);
    if (m[0] == m[1] || m[1] == m[2] || m[2] == m[0]) continue;  // collapsed by welding
    if (split_edges == 0) {
      out.triangles.push_back(m);
      continue;
    }
    ++st.fans;
    ring.clear();
    for (int k = 0; k < 3; ++k) {
      ring.push_back(m[k]);
      const std::uint32_t e = b.edge_of_slot[3 * t + std::uint32_t(k)];
      if (e != kNo)
        for (const Insertion& in : inserted[e]) ring.push_back(index[in.vertex]);
    }
    std::uint32_t apex;
    std::size_t first;
    if (split_edges == 1) {  // fan from the corner facing the split edge
      apex = m[(split_slot + 2) % 3];
      first = std::size_t(std::find(ring.begin(), ring.end(), m[split_slot]) - ring.begin());
    } else {  // fan from the centroid of the final ring (the seam vertices may have moved)
      glm::dvec3 centre(0.0);
      for (std::uint32_t r : ring) centre += out.positions[r];
      apex = std::uint32_t(out.positions.size());
      out.positions.push_back(centre / double(ring.size()));
      if (seam) seam->push_back(0);
      first = 0;
    }
    const std::size_t n = ring.size();
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t p = ring[(first + i) % n], q = ring[(first + i + 1) % n];
      if (p != apex && q != apex && p != q) out.triangles.push_back({p, q, apex});
    }
  }
  if (stats) *stats = st;
  return out;
}

}  // namespace

TriangleMesh stitch(std::span<const TriangleMesh* const> pieces, const StitchOptions& o, StitchStats* stats,
                    std::vector<std::uint8_t>* seam) {
  if (pieces.size() > 64) throw StitchError("stitching takes at most 64 pieces");
  return stitch_soup(concatenate(pieces), o, stats, seam);
}

TriangleMesh stitch(std::vector<TriangleMesh>&& pieces, const StitchOptions& o, StitchStats* stats,
                    std::vector<std::uint8_t>* seam) {
  if (pieces.size() > 64) throw StitchError("stitching takes at most 64 pieces");
  return stitch_soup(concatenate(std::move(pieces)), o, stats, seam);
}

}  // namespace ht
