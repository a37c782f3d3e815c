#include "meshers/bridge.hpp"

#include "meshers/edges.hpp"
#include "meshers/union_find.hpp"

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <unordered_map>

namespace ht {
namespace {

constexpr std::uint32_t kNo = ~0u;

// Directed boundary edges: from -> to for every edge used by one triangle. A vertex with two
// outgoing boundary edges (where the boundary touches itself) goes to `pinched` if given, else
// throws.
std::vector<std::uint32_t> boundary_next(const TriangleMesh& m, std::vector<std::uint32_t>* pinched = nullptr) {
  std::vector<std::uint32_t> next(m.positions.size(), kNo);
  for (const BoundaryEdge& e : boundary_edges(m)) {
    if (next[e.from] != kNo) {
      if (!pinched) throw BridgeError("a boundary touches itself at a vertex");
      pinched->push_back(e.from);
    }
    next[e.from] = e.to;
  }
  return next;
}

struct CellHash {
  std::size_t operator()(const glm::i64vec3& c) const { return std::size_t(c.x * 73856093 ^ c.y * 19349663 ^ c.z * 83492791); }
};

// The loop and position within it of the nearest patch boundary vertex within `reach`.
struct Nearest {
  std::uint32_t loop = kNo, at = 0;
  double distance = std::numeric_limits<double>::infinity();
};

class PatchIndex {
 public:
  PatchIndex(const std::vector<glm::dvec3>& pos, const std::vector<std::vector<std::uint32_t>>& loops, double cell)
      : pos_(pos), loops_(loops), cell_(cell) {
    for (std::uint32_t l = 0; l < loops.size(); ++l)
      for (std::uint32_t i = 0; i < loops[l].size(); ++i) grid_[key(pos[loops[l][i]])].push_back({l, i});
  }
  Nearest find(const glm::dvec3& p) const {
    Nearest best;
    const glm::i64vec3 c = key(p);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const auto it = grid_.find(c + glm::i64vec3(dx, dy, dz));
          if (it == grid_.end()) continue;
          for (const auto& [l, i] : it->second) {
            const double d = glm::length(pos_[loops_[l][i]] - p);
            if (d < best.distance) best = {l, i, d};
          }
        }
    return best;
  }

 private:
  glm::i64vec3 key(const glm::dvec3& p) const { return glm::i64vec3(glm::floor(p / cell_)); }
  const std::vector<glm::dvec3>& pos_;
  const std::vector<std::vector<std::uint32_t>>& loops_;
  double cell_;
  std::unordered_map<glm::i64vec3, std::vector<std::pair<std::uint32_t, std::uint32_t>>, CellHash> grid_;
};

glm::dvec3 normal(const std::vector<glm::dvec3>& pos, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  const glm::dvec3 n = glm::cross(pos[b] - pos[a], pos[c] - pos[a]);
  const double l = glm::length(n);
  return l > 0 ? n / l : n;
}

// Arc length from the start to each vertex, as a fraction of the loop's length (n + 1 entries).
std::vector<double> arc_fractions(const std::vector<glm::dvec3>& pos, std::size_t n, const auto& at) {
  std::vector<double> s(n + 1, 0.0);
  for (std::size_t k = 0; k < n; ++k) s[k + 1] = s[k] + glm::length(pos[at(k + 1)] - pos[at(k)]);
  for (double& x : s) x /= s[n] > 0 ? s[n] : 1.0;
  return s;
}

// The strip between loop a (walked forward) and loop b (walked backward from b[start]). Each
// step takes the shorter of the two diagonals, unless one loop lags behind the other (in arc
// length), and a triangle that would turn against the surface beside it (`side`, the loops' own
// vertex normals) only where the other would too or the other loop lags.
std::vector<glm::uvec3> zip(const std::vector<glm::dvec3>& pos, const std::vector<glm::dvec3>& side,
                            const std::vector<std::uint32_t>& a, const std::vector<std::uint32_t>& b,
                            std::size_t start, double max_width, double& widest) {
  const std::size_t m = a.size(), n = b.size();
  auto A = [&](std::size_t i) { return a[i % m]; };
  auto B = [&](std::size_t j) { return b[(start + n - j % n) % n]; };
  const std::vector<double> sa = arc_fractions(pos, m, A), sb = arc_fractions(pos, n, B);
  // How far one loop may run ahead of the other, as a fraction of their lengths: 4%, and no
  // more than half the widest band allowed (on a long loop, 4% is wider than any band).
  double length = 0.0;
  for (std::size_t i = 0; i < m; ++i) length += glm::length(pos[A(i + 1)] - pos[A(i)]);
  for (std::size_t j = 0; j < n; ++j) length += glm::length(pos[B(j + 1)] - pos[B(j)]);
  const double lag = length > 0 ? std::min(0.04, 0.5 * max_width / (0.5 * length)) : 0.04;
  std::vector<glm::uvec3> out;
  out.reserve(m + n);
  std::size_t i = 0, j = 0;
  while (i < m || j < n) {
    const glm::dvec3 up = side[A(i)] + side[B(j)];
    const bool a_ok = i < m && glm::dot(normal(pos, A(i + 1), A(i), B(j)), up) > 0;
    const bool b_ok = j < n && glm::dot(normal(pos, B(j), B(j + 1), A(i)), up) > 0;
    // The shorter diagonal follows the loops' local shape; the arc fractions keep the walk from
    // running away along one loop where the shapes differ.
    constexpr double kNever = std::numeric_limits<double>::infinity();
    const double da = i < m ? glm::length(pos[A(i + 1)] - pos[B(j)]) : kNever;
    const double db = j < n ? glm::length(pos[B(j + 1)] - pos[A(i)]) : kNever;
    const bool a_lags = j == n || (i < m && sb[j] - sa[i] > lag), b_lags = !a_lags && (i == m || sa[i] - sb[j] > lag);
    bool advance_a = a_lags || (!b_lags && da <= db);
    // A triangle turned against the surface is avoided by advancing the other loop, unless that
    // one lags already: where the two loops touch and cross by a hair (a cut that wanders across
    // the patch's rim), one loop's edge can see all the other's next vertices on its wrong side,
    // and sparing it ran the other loop away until the band passed its width (the bowl at
    // h = 0.001 and the winged bunny at 0.0068 fell back to global so). The few turned triangles
    // made instead are the band's relaxing, untangling and remeshing's to mend.
    if (advance_a && !a_ok && b_ok && !a_lags) advance_a = false;
    if (!advance_a && !b_ok && a_ok && !b_lags) advance_a = true;
    const double d = advance_a ? da : db;
    widest = std::max(widest, d);
    if (d > max_width) throw BridgeError("a band would span " + std::to_string(d) + ", wider than " + std::to_string(max_width));
    if (advance_a) {
      out.push_back({A(i + 1), A(i), B(j)});
      ++i;
    } else {
      out.push_back({B(j), B(j + 1), A(i)});
      ++j;
    }
  }
  return out;
}

// Per vertex of `loops`: the sum of the unit normals of its triangles (the direction of the
// surface there), in triangle order; 0 elsewhere (the bands read the loops' alone).
std::vector<glm::dvec3> loop_normals(const TriangleMesh& m, std::span<const std::vector<std::uint32_t>> loops) {
  std::vector<std::uint8_t> on(m.positions.size(), 0);
  for (const auto& loop : loops)
    for (const std::uint32_t v : loop) on[v] = 1;
  std::vector<glm::dvec3> n(m.positions.size(), glm::dvec3(0.0));
  for (const glm::uvec3& t : m.triangles) {
    if (!on[t[0]] && !on[t[1]] && !on[t[2]]) continue;
    const glm::dvec3 f = normal(m.positions, t[0], t[1], t[2]);
    for (int k = 0; k < 3; ++k) n[t[k]] += f;
  }
  return n;
}

double perimeter(const std::vector<glm::dvec3>& pos, const std::vector<std::uint32_t>& loop) {
  double sum = 0.0;
  for (std::size_t i = 0; i < loop.size(); ++i) sum += glm::length(pos[loop[(i + 1) % loop.size()]] - pos[loop[i]]);
  return sum;
}

// The patch loops (indices into `loops`, whose vertices are the patch's plus `base`) that no
// operand loop took, if each is shorter than `longest` and lies on a piece of the patch that has
// a loop an operand loop took (a hole beside a seam, not the rim of an island); empty otherwise,
// and then the caller's count check fails.
std::vector<std::size_t> unfaced_specks(const std::vector<glm::dvec3>& pos, const TriangleMesh& patch, std::uint32_t base,
                                        const std::vector<std::vector<std::uint32_t>>& loops,
                                        const std::vector<std::uint32_t>& taken, double longest) {
  if (std::all_of(taken.begin(), taken.end(), [](std::uint32_t t) { return t != 0; })) return {};  // the common case
  UnionFind parts(patch.positions.size());
  for (const glm::uvec3& t : patch.triangles) parts.unite(t[0], t[1]), parts.unite(t[0], t[2]);
  std::unordered_map<std::uint32_t, std::size_t> seams_on;
  for (std::size_t l = 0; l < loops.size(); ++l) seams_on[parts.find(loops[l][0] - base)] += taken[l] ? 1 : 0;
  std::vector<std::size_t> out;
  for (std::size_t l = 0; l < loops.size(); ++l) {
    if (taken[l]) continue;
    if (!(perimeter(pos, loops[l]) <= longest) || seams_on[parts.find(loops[l][0] - base)] == 0) return {};
    out.push_back(l);
  }
  return out;
}

// Closes a hole by a fan: one triangle for three edges, else around a new vertex at the loop's
// centroid (the local strategies' remeshing of the patch moves it onto the surface). The new
// triangles run against the loop, as the mesh's own run along it.
void close_hole(TriangleMesh& m, const std::vector<std::uint32_t>& loop) {
  const std::size_t n = loop.size();
  if (n == 3) {
    m.triangles.push_back({loop[0], loop[2], loop[1]});
    return;
  }
  glm::dvec3 centre(0.0);
  for (const std::uint32_t v : loop) centre += m.positions[v];
  const auto c = static_cast<std::uint32_t>(m.positions.size());
  m.positions.push_back(centre / double(n));
  for (std::size_t i = 0; i < n; ++i) m.triangles.push_back({c, loop[(i + 1) % n], loop[i]});
}

}  // namespace

std::vector<std::vector<std::uint32_t>> boundary_loops(const TriangleMesh& mesh) {
  std::vector<std::uint32_t> next = boundary_next(mesh);
  std::vector<std::vector<std::uint32_t>> loops;
  for (std::uint32_t v = 0; v < next.size(); ++v) {
    if (next[v] == kNo) continue;
    std::vector<std::uint32_t> loop;
    for (std::uint32_t w = v; next[w] != kNo;) {
      loop.push_back(w);
      const std::uint32_t n = next[w];
      next[w] = kNo;
      w = n;
    }
    if (loop.size() < 3) throw BridgeError("a boundary loop of fewer than three edges");
    loops.push_back(std::move(loop));
  }
  return loops;
}

// The triangles of `m` but those with a corner marked in `drop`, unused vertices removed, the
// others in their original order.
// `renumber` (if given) receives each vertex's new index, kNo for those removed.
TriangleMesh without(const TriangleMesh& m, const std::vector<std::uint8_t>& drop, std::vector<std::uint32_t>* renumber = nullptr) {
  std::vector<std::uint8_t> used(m.positions.size(), 0);
  for (const glm::uvec3& t : m.triangles)
    if (!drop[t[0]] && !drop[t[1]] && !drop[t[2]]) used[t[0]] = used[t[1]] = used[t[2]] = 1;
  std::vector<std::uint32_t> local;
  std::vector<std::uint32_t>& index = renumber ? *renumber : local;
  index.assign(m.positions.size(), kNo);
  TriangleMesh out;
  for (std::uint32_t v = 0; v < m.positions.size(); ++v)
    if (used[v]) index[v] = std::uint32_t(out.positions.size()), out.positions.push_back(m.positions[v]);
  for (const glm::uvec3& t : m.triangles)
    if (!drop[t[0]] && !drop[t[1]] && !drop[t[2]]) out.triangles.push_back({index[t[0]], index[t[1]], index[t[2]]});
  return out;
}

bool drop_pinched_fans(TriangleMesh& mesh, std::vector<std::uint32_t>* renumber) {
  if (renumber) {
    renumber->resize(mesh.positions.size());
    std::iota(renumber->begin(), renumber->end(), 0u);
  }
  bool changed = false;
  for (int round = 0; round < 8; ++round) {
    std::vector<std::uint32_t> pinched;
    boundary_next(mesh, &pinched);
    if (pinched.empty()) break;
    std::vector<std::uint8_t> drop(mesh.positions.size(), 0);
    for (std::uint32_t v : pinched) drop[v] = 1;
    std::vector<std::uint32_t> index;
    mesh = without(mesh, drop, &index);
    if (renumber)
      for (std::uint32_t& v : *renumber)
        if (v != kNo) v = index[v];
    changed = true;
  }
  return changed;
}

TriangleMesh pull_back_boundary(const TriangleMesh& mesh) {
  std::vector<std::uint8_t> drop(mesh.positions.size(), 0);
  const std::vector<std::uint32_t> next = boundary_next(mesh);
  for (std::size_t v = 0; v < next.size(); ++v) drop[v] = next[v] != kNo;
  TriangleMesh out = without(mesh, drop);
  // Pulling back can leave vertices where the new boundary touches itself: drop their fans too.
  drop_pinched_fans(out);
  // A piece that lost every interior vertex (a lone triangle whose neighbours all touched the
  // boundary) is all rim: no seam faces it, so it goes too.
  const std::vector<std::uint32_t> rim = boundary_next(out);
  UnionFind parts(out.positions.size());
  for (const glm::uvec3& t : out.triangles) parts.unite(t[0], t[1]), parts.unite(t[0], t[2]);
  std::vector<std::uint8_t> inner(out.positions.size(), 0), drop_rim(out.positions.size(), 0);
  bool any = false;
  for (std::uint32_t v = 0; v < out.positions.size(); ++v)
    if (rim[v] == kNo) inner[parts.find(v)] = 1;
  for (std::uint32_t v = 0; v < out.positions.size(); ++v)
    if (!inner[parts.find(v)]) drop_rim[v] = 1, any = true;
  return any ? without(out, drop_rim) : out;
}

TriangleMesh bridge(std::span<const TriangleMesh* const> operands, const TriangleMesh& patch, double max_width,
                    BridgeStats* stats, std::uint32_t* patch_begin) {
  TriangleMesh out;
  std::vector<std::vector<std::uint32_t>> op_loops;  // each operand's, in the joined numbering
  for (const TriangleMesh* m : operands) {
    const std::uint32_t first = append(out, *m);
    for (auto& loop : boundary_loops(*m)) {
      for (std::uint32_t& v : loop) v += first;
      op_loops.push_back(std::move(loop));
    }
  }
  const std::uint32_t base = append(out, patch);
  if (patch_begin) *patch_begin = base;

  auto patch_loops = boundary_loops(patch);
  for (auto& l : patch_loops)
    for (auto& v : l) v += base;
  const auto mismatch = [&] {
    return BridgeError(std::to_string(op_loops.size()) + " operand loops face " + std::to_string(patch_loops.size()) +
                       " patch loops");
  };
  if (op_loops.size() > patch_loops.size()) throw mismatch();
  const PatchIndex index(out.positions, patch_loops, max_width);
  // Each operand loop faces the patch loop most of its vertices are nearest to.
  std::vector<std::uint32_t> partner(op_loops.size(), kNo), taken(patch_loops.size(), 0);
  std::vector<std::size_t> start(op_loops.size(), 0);
  for (std::size_t l = 0; l < op_loops.size(); ++l) {
    std::unordered_map<std::uint32_t, std::size_t> votes;
    for (std::uint32_t v : op_loops[l]) {
      const Nearest n = index.find(out.positions[v]);
      if (n.loop != kNo) ++votes[n.loop];
    }
    std::size_t best = 0;
    for (const auto& [loop, count] : votes)
      if (count > best || (count == best && loop < partner[l])) best = count, partner[l] = loop;
    if (partner[l] == kNo || 2 * best < op_loops[l].size()) throw BridgeError("an operand loop faces no patch loop");
    if (taken[partner[l]]++) throw BridgeError("two operand loops face the same patch loop");
    start[l] = index.find(out.positions[op_loops[l][0]]).at;
    if (index.find(out.positions[op_loops[l][0]]).loop != partner[l])
      throw BridgeError("an operand loop's first vertex faces another patch loop");
  }
  // A patch loop no operand loop faces is a speck the cut left (where the operands' fields both
  // dip under eps for a moment): closed, when small and a hole in a piece that has a seam.
  const std::vector<std::size_t> specks = unfaced_specks(out.positions, patch, base, patch_loops, taken, 0.25 * max_width);
  if (op_loops.size() + specks.size() != patch_loops.size()) throw mismatch();
  for (const std::size_t l : specks) close_hole(out, patch_loops[l]);
  std::vector<std::vector<std::uint32_t>> faced(op_loops);
  for (std::size_t l = 0; l < op_loops.size(); ++l) faced.push_back(patch_loops[partner[l]]);
  const std::vector<glm::dvec3> side = loop_normals(out, faced);
  std::vector<std::vector<glm::uvec3>> bands(op_loops.size());
  std::vector<double> widest(op_loops.size(), 0.0);
  tbb::parallel_for(std::size_t(0), op_loops.size(), [&](std::size_t l) {
    bands[l] = zip(out.positions, side, op_loops[l], patch_loops[partner[l]], start[l], max_width, widest[l]);
  });
  BridgeStats st;
  st.loops = op_loops.size();
  st.holes_closed = specks.size();
  for (std::size_t l = 0; l < bands.size(); ++l) {
    out.triangles.insert(out.triangles.end(), bands[l].begin(), bands[l].end());
    st.band_triangles += bands[l].size();
    st.widest = std::max(st.widest, widest[l]);
  }
  if (stats) *stats = st;
  return out;
}

}  // namespace ht
