#include "meshers/quality_improver.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>

namespace ht::quality_detail {

std::vector<std::uint8_t> Improver::thin_faces() const {
  std::vector<std::uint8_t> thin(m_.n_faces(), 0);
  tbb::parallel_for(std::size_t(0), thin.size(), [&](std::size_t fi) {
    const FH f{int(fi)};
    if (m_.status(f).deleted()) return;
    const auto c = corners(f);
    thin[fi] = thinness(p(c[0]), p(c[1]), p(c[2])) > kAimCos;
  });
  return thin;
}

void Improver::stay_on_surface(const std::vector<std::uint32_t>& movers, const std::vector<glm::dvec3>& dirs,
                     const std::vector<glm::dvec3>& tangential, const std::vector<glm::dvec3>& old,
                     std::vector<glm::dvec3>& now) {
  if (!creases_near_) return;  // a field without creases has no kink to stop at
  std::vector<std::uint32_t> check;
  std::vector<glm::dvec3> at, dir;
  for (std::size_t i = 0; i < movers.size(); ++i)
    if (now[movers[i]] != old[movers[i]] && glm::length(now[movers[i]] - tangential[i]) >= kOffCells * h_) {
      check.push_back(std::uint32_t(i));
      at.push_back(now[movers[i]]);
      dir.push_back(dirs[i]);
    }
  const std::vector<double>& off = off_.points(at, dir);
  for (std::size_t k = 0; k < check.size(); ++k)
    if (!(off[k] <= kOffCells * h_)) now[movers[check[k]]] = old[movers[check[k]]];
}

void Improver::relax(QualityStats& st) {
  // Only the corners of thin faces move: the rest is as good as relaxation makes it. The work
  // is on them, their rings (whose normals judge the moves) and the faces around them.
  // Per vertex: 1 when locked or next to a vertex that holds its neighbours (near_rim, found from the few
  // locked vertices' rings rather than every candidate's), 2 when it moves. Crease points'
  // neighbours move, held to the surface beside the crease.
  std::vector<std::uint8_t> wanted(m_.n_vertices(), 0);
  for (const VH v : m_.vertices())
    if (locked(v)) {
      wanted[std::size_t(v.idx())] = 1;
      if (!holds_neighbours(v)) continue;
      for (const VH w : m_.vv_range(v)) wanted[std::size_t(w.idx())] = 1;
    }
  const std::vector<std::uint8_t> thin = thin_faces();
  for (std::size_t f = 0; f < thin.size(); ++f)
    if (thin[f])
      for (const VH v : corners(FH{int(f)}))
        if (!wanted[std::size_t(v.idx())]) wanted[std::size_t(v.idx())] = 2;
  std::vector<std::uint32_t> who;  // ascending
  for (std::uint32_t v = 0; v < wanted.size(); ++v)
    if (wanted[v] == 2) who.push_back(v);
  std::vector<std::uint32_t> faces, ring;
  std::vector<std::uint8_t> face_seen(m_.n_faces(), 0), ring_seen(m_.n_vertices(), 0);
  for (const std::uint32_t v : who)
    for (const FH f : m_.vf_range(VH(int(v))))
      if (!face_seen[std::size_t(f.idx())]) {
        face_seen[std::size_t(f.idx())] = 1;
        faces.push_back(std::uint32_t(f.idx()));
        for (const VH c : corners(f))
          if (!ring_seen[std::size_t(c.idx())]) ring_seen[std::size_t(c.idx())] = 1, ring.push_back(std::uint32_t(c.idx()));
      }
  std::sort(faces.begin(), faces.end());
  // Ring normals (area-weighted) of every vertex the checks read; centroids of the movers.
  std::vector<glm::dvec3> normal(m_.n_vertices(), glm::dvec3(0.0)), moved(who.size()), dirs(who.size());
  std::vector<std::uint8_t> moves(who.size(), 0);
  auto ring_of = [&](VH v, glm::dvec3& centroid) {
    glm::dvec3 c(0.0), n(0.0);
    double area = 0;
    for (const FH f : m_.vf_range(v)) {
      const auto k = corners(f);
      const glm::dvec3 a = p(k[0]), b = p(k[1]), d = p(k[2]);
      const glm::dvec3 cr = glm::cross(b - a, d - a);
      const double w = glm::length(cr);
      c += w * (a + b + d) / 3.0;
      n += cr;
      area += w;
    }
    const double nl = glm::length(n);
    if (!(area > 0) || !(nl > 0)) return false;
    normal[std::size_t(v.idx())] = n / nl;
    centroid = c / area;
    return true;
  };
  // The movers' own rings are done below, with their centroids.
  tbb::parallel_for(std::size_t(0), ring.size(), [&](std::size_t i) {
    glm::dvec3 unused;
    if (wanted[ring[i]] != 2) ring_of(VH(int(ring[i])), unused);
  });
  tbb::parallel_for(std::size_t(0), who.size(), [&](std::size_t i) {
    const VH v(static_cast<int>(who[i]));  // not VH v(int(x)): clang reads that as a function
    glm::dvec3 c;
    if (!ring_of(v, c)) return;
    const glm::dvec3 n = normal[who[i]], at = p(v);
    glm::dvec3 d = c - at;
    d -= glm::dot(d, n) * n;
    // A move this short changes no angle that matters and is not worth a field evaluation.
    if (glm::dot(d, d) < kShortMove * kShortMove * h_ * h_) return;
    moved[i] = at + d;
    dirs[i] = n;
    moves[i] = 1;
  });
  std::vector<std::uint32_t> movers;
  std::vector<glm::dvec3> targets, normals_of;
  for (std::size_t i = 0; i < who.size(); ++i)
    if (moves[i]) movers.push_back(who[i]), targets.push_back(moved[i]), normals_of.push_back(dirs[i]);
  std::vector<double> slopes(movers.size());
  for (std::size_t i = 0; i < movers.size(); ++i) slopes[i] = m_.property(slope_, VH{int(movers[i])});
  const std::vector<glm::dvec3> tangential = creases_near_ ? targets : std::vector<glm::dvec3>();
  off_.project(targets, normals_of, slopes, o_.newton_steps);
  for (std::size_t i = 0; i < movers.size(); ++i) m_.property(slope_, VH{int(movers[i])}) = slopes[i];
  // Positions before and after, indexed like the mesh's vertices but filled only where read.
  std::vector<glm::dvec3> old(m_.n_vertices()), now(m_.n_vertices());
  for (const std::uint32_t v : ring) old[v] = now[v] = p(VH(int(v)));
  for (std::size_t i = 0; i < movers.size(); ++i)
    if (!std::isnan(targets[i].x)) now[movers[i]] = targets[i];
  stay_on_surface(movers, normals_of, tangential, old, now);
  // Beside a crease, faces a move takes further off the surface than kOffCells or than they
  // were are marked: their moves are undone below with the others'.
  std::vector<std::uint8_t> too_far(creases_near_ ? m_.n_faces() : 0, 0);
  if (creases_near_) {
    std::vector<std::uint32_t> near;  // faces with a corner beside a crease and one that moved
    std::vector<std::array<glm::dvec3, 3>>& both = faces_;
    both.clear();
    for (const std::uint32_t f : faces) {
      const auto k = corners(FH(int(f)));
      bool beside = false, moved_one = false;
      for (const VH v : k) {
        beside |= beside_crease(v);
        moved_one |= now[std::size_t(v.idx())] != old[std::size_t(v.idx())];
      }
      if (!beside || !moved_one) continue;
      near.push_back(f);
      both.push_back({old[std::size_t(k[0].idx())], old[std::size_t(k[1].idx())], old[std::size_t(k[2].idx())]});
    }
    for (const std::uint32_t f : near) {
      const auto k = corners(FH(int(f)));
      both.push_back({now[std::size_t(k[0].idx())], now[std::size_t(k[1].idx())], now[std::size_t(k[2].idx())]});
    }
    const std::vector<double>& off = off_.faces(both);
    for (std::size_t i = 0; i < near.size(); ++i)
      too_far[near[i]] = off[near.size() + i] > std::max(off[i], kOffCells * h_);
  }
  // Undo the moves of every face that turned or got much thinner, until none does. After the
  // first round only the faces around a vertex just put back can have turned bad: the others
  // are as they were checked.
  auto turns_bad = [&](std::uint32_t f) {
    if (!too_far.empty() && too_far[f]) return true;
    const auto k = corners(FH(int(f)));
    const std::size_t i0 = std::size_t(k[0].idx()), i1 = std::size_t(k[1].idx()), i2 = std::size_t(k[2].idx());
    if (now[i0] == old[i0] && now[i1] == old[i1] && now[i2] == old[i2]) return false;
    // Held to its corners' ring normals: a sliver's own normal means nothing.
    const glm::dvec3 ref = normal[i0] + normal[i1] + normal[i2], after = unit_normal(now[i0], now[i1], now[i2]);
    const double t0 = thinness(old[i0], old[i1], old[i2]), t1 = thinness(now[i0], now[i1], now[i2]);
    // Beside a crease a face stays on its sheet: a mover's faces keep to its ring's plane.
    for (const VH v : k)
      if (m_.property(near_crease_, v) && now[std::size_t(v.idx())] != old[std::size_t(v.idx())] &&
          glm::dot(normal[std::size_t(v.idx())], after) < kKeepPlaneCos)
        return true;
    return glm::dot(ref, after) < kTurnCos * glm::length(ref) || (t1 > t0 && t1 > kWorseCos) || t1 > kDegenerateCos;
  };
  std::vector<std::uint32_t> check = faces, undone;
  std::vector<std::uint8_t> bad, queued(m_.n_faces(), 0);
  for (int round = 0; round < 16 && !check.empty(); ++round) {
    bad.assign(check.size(), 0);
    tbb::parallel_for(std::size_t(0), check.size(), [&](std::size_t fi) { bad[fi] = turns_bad(check[fi]); });
    undone.clear();
    for (std::size_t fi = 0; fi < check.size(); ++fi)
      if (bad[fi])
        for (const VH v : corners(FH(int(check[fi])))) {
          const std::size_t i = std::size_t(v.idx());
          if (now[i] != old[i]) now[i] = old[i], undone.push_back(std::uint32_t(i));
        }
    st.reverted += undone.size();
    check.clear();
    for (const std::uint32_t v : undone)
      for (const FH f : m_.vf_range(VH(int(v))))
        if (!queued[std::size_t(f.idx())]) queued[std::size_t(f.idx())] = 1, check.push_back(std::uint32_t(f.idx()));
    for (const std::uint32_t f : check) queued[f] = 0;
  }
  for (const std::uint32_t v : movers)
    if (now[v] != old[v]) m_.set_point(VH(int(v)), om(now[v])), ++st.moved;
}

}  // namespace ht::quality_detail
