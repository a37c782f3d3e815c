// Mesh leaves, queries: the Embree acceleration structure, the distance and inside queries
// behind the pseudo-distance field, and the field itself. The contract is in nodes/mesh_leaf.hpp;
// the field in SCENE_FORMAT.md. Reading is in nodes/mesh_read.cpp, validation in nodes/mesh_build.cpp.
#include "nodes/mesh_internal.hpp"
#include "nodes/trimesh.hpp"
#include "nodes/winding.hpp"

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cfloat>
#include <numeric>

namespace ht {

using namespace mesh_detail;

namespace {

glm::dvec3 unit_or_zero(const glm::dvec3& v) {
  const double l = glm::length(v);
  return l > 0 && std::isfinite(l) ? v / l : glm::dvec3(0.0);
}

// The nearest float at or above x.
float float_up(double x) {
  const float f = static_cast<float>(x);
  return static_cast<double>(f) < x ? std::nextafter(f, std::numeric_limits<float>::infinity()) : f;
}

}  // namespace

void MeshLeaf::Accel::morton_sort_shells(const std::vector<glm::dvec3>& pos, const std::vector<glm::uvec3>& tris) {
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

MeshLeaf::Accel::Accel(const std::string& name, const std::vector<glm::dvec3>& pos,
                       const std::vector<glm::uvec3>& tris, const Shells& shells) {
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
  // high quality spends build time once for the many queries a mesher makes. The compact layout
  // holds bunny00's hierarchy in about 2.5 MiB less (a tenth of a trimmed Boolean's peak on one
  // thread) for a few percent more time in its queries.
  rtcSetSceneFlags(scene.get(), RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_COMPACT);
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

void MeshLeaf::Accel::compute_normals(const std::vector<glm::dvec3>& pos, const std::vector<glm::uvec3>& tris,
                                      std::vector<std::uint32_t> neighbours) {
  nbr = std::move(neighbours);
  // Built from the final, oriented triangles, so that a mesh and its flipped twin answer alike
  // to the last bit.
  // Each loop runs in parallel over independent items; the angle-weighted sums are added up in
  // triangle order afterwards, so the normals are the same bits at any thread count.
  records.resize(tris.size());
  slot.resize(tris.size());
  tbb::parallel_for(std::size_t(0), order.size(), [&](std::size_t s) {
    const glm::uvec3 t = tris[order[s]];
    const glm::dvec3 a = pos[t[0]], b = pos[t[1]], c = pos[t[2]];
    TriRecord& r = records[s];
    r.centre = glm::vec3((a + b + c) / 3.0);
    r.normal = unit_or_zero(glm::cross(b - a, c - a));
    const glm::dvec3 o(r.centre);
    r.reach = float_up(std::max({glm::length(a - o), glm::length(b - o), glm::length(c - o)}));
    r.thickness = float_up(std::max({std::abs(glm::dot(a - o, r.normal)), std::abs(glm::dot(b - o, r.normal)),
                                     std::abs(glm::dot(c - o, r.normal))}));
    r.tri = order[s];
    slot[order[s]] = static_cast<std::uint32_t>(s);
  });
  std::vector<std::uint32_t>().swap(order);
  // The corners' angle-weighted normals are made in parallel a block of triangles at a time and
  // added up in triangle order (a block, not the whole mesh's, held at once).
  constexpr std::size_t kBlock = 8192;
  std::vector<glm::dvec3> corner_normal(3 * std::min(kBlock, tris.size()));  // angle * face normal
  vertex_normal.assign(pos.size(), glm::dvec3(0.0));
  for (std::size_t b = 0; b < tris.size(); b += kBlock) {
    const std::size_t e = std::min(tris.size(), b + kBlock);
    tbb::parallel_for(b, e, [&](std::size_t t) {
      const glm::dvec3 p[3] = {pos[tris[t][0]], pos[tris[t][1]], pos[tris[t][2]]};
      const glm::dvec3& n = face_normal(static_cast<std::uint32_t>(t));
      for (int k = 0; k < 3; ++k) {
        const glm::dvec3 e1 = p[(k + 1) % 3] - p[k], e2 = p[(k + 2) % 3] - p[k];
        corner_normal[3 * (t - b) + std::size_t(k)] = std::atan2(glm::length(glm::cross(e1, e2)), glm::dot(e1, e2)) * n;
      }
    });
    for (std::size_t t = b; t < e; ++t)
      for (int k = 0; k < 3; ++k) vertex_normal[tris[t][k]] += corner_normal[3 * (t - b) + std::size_t(k)];
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
  tbb::parallel_for(std::uint32_t(0), std::uint32_t(pos.size()), [&](std::uint32_t v) {
    if (first[v] == kNone) return;
    std::uint32_t t = first[v], steps = 0;
    do {  // turn about v across the edge leaving it
      const std::uint32_t k = tris[t][0] == v ? 0u : tris[t][1] == v ? 1u : 2u;
      t = nbr[3 * t + k];
      ++steps;
    } while (t != first[v] && t != kNone && steps <= incident[v]);
    complex_vertex[v] = steps != incident[v] ? 1 : 0;
  });
}

// True when the closest point is (within rounding) a vertex where several fans meet: the
// closest feature may then be reported as an edge or face of either fan, and only parity
// tells inside from outside.
bool MeshLeaf::Accel::needs_parity(std::uint32_t t, int feature, const glm::dvec3& closest,
                                   const std::vector<glm::dvec3>& pos, const std::vector<glm::uvec3>& tris) const {
  if (feature >= kVertex) return complex_vertex[tris[t][feature - kVertex]] != 0;
  for (std::uint32_t k = 0; k < 3; ++k) {
    const std::uint32_t v = tris[t][k];
    if (complex_vertex[v] && glm::length(pos[v] - closest) <= 1e-9 * std::max(1.0, scale)) return true;
  }
  return false;
}

glm::dvec3 MeshLeaf::Accel::pseudo_normal(std::uint32_t t, int feature, const std::vector<glm::uvec3>& tris) const {
  if (feature == kFace) return face_normal(t);
  if (feature < kVertex) {
    const std::uint32_t g = nbr[3 * t + static_cast<std::uint32_t>(feature - kEdge)];
    return g == kNone ? face_normal(t) : face_normal(t) + face_normal(g);
  }
  return vertex_normal[tris[t][feature - kVertex]];
}

glm::dvec3 MeshLeaf::Accel::unit_normal(const glm::dvec3& pseudo, std::uint32_t t, bool parity,
                                        const std::vector<glm::uvec3>& tris) const {
  // Where fans meet (parity) the summed normal means nothing: the nearest face's stands in.
  glm::dvec3 n = parity ? glm::dvec3(0.0) : unit_or_zero(pseudo);
  if (n == glm::dvec3(0.0)) n = face_normal(t);
  for (std::uint32_t k = 0; k < 3 && n == glm::dvec3(0.0); ++k) n = unit_or_zero(vertex_normal[tris[t][k]]);
  // Only a triangle degenerate among degenerate ones gets here: any unit vector is as good.
  return n == glm::dvec3(0.0) ? glm::dvec3(0.0, 0.0, 1.0) : n;
}

std::size_t MeshLeaf::Accel::bytes() const {
  return vertices.capacity() * sizeof(float) + (order.capacity() + offset.capacity() + slot.capacity() + nbr.capacity()) * 4 +
         vertex_normal.capacity() * sizeof(glm::dvec3) + records.capacity() * sizeof(TriRecord) +
         // Embree's own memory is not exposed: its index buffers (12 bytes per triangle) plus
         // a BVH estimate of 64 bytes per triangle (high-quality builds with spatial splits
         // measure around 40-80).
         records.size() * (12 + 64);
}

namespace {

// State of one point query, on the caller's stack: queries share nothing mutable.
struct PointQueryState {
  const TriRecord* records;     // Accel::records and Accel::offset: (shell, primID) -> record
  const std::uint32_t* offset;
  const glm::dvec3* pos;        // the mesh's positions and triangles
  const glm::uvec3* tris;
  glm::dvec3 p;
  float slack;
  double best2 = kInf;
  double best = kInf;  // sqrt(best2)
  std::uint32_t tri = kNone;
  int feature = 0;
  glm::dvec3 closest{0.0};
};

// The feature of triangle `tri` that point c (on it) lies on within `band`: a corner nearer than
// band, else an edge nearer than band, else `feature` as the closest-point search found it.
int snap_feature(const glm::dvec3& c, const std::vector<glm::dvec3>& pos, const glm::uvec3& tri, int feature,
                 double band) {
  for (int k = 0; k < 3; ++k)
    if (glm::length(pos[tri[k]] - c) <= band) return kVertex + k;
  for (int k = 0; k < 3; ++k) {
    const glm::dvec3 a = pos[tri[k]], e = pos[tri[(k + 1) % 3]] - a;
    const double len2 = glm::dot(e, e);
    const double s = len2 > 0 ? std::clamp(glm::dot(c - a, e) / len2, 0.0, 1.0) : 0.0;
    if (glm::length(a + s * e - c) <= band) return kEdge + k;
  }
  return feature;
}

}  // namespace

MeshLeaf::~MeshLeaf() = default;

namespace {
bool point_query_visit(RTCPointQueryFunctionArguments* args) {
  auto* st = static_cast<PointQueryState*>(args->userPtr);
  const TriRecord& rec = st->records[st->offset[args->geomID] + args->primID];
  // Most triangles Embree hands over are far: their bounding sphere rejects them before the
  // exact (and costlier) closest-point computation.
  const glm::dvec3 to_centre = st->p - glm::dvec3(rec.centre);
  const double reach = static_cast<double>(rec.reach) + st->best;
  if (glm::dot(to_centre, to_centre) >= reach * reach) return false;
  // The triangle lies in a disc of radius reach around its centre, thickness thick, so p is at
  // least sqrt(above^2 + gap^2) from it. Seen from above, a surface's triangles beside the
  // nearest one pass the sphere (their centres are barely farther than the nearest point) but
  // not the disc. The margin keeps rounding from rejecting a triangle as near as the best.
  const double across = glm::dot(to_centre, rec.normal);
  const double above = std::max(0.0, std::abs(across) - static_cast<double>(rec.thickness));
  const double gap = std::max(0.0, glm::length(to_centre - across * rec.normal) - static_cast<double>(rec.reach));
  if (above * above + gap * gap > st->best2 * (1.0 + 1e-9)) return false;
  const std::uint32_t t = rec.tri;
  const glm::uvec3 v = st->tris[t];
  const Nearest n = closest_on_triangle(st->p, st->pos[v[0]], st->pos[v[1]], st->pos[v[2]]);
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

MeshLeaf::Closest MeshLeaf::query(const glm::dvec3& p, double radius, double bound, int side_if_none) const {
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return {kInf, false, p};
  if (largest_coordinate(p) > kMaxCoordinate) return far_query(p, radius);
  const double mag = std::max({accel_->scale, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
  PointQueryState st{accel_->records.data(),
                     accel_->offset.data(),
                     surface_->positions.data(),
                     surface_->triangles.data(),
                     p,
                     static_cast<float>(8 * FLT_EPSILON * mag)};
  RTCPointQuery q;
  q.x = static_cast<float>(p.x);
  q.y = static_cast<float>(p.y);
  q.z = static_cast<float>(p.z);
  q.time = 0.0f;
  // Embree visits near nodes first, but enters every node the ball reaches before the nearest
  // triangle shrinks it: a neighbour's bound, when smaller, cuts those. A triangle as near as the
  // nearest lies within the bound, so the answer does not change.
  const double start = std::min(radius, bound * (1.0 + 1e-9));
  q.radius = start >= static_cast<double>(FLT_MAX) ? std::numeric_limits<float>::infinity()
                                                   : static_cast<float>(std::max(start, 0.0)) + st.slack;
  // Embree hands over every triangle of each leaf it reaches, near or not: only those within the
  // (slackened) radius may become the closest, or a far triangle's pseudo-normal would decide.
  st.best = static_cast<double>(q.radius);
  st.best2 = st.best * st.best;
  RTCPointQueryContext ctx;
  rtcInitPointQueryContext(&ctx);
  rtcPointQuery(accel_->scene.get(), &q, &ctx, point_query_visit, &st);
  if (st.tri == kNone) return {kInf, side_if_none >= 0 && !winding_ ? side_if_none == 1 : inside(p), p};
  const double dist = std::sqrt(st.best2);
  // Baerentzen & Aanaes: p is inside iff p - closest points against the closest feature's
  // angle-weighted pseudo-normal. On the surface itself (dist 0) either answer gives the same
  // field value, so "outside" is fine there.
  const auto& pos = surface_->positions;
  const auto& tris = surface_->triangles;
  const bool parity = accel_->needs_parity(st.tri, st.feature, st.closest, pos, tris);
  const glm::dvec3 normal = accel_->pseudo_normal(st.tri, st.feature, tris);
  const bool in = dist > 0 && (winding_ ? inside(p) : parity ? inside(p) : glm::dot(p - st.closest, normal) < 0);
  // On the surface (within the band) rounding decides which feature the nearest point is
  // reported on; the normal is that of the feature it lies on within the band.
  const int snapped = dist <= surface_band_ ? snap_feature(st.closest, pos, tris[st.tri], st.feature, surface_band_) : st.feature;
  if (snapped == st.feature) return {dist <= radius ? dist : kInf, in, st.closest, accel_->unit_normal(normal, st.tri, parity, tris)};
  return {dist <= radius ? dist : kInf, in, st.closest,
          accel_->unit_normal(accel_->pseudo_normal(st.tri, snapped, tris), st.tri,
                              accel_->needs_parity(st.tri, snapped, st.closest, pos, tris), tris)};
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

// The distance to the previous point's nearest point bounds this one's distance to the mesh. A
// closed surface does not cross the empty ball of radius r around a point that found no
// triangle, so a neighbour within half of it that finds none either is on the same side, without
// casting rays (as for a whole block in shared_far_block).
MeshLeaf::Closest MeshLeaf::Neighbours::next(const glm::dvec3& p) {
  const int side = far_side_ >= 0 && glm::length(p - far_at_) <= 0.5 * radius_ ? far_side_ : -1;
  const Closest c = leaf_.query(p, radius_, have_last_ ? glm::length(p - last_) : kInf, side);
  have_last_ = std::isfinite(c.distance);
  if (have_last_) last_ = c.point;
  far_side_ = !have_last_ && std::isfinite(radius_) ? int(c.inside) : -1;
  far_at_ = p;
  return c;
}

double MeshLeaf::winding_number(const glm::dvec3& p, double tolerance) const {
  return winding_ ? winding_->estimate(p, 0.0, tolerance).w : std::numeric_limits<double>::quiet_NaN();
}

bool MeshLeaf::inside(const glm::dvec3& p) const {
  if (!bounds_.contains(p)) return false;
  if (winding_) return winding_->inside(p);
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
  if (n >= 8 && !winding_ && shared_far_block(xs, ys, zs, n, radius, distance, inside)) return;
  // The points of a block are neighbours.
  Neighbours run(*this, static_cast<double>(radius));
  for (std::size_t i = 0; i < n; ++i) {
    const Closest c = run.next(glm::dvec3(xs[i], ys[i], zs[i]));
    distance[i] =
        std::isfinite(c.distance) ? static_cast<float>(c.distance) : std::numeric_limits<float>::infinity();
    inside[i] = c.inside ? 1 : 0;
  }
}

// The work a block shares (Embree 3's point-query packets run their lanes one by one, so there is
// none to share inside a query): the ball around the block's box. When no triangle comes within
// the radius of it, none comes within the radius of any of the block's points, and a closed
// surface does not cross the ball, so its points are all on the side of its centre: one query and
// one inside test answer the block. A winding leaf's inside varies off the surface: not for it.
bool MeshLeaf::shared_far_block(const float* xs, const float* ys, const float* zs, std::size_t n, float radius,
                                float* distance, std::uint8_t* inside) const {
  glm::dvec3 lo(xs[0], ys[0], zs[0]), hi = lo;
  for (std::size_t i = 1; i < n; ++i) {
    const glm::dvec3 p(xs[i], ys[i], zs[i]);
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  if (!std::isfinite(lo.x + lo.y + lo.z + hi.x + hi.y + hi.z)) return false;
  const glm::dvec3 centre = 0.5 * (lo + hi);
  // The ball's radius rounded up a little, so that the points' own queries (whose slack follows
  // their coordinates) could not reach a triangle this one misses.
  const double reach = (0.5 * glm::length(hi - lo) + static_cast<double>(radius)) * (1.0 + 1e-6) +
                       1e-6 * std::max(accel_->scale, glm::length(centre));
  const Closest c = query(centre, reach);
  if (std::isfinite(c.distance)) return false;
  const std::uint8_t side = c.inside ? 1 : 0;
  for (std::size_t i = 0; i < n; ++i) {
    distance[i] = std::numeric_limits<float>::infinity();
    inside[i] = side;
  }
  return true;
}

int MeshLeaf::box_side(const Aabb& box) const {
  if (!winding_) return -1;
  if (intersect(box, bounds_).empty()) return 0;
  return winding_->box_side(box);
}

std::size_t MeshLeaf::bytes() const {
  return sizeof(MeshLeaf) + name_.capacity() + surface_->positions.capacity() * sizeof(glm::dvec3) +
         surface_->triangles.capacity() * sizeof(glm::uvec3) + (accel_ ? accel_->bytes() : 0) +
         (winding_ ? winding_->bytes() : 0) +
         (manifold_ ? manifold_->positions.capacity() * sizeof(glm::dvec3) +
                          manifold_->triangles.capacity() * sizeof(glm::uvec3)
                    : 0);
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

glm::dvec3 pseudo_distance_gradient(const MeshLeaf::Closest& c, const glm::dvec3& p, double band) {
  if (!std::isfinite(c.distance)) return glm::dvec3(0.0);
  if (c.distance <= band) return c.normal;
  const glm::dvec3 away = (p - c.point) / c.distance;  // the gradient of dM
  return c.inside ? -away : away;
}

MeshFieldSample mesh_field_gradient(const MeshLeaf& mesh, const MeshFieldParams& params, const glm::dvec3& p) {
  const MeshLeaf::Closest q = mesh.query(p, params.query_radius);
  MeshFieldSample s;
  if (!std::isfinite(q.distance)) {
    s.value = q.inside ? params.F : 0.0;
    return s;
  }
  double d;
  if (!q.inside) {
    d = q.distance + params.r0;
  } else if (q.distance < params.r0) {
    d = params.r0 - q.distance;
  } else {
    s.value = params.F;
    return s;
  }
  if (d >= params.kernel_radius) return s;
  const double k2 = params.kernel_radius * params.kernel_radius;
  const double u = 1.0 - (d * d) / k2;
  s.value = params.F * u * u * u;
  s.gradient = (-6.0 * params.F * d / k2 * u * u) * pseudo_distance_gradient(q, p, mesh.surface_band());
  return s;
}

double mesh_field(const MeshLeaf& mesh, const MeshFieldParams& params, const glm::dvec3& p) {
  return mesh_field_gradient(mesh, params, p).value;
}

}  // namespace ht
