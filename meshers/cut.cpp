#include "meshers/cut.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <vector>

namespace ht {
namespace {

std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
  return (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b);
}

// The edges whose ends c puts on opposite sides, sorted by key, the kept end first, with the
// parameter t of c's root from the kept end.
struct Crossings {
  std::vector<std::uint64_t> keys;
  std::vector<std::uint32_t> kept_end, cut_end;
  std::vector<double> t;

  std::uint32_t find(std::uint32_t a, std::uint32_t b) const {
    const auto it = std::lower_bound(keys.begin(), keys.end(), edge_key(a, b));
    return it != keys.end() && *it == edge_key(a, b) ? std::uint32_t(it - keys.begin()) : ~0u;
  }
};

// side: -1 kept, 0 on the cut, +1 dropped.
Crossings find_crossings(const TriangleMesh& mesh, std::span<const std::int8_t> side) {
  Crossings x;
  for (const glm::uvec3& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % 3];
      if (side[a] * side[b] < 0) x.keys.push_back(edge_key(a, b));
    }
  std::sort(x.keys.begin(), x.keys.end());
  x.keys.erase(std::unique(x.keys.begin(), x.keys.end()), x.keys.end());
  for (std::uint64_t key : x.keys) {
    const std::uint32_t lo = std::uint32_t(key >> 32), hi = std::uint32_t(key);
    x.kept_end.push_back(side[lo] < 0 ? lo : hi);
    x.cut_end.push_back(side[lo] < 0 ? hi : lo);
  }
  return x;
}

// Illinois false position along every crossing edge at once, one batch of c per step.
std::size_t find_roots(std::span<const glm::dvec3> pos, std::span<const double> cv, const BatchField& c,
                       const CutOptions& o, Crossings& x) {
  const std::size_t n = x.keys.size();
  struct Bracket {
    double ta = 0.0, tb = 1.0, fa, fb, span;
    int side = 0;  // which end the last step replaced: -1 a, 1 b, 0 none yet
  };
  std::vector<Bracket> br(n);
  x.t.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    Bracket& b = br[i];
    b.fa = cv[x.kept_end[i]];
    b.fb = cv[x.cut_end[i]];
    b.span = b.fb - b.fa;
    x.t[i] = b.span > 0 ? -b.fa / b.span : 0.5;
  }
  std::vector<std::uint32_t> live(n);
  std::iota(live.begin(), live.end(), 0u);
  std::vector<glm::dvec3> pts;
  std::vector<double> vals;
  std::size_t evaluations = 0;
  for (int step = 0; step < o.refine_steps && !live.empty(); ++step) {
    evaluations += live.size();
    pts.resize(live.size());
    vals.resize(live.size());
    for (std::size_t j = 0; j < live.size(); ++j) {
      const std::uint32_t i = live[j];
      pts[j] = pos[x.kept_end[i]] + x.t[i] * (pos[x.cut_end[i]] - pos[x.kept_end[i]]);
    }
    c(pts, vals);
    std::size_t kept = 0;
    for (std::size_t j = 0; j < live.size(); ++j) {
      const std::uint32_t i = live[j];
      Bracket& b = br[i];
      const double f = vals[j];
      // Illinois: an end kept twice in a row has its weight halved, so the bracket closes from
      // both sides. (Halving it at every step, fresh or not, left most edges creeping for ten
      // steps and more. Anderson-Bjorck's scaling, tried, saved a fifth of the values on the
      // bowl and took more on the winged bunny, whose distance fields bend at medial axes.)
      if (f < 0) {
        b.ta = x.t[i];
        b.fa = f;
        if (b.side < 0) b.fb *= 0.5;
        b.side = -1;
      } else {
        b.tb = x.t[i];
        b.fb = f;
        if (b.side > 0) b.fa *= 0.5;
        b.side = 1;
      }
      if (std::abs(f) <= o.refine_tolerance * b.span || b.tb - b.ta <= o.refine_tolerance) continue;
      x.t[i] = b.fb > b.fa ? b.ta - b.fa / (b.fb - b.fa) * (b.tb - b.ta) : 0.5 * (b.ta + b.tb);
      live[kept++] = i;
    }
    live.resize(kept);
  }
  return evaluations;
}

// Moves every vertex that has a root within o.snap of it onto its nearest such root and puts
// it on the cut. Returns how many moved.
std::size_t snap_vertices(std::vector<glm::dvec3>& pos, std::vector<std::int8_t>& side, const Crossings& x,
                          const CutOptions& o, const std::vector<std::uint8_t>& no_snap) {
  std::vector<double> best(pos.size(), o.snap);
  std::vector<std::uint32_t> pick(pos.size(), ~0u);
  std::vector<std::uint8_t> end(pos.size(), 0);
  for (std::uint32_t i = 0; i < x.keys.size(); ++i) {
    const double t = x.t[i];
    const double len = glm::length(pos[x.cut_end[i]] - pos[x.kept_end[i]]);
    const std::uint32_t a = x.kept_end[i], b = x.cut_end[i];
    auto reach = [&](std::uint32_t v) { return v >= o.snap_freely_from ? len : o.snap_distance; };
    if (t < best[a] && t * len <= reach(a)) best[a] = t, pick[a] = i, end[a] = 0;
    if (1.0 - t < best[b] && (1.0 - t) * len <= reach(b)) best[b] = 1.0 - t, pick[b] = i, end[b] = 1;
  }
  const std::vector<glm::dvec3> before = pos;
  std::size_t moved = 0;
  for (std::size_t v = 0; v < pos.size(); ++v) {
    if (pick[v] == ~0u || no_snap[v]) continue;
    const std::uint32_t i = pick[v];
    const glm::dvec3 a = before[x.kept_end[i]], b = before[x.cut_end[i]];
    pos[v] = a + x.t[i] * (b - a);
    side[v] = 0;
    ++moved;
  }
  return moved;
}

double min_angle_cos(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  // The largest cosine of the triangle's angles (the smallest angle has the largest cosine).
  auto cosine = [](const glm::dvec3& o, const glm::dvec3& p, const glm::dvec3& q) {
    const glm::dvec3 u = p - o, v = q - o;
    const double l = glm::length(u) * glm::length(v);
    return l > 0 ? glm::dot(u, v) / l : 1.0;
  };
  return std::max({cosine(a, b, c), cosine(b, c, a), cosine(c, a, b)});
}

// The vertices of `snapped` (of `m`: vertices moved onto the cut) with more than one outgoing
// boundary edge, where the kept part pinches. Only they can: the roots lie on one crossing edge
// each, and a vertex off the cut has no boundary edge from the cut. Reads their fans alone (both
// triangles of an edge from one are in them), not the whole mesh.
std::vector<std::uint32_t> pinched(const TriangleMesh& m, std::span<const std::uint32_t> snapped) {
  if (snapped.empty()) return {};
  std::vector<std::uint8_t> count(m.positions.size(), 0), mark(m.positions.size(), 0);
  for (std::uint32_t v : snapped) mark[v] = 1;
  auto key = [](std::uint32_t a, std::uint32_t b) { return std::uint64_t(a) << 32 | b; };
  std::vector<std::uint64_t> sides;
  for (const glm::uvec3& t : m.triangles)
    if (mark[t[0]] || mark[t[1]] || mark[t[2]])
      for (int k = 0; k < 3; ++k) sides.push_back(key(t[k], t[(k + 1) % 3]));
  std::sort(sides.begin(), sides.end());
  std::vector<std::uint32_t> bad;
  for (const std::uint64_t k : sides) {
    const std::uint32_t from = std::uint32_t(k >> 32), to = std::uint32_t(k);
    if (mark[from] && !std::binary_search(sides.begin(), sides.end(), key(to, from)) && ++count[from] == 2)
      bad.push_back(from);
  }
  return bad;
}

// `source`: each output vertex's input vertex (~0u for a root); `snapped`: the output vertices
// moved onto the cut.
TriangleMesh cut_once(const TriangleMesh& mesh, std::span<const double> cv, const BatchField& c,
                      const CutOptions& options, const std::vector<std::uint8_t>& no_snap, CutStats& s,
                      std::vector<std::uint32_t>& source, std::vector<std::uint32_t>& snapped);

}  // namespace

TriangleMesh cut_mesh(const TriangleMesh& mesh, const BatchField& c, const CutOptions& options, CutStats* stats) {
  std::vector<double> cv(mesh.positions.size());
  c(mesh.positions, cv);
  return cut_mesh(mesh, cv, c, options, stats);
}

TriangleMesh cut_mesh(const TriangleMesh& mesh, std::span<const double> cv, const BatchField& c,
                      const CutOptions& options, CutStats* stats) {
  // A snapped vertex where the cut passes twice pinches the kept part: cut again without
  // snapping it.
  std::vector<std::uint8_t> no_snap(mesh.positions.size(), 0);
  std::size_t evaluations = 0;
  for (int attempt = 0;; ++attempt) {
    CutStats s;
    std::vector<std::uint32_t> source, snapped;
    TriangleMesh out = cut_once(mesh, cv, c, options, no_snap, s, source, snapped);
    const auto bad = pinched(out, snapped);
    bool retry = false;
    for (std::uint32_t v : bad)
      if (source[v] != ~0u && !no_snap[source[v]]) no_snap[source[v]] = 1, retry = true;
    evaluations += s.root_evaluations;
    if (!retry || attempt == 3) {
      s.root_evaluations = evaluations;
      if (stats) *stats = s;
      return out;
    }
  }
}

namespace {

TriangleMesh cut_once(const TriangleMesh& mesh, std::span<const double> cv, const BatchField& c,
                      const CutOptions& options, const std::vector<std::uint8_t>& no_snap, CutStats& s,
                      std::vector<std::uint32_t>& source, std::vector<std::uint32_t>& snapped) {
  std::vector<glm::dvec3> pos = mesh.positions;
  std::vector<std::int8_t> side(pos.size());
  for (std::size_t v = 0; v < pos.size(); ++v) side[v] = cv[v] < 0 ? -1 : 1;
  // Snap vertices that lie near the cut onto it, then find the roots of the edges still crossing.
  Crossings x = find_crossings(mesh, side);
  s.root_evaluations += find_roots(pos, cv, c, options, x);
  s.snapped_vertices = snap_vertices(pos, side, x, options, no_snap);
  if (s.snapped_vertices) {
    // A snapped vertex is on the cut (side 0), so the edges still crossing have both ends as
    // they were: the same ends, values and roots, taken over rather than searched again.
    Crossings still = find_crossings(mesh, side);
    still.t.resize(still.keys.size());
    bool all_known = true;
    for (std::size_t i = 0; i < still.keys.size() && all_known; ++i) {
      const std::uint32_t j = x.find(still.kept_end[i], still.cut_end[i]);
      all_known = j != ~0u && x.kept_end[j] == still.kept_end[i];
      if (all_known) still.t[i] = x.t[j];
    }
    x = std::move(still);
    if (!all_known) s.root_evaluations += find_roots(pos, cv, c, options, x);
  }

  // Each triangle's kept polygon: its corners on the kept side and the roots between, in order
  // (vertices 0..n-1 are the mesh's, n.. the roots). Made twice, to mark the vertices used and
  // then to emit, rather than stored (16 bytes a triangle at the peak of a Boolean).
  auto polygon = [&](const glm::uvec3& t, std::uint32_t (&poly)[4]) {
    int n = 0;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % 3];
      if (side[a] <= 0) poly[n++] = a;
      if (side[a] * side[b] < 0) poly[n++] = std::uint32_t(pos.size()) + x.find(a, b);
    }
    return n;
  };
  std::vector<std::uint32_t> index(pos.size() + x.keys.size(), ~0u);
  std::uint32_t poly[4];
  std::size_t used = 0, emitted = 0;
  for (const glm::uvec3& t : mesh.triangles) {
    const int n = polygon(t, poly);
    if (n < 3) {
      ++s.dropped_triangles;
      continue;
    }
    ++(n == 3 && side[t[0]] < 0 && side[t[1]] < 0 && side[t[2]] < 0 ? s.kept_triangles : s.clipped_triangles);
    emitted += std::size_t(n - 2);
    for (int k = 0; k < n; ++k) used += index[poly[k]] == ~0u, index[poly[k]] = 0;
  }
  // Positions: the mesh's used vertices in order, then the used roots.
  auto position = [&](std::uint32_t v) {
    if (v < pos.size()) return pos[v];
    const std::uint32_t i = v - std::uint32_t(pos.size());
    const glm::dvec3 a = pos[x.kept_end[i]], b = pos[x.cut_end[i]];
    return a + x.t[i] * (b - a);
  };
  TriangleMesh out;
  out.positions.reserve(used);
  source.reserve(used);
  for (std::uint32_t v = 0; v < index.size(); ++v)
    if (index[v] != ~0u) {
      index[v] = std::uint32_t(out.positions.size());
      out.positions.push_back(position(v));
      source.push_back(v < pos.size() ? v : ~0u);
      if (v < pos.size() && side[v] == 0) snapped.push_back(index[v]);
      if (v >= pos.size()) ++s.new_vertices;
      else ++s.kept_vertices;
    }
  out.triangles.reserve(emitted);
  for (const glm::uvec3& t : mesh.triangles) {
    const int n = polygon(t, poly);
    if (n < 3) continue;
    if (n == 3) {
      out.triangles.push_back({index[poly[0]], index[poly[1]], index[poly[2]]});
      continue;
    }
    // A quad: cut along the diagonal that gives the better smallest angle.
    const std::uint32_t q[4] = {index[poly[0]], index[poly[1]], index[poly[2]], index[poly[3]]};
    const auto& P = out.positions;
    const double d02 = std::max(min_angle_cos(P[q[0]], P[q[1]], P[q[2]]), min_angle_cos(P[q[0]], P[q[2]], P[q[3]]));
    const double d13 = std::max(min_angle_cos(P[q[0]], P[q[1]], P[q[3]]), min_angle_cos(P[q[1]], P[q[2]], P[q[3]]));
    if (d02 <= d13) {
      out.triangles.push_back({q[0], q[1], q[2]});
      out.triangles.push_back({q[0], q[2], q[3]});
    } else {
      out.triangles.push_back({q[0], q[1], q[3]});
      out.triangles.push_back({q[1], q[2], q[3]});
    }
  }
  return out;
}

}  // namespace
}  // namespace ht
