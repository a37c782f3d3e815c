// Marching tetrahedra in one brick and its vertices' placement; see meshers/brick_extract.hpp.
// References: Kuhn's triangulation of the cube (Kuhn 1960, as used by Freudenthal); marching
// tetrahedra (Doi & Koide 1991).
#include "meshers/brick_extract.hpp"

#include "runtime/tape_eval.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace ht::brick {
namespace {

// The six tetrahedra of Kuhn's triangulation: monotone paths from corner 000 to 111, one per
// order of the axes. Corners are bit masks (x = 1, y = 2, z = 4).
constexpr std::array<std::array<int, 4>, 6> kTets = {{{0, 1, 3, 7},
                                                      {0, 1, 5, 7},
                                                      {0, 2, 3, 7},
                                                      {0, 2, 6, 7},
                                                      {0, 4, 5, 7},
                                                      {0, 4, 6, 7}}};

constexpr double kMargin = 1e-3;  // keeps vertices off grid points: no degenerate triangles

int local_index(glm::ivec3 l) { return l.x + kPoints * (l.y + kPoints * l.z); }
glm::ivec3 local_point(int li) { return {li % kPoints, (li / kPoints) % kPoints, li / (kPoints * kPoints)}; }

// Where the field crosses T on the edge from grid point a (inside, value fa > T) to b (fb < T),
// as a fraction of the edge, and the field's slope there (per edge length; NaN when unknown):
// the linear guess, improved by a polynomial through the values on the edge's line that the
// brick holds: a cubic with one grid point beyond each end, a quadratic with one beyond either.
// Along a smooth field their errors are O(h^4) and O(h^3) against the line's O(h^2), and the
// slope makes the next step a Newton step.
struct Guess {
  double t, slope;
};
Guess first_guess(const float* own, int a, int b, double T) {
  const double fa = own[a], fb = own[b];
  const Guess linear{(fa - T) / (fa - fb), std::nan("")};
  const glm::ivec3 pa = local_point(a), pb = local_point(b), d = pb - pa, before = pa - d, after = pb + d;
  auto held = [](glm::ivec3 q) {
    return glm::all(glm::greaterThanEqual(q, glm::ivec3(0))) && glm::all(glm::lessThan(q, glm::ivec3(kPoints)));
  };
  const bool has_m = held(before), has_p = held(after);
  const double fm = has_m ? own[local_index(before)] : 0.0, fp = has_p ? own[local_index(after)] : 0.0;
  if (!std::isfinite(fm) || !std::isfinite(fp)) return linear;
  // The polynomial minus T in power form, through (-1, fm), (0, fa), (1, fb), (2, fp) as held.
  double c0 = fa - T, c1, c2, c3 = 0.0;
  if (has_m && has_p) {
    c1 = -fm / 3.0 - fa / 2.0 + fb - fp / 6.0, c2 = fm / 2.0 - fa + fb / 2.0, c3 = -fm / 6.0 + fa / 2.0 - fb / 2.0 + fp / 6.0;
  } else if (has_m) {
    c1 = (fb - fm) / 2.0, c2 = (fb + fm) / 2.0 - fa;
  } else if (has_p) {
    c2 = (fa - 2.0 * fb + fp) / 2.0, c1 = fb - fa - c2;
  } else {
    return linear;
  }
  // Newton on the polynomial from the linear guess; kept only if it stays on the edge.
  double t = linear.t, df = 0.0;
  for (int i = 0; i < 4; ++i) {
    const double f = c0 + t * (c1 + t * (c2 + t * c3));
    df = c1 + t * (2.0 * c2 + t * 3.0 * c3);
    if (!(df < 0)) return linear;  // the field falls from a to b; a polynomial that does not is no guide
    t -= f / df;
    if (!(t > 0.0 && t < 1.0)) return linear;
  }
  return {t, c1 + t * (2.0 * c2 + t * 3.0 * c3)};
}

}  // namespace

void march(const Grid& grid, glm::ivec3 b, const std::uint8_t* label, Scratch& sc, const std::uint8_t* cells) {
  const glm::i64vec3 base = glm::i64vec3(b) * std::int64_t(kCells);
  sc.keys.clear();
  sc.ends.clear();
  sc.cell_begin.clear();
  auto edge = [&](glm::ivec3 p, glm::ivec3 q) {
    const glm::ivec3 d = q - p;  // monotone: every component 0 or 1
    const std::uint64_t key = grid.point_index(base + glm::i64vec3(p)) * 8 + std::uint64_t(d.x + 2 * d.y + 4 * d.z);
    sc.keys.push_back(key);
    sc.ends.push_back({local_index(p), local_index(q)});
    return key;
  };
  for (int cz = 0; cz < kCells; ++cz)
    for (int cy = 0; cy < kCells; ++cy)
      for (int cx = 0; cx < kCells; ++cx) {
        sc.cell_begin.push_back(static_cast<std::uint32_t>(sc.keys.size() / 3));
        int mask = 0;
        glm::ivec3 corner[8];
        for (int c = 0; c < 8; ++c) {
          corner[c] = {cx + (c & 1), cy + ((c >> 1) & 1), cz + ((c >> 2) & 1)};
          mask |= label[local_index(corner[c])] << c;
        }
        if (mask == 0 || mask == 255 || (cells && !cells[cx + kCells * (cy + kCells * cz)])) continue;
        for (const auto& tet : kTets) {
          int in[4], out_[4], ni = 0, no = 0;
          for (int v : tet) (label[local_index(corner[v])] ? in[ni++] : out_[no++]) = v;
          if (ni == 0 || no == 0) continue;
          // Orientation: normals point from the inside corners toward the outside ones.
          glm::dvec3 cin(0.0), cout(0.0);
          for (int i = 0; i < ni; ++i) cin += glm::dvec3(corner[in[i]]);
          for (int i = 0; i < no; ++i) cout += glm::dvec3(corner[out_[i]]);
          const glm::dvec3 outward = cout / double(no) - cin / double(ni);
          auto emit = [&](std::array<std::pair<int, int>, 3> e) {
            std::array<glm::dvec3, 3> mid;
            for (int i = 0; i < 3; ++i) mid[i] = 0.5 * glm::dvec3(corner[e[i].first] + corner[e[i].second]);
            if (glm::dot(glm::cross(mid[1] - mid[0], mid[2] - mid[0]), outward) < 0) std::swap(e[1], e[2]);
            for (int i = 0; i < 3; ++i) {
              glm::ivec3 p = corner[e[i].first], q = corner[e[i].second];
              if (p.x > q.x || p.y > q.y || p.z > q.z) std::swap(p, q);
              edge(p, q);
            }
          };
          if (ni == 1) {
            emit({{{in[0], out_[0]}, {in[0], out_[1]}, {in[0], out_[2]}}});
          } else if (no == 1) {
            emit({{{out_[0], in[0]}, {out_[0], in[1]}, {out_[0], in[2]}}});
          } else {  // a quad, cut along one diagonal
            emit({{{in[0], out_[0]}, {in[0], out_[1]}, {in[1], out_[1]}}});
            emit({{{in[0], out_[0]}, {in[1], out_[1]}, {in[1], out_[0]}}});
          }
        }
      }
  sc.cell_begin.push_back(static_cast<std::uint32_t>(sc.keys.size() / 3));
}

std::size_t place_vertices(const Grid& grid, glm::ivec3 b, std::uint32_t brick_index, const float* own,
                    const std::uint8_t* label, const TapeEvaluator& eval, double T, const Refine& refine, Scratch& sc,
                    BrickOutput& out) {
  const glm::i64vec3 base = glm::i64vec3(b) * std::int64_t(kCells);
  sc.order.resize(sc.keys.size());
  std::iota(sc.order.begin(), sc.order.end(), std::size_t(0));
  std::sort(sc.order.begin(), sc.order.end(), [&](std::size_t x, std::size_t y) { return sc.keys[x] < sc.keys[y]; });
  sc.unique.clear();
  sc.vertex_of.resize(sc.keys.size());
  for (std::size_t i : sc.order) {
    if (sc.unique.empty() || sc.keys[sc.unique.back()] != sc.keys[i]) sc.unique.push_back(i);
    sc.vertex_of[i] = static_cast<std::uint16_t>(sc.unique.size() - 1);
  }
  const std::size_t nv = sc.unique.size();
  for (auto* v : {&sc.pa, &sc.pb}) v->resize(nv);
  for (auto* v : {&sc.fa, &sc.fb, &sc.t, &sc.span, &sc.slope}) v->resize(nv);
  auto& pa = sc.pa;
  auto& pb = sc.pb;
  auto& fa = sc.fa;
  auto& fb = sc.fb;
  auto& t = sc.t;
  auto& span = sc.span;
  for (std::size_t v = 0; v < nv; ++v) {
    const auto [ia, ib] = sc.ends[sc.unique[v]];
    auto pos = [&](int li) {
      return grid.position(base + glm::i64vec3(li % kPoints, (li / kPoints) % kPoints, li / (kPoints * kPoints)));
    };
    // Keep the inside end as `a`.
    const bool a_in = label[ia] != 0;
    pa[v] = pos(a_in ? ia : ib);
    pb[v] = pos(a_in ? ib : ia);
    fa[v] = std::max(double(own[a_in ? ia : ib]), T);
    fb[v] = std::min(double(own[a_in ? ib : ia]), T);
    span[v] = fa[v] - fb[v];
    // An inside end exactly at T (a face through the grid point) says nothing of where the
    // solid ends along the edge: bisect there.
    const Guess g = fa[v] > T && fb[v] < T ? first_guess(own, a_in ? ia : ib, a_in ? ib : ia, T)
                    : Guess{fa[v] > T && fa[v] > fb[v] ? (fa[v] - T) / (fa[v] - fb[v]) : 0.5, std::nan("")};
    t[v] = g.t;
    sc.slope[v] = g.slope;
  }
  // Illinois false position (Dowell & Jarratt 1971), the brick's unconverged vertices per batch.
  // Most converge in a few steps; those next to a crease of a min/max field need more.
  auto& ta = sc.ta;
  auto& tb = sc.tb;
  ta.assign(nv, 0.0);
  tb.assign(nv, 1.0);
  auto& side = sc.side;  // which end the last step replaced: 1 a, -1 b, 0 none yet
  side.assign(nv, 0);
  sc.probed.assign(nv, 0);
  for (auto* v : {&sc.xs, &sc.ys, &sc.zs, &sc.fv}) v->resize(nv);
  // An edge to a point that was not sampled (NaN: outside the octants a filter wanted) keeps
  // its midpoint: its sign change is not the surface's, and drop_unsampled takes it away.
  auto& live = sc.live;
  live.clear();
  for (std::uint32_t v = 0; v < nv; ++v)
    if (!std::isnan(fb[v])) live.push_back(v);
  std::size_t evaluations = 0;
  for (int step = 0; step < refine.steps && !live.empty(); ++step) {
    const std::size_t nl = live.size();
    evaluations += nl;
    for (std::size_t i = 0; i < nl; ++i) {
      const std::uint32_t v = live[i];
      t[v] = std::clamp(t[v], kMargin, 1.0 - kMargin);
      const glm::dvec3 p = pa[v] + t[v] * (pb[v] - pa[v]);
      sc.xs[i] = float(p.x);
      sc.ys[i] = float(p.y);
      sc.zs[i] = float(p.z);
    }
    for (std::size_t at = 0; at < nl; at += kBlock)
      eval.field_block(sc.xs.data() + at, sc.ys.data() + at, sc.zs.data() + at, int(std::min<std::size_t>(kBlock, nl - at)),
                       sc.fv.data() + at);
    std::size_t kept = 0;
    for (std::size_t i = 0; i < nl; ++i) {
      const std::uint32_t v = live[i];
      const double f = sc.fv[i];
      // Illinois: an end kept twice in a row has its weight halved, so the bracket closes from
      // both sides instead of creeping toward the root from one.
      if (f >= T) {
        ta[v] = t[v];
        fa[v] = f;
        if (side[v] > 0) fb[v] = T + 0.5 * (fb[v] - T);
        side[v] = 1;
      } else {
        tb[v] = t[v];
        fb[v] = f;
        if (side[v] < 0) fa[v] = T + 0.5 * (fa[v] - T);
        side[v] = -1;
      }
      // Done when f - T, or the bracket, is a small fraction of the change across the edge.
      // A value exactly T may be a plateau of the surface along the edge (a crease line on it):
      // then the crossing is where the plateau ends, found by bisection (after the probe below).
      const bool converged = (f != T && std::abs(f - T) <= refine.tolerance * span[v]) || tb[v] - ta[v] <= refine.tolerance;
      if (converged) continue;  // t[v] is the last point evaluated
      // After a polynomial's guess, a Newton step with its slope, while it stays inside the bracket.
      if (step == 0 && std::isfinite(sc.slope[v])) {
        const double next = t[v] - (f - T) / sc.slope[v];
        if (next > ta[v] && next < tb[v]) {
          t[v] = next;
          live[kept++] = v;
          continue;
        }
      }
      // A value exactly T is the surface (within rounding: the polynomials' guesses land there often)
      // or a plateau of it: one probe a tolerance on tells which, where bisection took ten steps.
      if (f == T && !sc.probed[v] && ta[v] + refine.tolerance < tb[v]) {
        sc.probed[v] = 1;
        t[v] = ta[v] + refine.tolerance;
        live[kept++] = v;
        continue;
      }
      t[v] = fa[v] > T && fa[v] > fb[v] ? ta[v] + (fa[v] - T) / (fa[v] - fb[v]) * (tb[v] - ta[v]) : 0.5 * (ta[v] + tb[v]);
      live[kept++] = v;
    }
    live.resize(kept);
  }
  // Sized exactly (a fresh vector each): every brick's output is held until the join.
  out.vertices = std::vector<EdgeVertex>(nv);
  for (std::size_t v = 0; v < nv; ++v)
    out.vertices[v] = {sc.keys[sc.unique[v]], pa[v] + std::clamp(t[v], kMargin, 1.0 - kMargin) * (pb[v] - pa[v]),
                       glm::vec3(0.0f), brick_index};
  // march() met each triangle's three edges in turn: key 3 i + k is corner k of triangle i.
  out.triangles = std::vector<LocalTriangle>(sc.keys.size() / 3);
  for (std::size_t i = 0; i < out.triangles.size(); ++i)
    for (std::size_t k = 0; k < 3; ++k) out.triangles[i][k] = sc.vertex_of[3 * i + k];
  return evaluations;
}

std::uint8_t octants_at(int i, int j, int k) {
  constexpr int half = kCells / 2;
  const int c[3] = {i, j, k};
  std::uint8_t mask = 0;
  for (int o = 0; o < 8; ++o) {
    bool in = true;
    for (int a = 0; a < 3; ++a) in = in && (((o >> a) & 1) ? c[a] >= half : c[a] <= half);
    if (in) mask = std::uint8_t(mask | (1u << o));
  }
  return mask;
}

std::size_t drop_unsampled(const Grid& grid, glm::ivec3 b, const float* own, std::uint8_t octants, const Scratch& sc,
                           BrickOutput& out) {
  const glm::i64vec3 base = glm::i64vec3(b) * std::int64_t(kCells);
  std::vector<std::uint8_t> unsampled(out.vertices.size());
  for (std::size_t v = 0; v < out.vertices.size(); ++v) {
    const std::uint64_t key = out.vertices[v].key, dir = key % 8;
    const glm::ivec3 a(grid.point_at(key / 8) - base), d(int(dir & 1), int((dir >> 1) & 1), int((dir >> 2) & 1));
    unsampled[v] = std::isnan(own[local_index(a)]) || std::isnan(own[local_index(a + d)]);
  }
  // Triangles by cell (march's order): a cell of an octant left out goes whole, even where its
  // corners were sampled for the octants beside it.
  constexpr int half = kCells / 2;
  std::vector<std::uint8_t> drop(out.triangles.size(), 0);
  std::size_t dropped = 0;
  for (int c = 0; c < kCells * kCells * kCells; ++c) {
    const int x = c % kCells, y = (c / kCells) % kCells, z = c / (kCells * kCells);
    const bool wanted = (octants >> ((x >= half) + 2 * (y >= half) + 4 * (z >= half))) & 1;
    for (std::uint32_t i = sc.cell_begin[std::size_t(c)]; i < sc.cell_begin[std::size_t(c) + 1]; ++i) {
      const LocalTriangle& t = out.triangles[i];
      drop[i] = !wanted || unsampled[t[0]] || unsampled[t[1]] || unsampled[t[2]];
      dropped += drop[i];
    }
  }
  if (dropped == 0) return 0;
  // The vertices the kept triangles use, renumbered in order (so still sorted by key).
  std::vector<std::uint16_t> renumber(out.vertices.size(), 0);
  for (std::size_t i = 0; i < out.triangles.size(); ++i)
    if (!drop[i])
      for (const std::uint16_t v : out.triangles[i]) renumber[v] = 1;
  std::vector<EdgeVertex> vertices;
  vertices.reserve(std::size_t(std::count(renumber.begin(), renumber.end(), std::uint16_t(1))));
  for (std::size_t v = 0; v < out.vertices.size(); ++v)
    if (renumber[v]) {
      renumber[v] = static_cast<std::uint16_t>(vertices.size());
      vertices.push_back(out.vertices[v]);
    }
  std::vector<LocalTriangle> triangles;
  triangles.reserve(out.triangles.size() - dropped);
  for (std::size_t i = 0; i < out.triangles.size(); ++i)
    if (!drop[i]) {
      const LocalTriangle& t = out.triangles[i];
      triangles.push_back({renumber[t[0]], renumber[t[1]], renumber[t[2]]});
    }
  out.vertices = std::move(vertices);
  out.triangles = std::move(triangles);
  return dropped;
}

void crease_normals(const float* own, const TapeEvaluator& eval, const FeatureOptions& options, Scratch& sc,
                    BrickOutput& out) {
  std::uint8_t suspect[kCells * kCells * kCells];
  mark_suspect_cells({own, std::size_t(kBrickPoints)}, kCells, options, suspect);
  const std::size_t nv = out.vertices.size();
  sc.wanted.assign(nv, 0);
  for (int c = 0; c < kCells * kCells * kCells; ++c) {
    if (!suspect[c]) continue;
    for (std::uint32_t i = sc.cell_begin[std::size_t(c)]; i < sc.cell_begin[std::size_t(c) + 1]; ++i)
      for (const std::uint16_t v : out.triangles[i]) sc.wanted[v] = 1;
  }
  sc.at.clear();
  for (std::size_t v = 0; v < nv; ++v)
    if (sc.wanted[v]) sc.at.push_back(out.vertices[v].position);
  sc.grad.resize(sc.at.size());
  if (!sc.at.empty()) eval.gradient(sc.at, {}, sc.grad);
  for (std::size_t v = 0, i = 0; v < nv; ++v) {
    if (!sc.wanted[v]) continue;
    const double len = glm::length(sc.grad[i]);
    // The field grows inward: the outward normal is -grad f.
    if (len > 0 && std::isfinite(len)) out.vertices[v].normal = glm::vec3(-sc.grad[i] / len);
    ++i;
  }
}

}  // namespace ht::brick
