#include "meshers/cache_parts.hpp"

#include "meshers/cache_bytes.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace ht {

static_assert(sizeof(brick::EdgeVertex) == 48 && sizeof(brick::KeptBrick) == 56,
              "store the new field in encode_kept and decode_kept");

std::string encode_kept(const brick::KeptBrick& k) {
  const std::vector<brick::EdgeVertex>& vs = k.out.vertices;
  std::vector<std::uint32_t> with_normal;
  for (std::uint32_t v = 0; v < vs.size(); ++v)
    if (vs[v].normal != glm::vec3(0.0f)) with_normal.push_back(v);
  CacheWriter w;
  w(k.reaches_boundary, vs.size(), with_normal.size(), k.out.triangles.size());
  for (const brick::EdgeVertex& v : vs) w.bytes(&v.key, 8), w.bytes(&v.brick, 4), w.bytes(&v.position, sizeof v.position);
  for (const std::uint32_t v : with_normal) w.bytes(&v, 4), w.bytes(&vs[v].normal, sizeof vs[v].normal);
  for (const brick::LocalTriangle& t : k.out.triangles)
    for (const std::uint16_t v : t) {
      assert(v < vs.size());  // a brick's triangles use its own vertices (place_vertices)
      const std::uint32_t i = v;
      w.bytes(&i, 4);
    }
  return std::move(w.out);
}

// The join takes the lowest brick's copy of each key: the keys must increase, and a brick's
// triangles index its vertices in 16 bits.
bool decode_kept(std::string_view payload, brick::KeptBrick& k, std::string& why) {
  CacheReader in(payload);
  std::size_t nv = 0, nn = 0, nt = 0;
  std::uint32_t last_normal = 0;
  in(k.reaches_boundary, nv, nn, nt);
  std::vector<brick::EdgeVertex>& vs = k.out.vertices;
  if (in.fits(nv, 8 + 4 + sizeof(glm::dvec3), "vertices")) {
    vs.resize(nv);
    for (brick::EdgeVertex& v : vs) in.bytes(&v.key, 8), in.bytes(&v.brick, 4), in.bytes(&v.position, sizeof v.position);
  }
  if (nv > 0xffffu) in.fail(std::to_string(nv) + " vertices, more than a brick's 16-bit indices reach");
  if (in.error().empty() && in.fits(nn, 4 + sizeof(glm::vec3), "normals"))
    for (std::size_t i = 0; i < nn && in.error().empty(); ++i) {
      std::uint32_t v = 0;
      in.bytes(&v, 4);
      if (v >= nv || (i && v <= last_normal)) in.fail("a normal of vertex " + std::to_string(v) + " out of place");
      else in.bytes(&vs[v].normal, sizeof(glm::vec3));
      if (in.error().empty() && vs[v].normal == glm::vec3(0.0f)) in.fail("a zero normal listed");
      last_normal = v;
    }
  if (in.error().empty() && in.fits(nt, 12, "triangles")) {
    k.out.triangles.resize(nt);
    for (std::size_t t = 0; t < nt && in.error().empty(); ++t)
      for (std::uint16_t& v : k.out.triangles[t]) {
        std::uint32_t i = 0;
        in.bytes(&i, 4);
        if (i >= nv) in.fail("triangle " + std::to_string(t) + " names vertex " + std::to_string(i) + " of " + std::to_string(nv));
        else v = static_cast<std::uint16_t>(i);
      }
  }
  if (in.error().empty() && in.remaining()) in.fail(std::to_string(in.remaining()) + " bytes after the triangles");
  for (std::size_t i = 0; in.error().empty() && i < vs.size(); ++i) {
    if (i && !(vs[i - 1].key < vs[i].key)) in.fail("vertex keys out of order at " + std::to_string(i));
    if (vs[i].brick >= (1u << 31) || !std::isfinite(vs[i].position.x) || !std::isfinite(vs[i].position.y) ||
        !std::isfinite(vs[i].position.z))
      in.fail("vertex " + std::to_string(i) + " out of range");
  }
  why = in.error();
  return why.empty();
}

static_assert(sizeof(QualityStats) == 80 && sizeof(QualityPiece) == 176,
              "store the new QualityStats or QualityPiece field in encode_piece and decode_piece");
template <class Io, class S>
void stats_fields(Io& io, S& s) {
  io(s.collapses, s.flips, s.splits, s.moved, s.reverted, s.pieces, s.pieces_reused, s.retries, s.skipped, s.seconds);
}

std::string encode_piece(const QualityPiece& p) {
  CacheWriter w;
  w(p.mesh.positions.size(), p.mesh.triangles.size(), p.parts.size());
  w.bytes(p.mesh.positions.data(), p.mesh.positions.size() * sizeof(glm::dvec3));
  w.bytes(p.mesh.triangles.data(), p.mesh.triangles.size() * sizeof(glm::uvec3));
  w.bytes(p.origin.data(), p.origin.size() * sizeof(std::uint32_t));
  w.bytes(p.parts.data(), p.parts.size() * sizeof(p.parts[0]));
  stats_fields(w, p.stats);
  return std::move(w.out);
}

bool decode_piece(std::string_view payload, std::size_t inputs, QualityPiece& p, std::string& why) {
  CacheReader in(payload);
  std::size_t nv = 0, nt = 0, np = 0;
  in(nv, nt, np);
  if (nv > 0xffffffffu) in.fail(std::to_string(nv) + " vertices, more than 32-bit indices reach");
  if (in.error().empty() && in.fits(nv, sizeof(glm::dvec3) + 4, "vertices")) {
    p.mesh.positions.resize(nv);
    in.bytes(p.mesh.positions.data(), nv * sizeof(glm::dvec3));
  }
  if (in.error().empty() && in.fits(nt, sizeof(glm::uvec3), "triangles")) {
    p.mesh.triangles.resize(nt);
    in.bytes(p.mesh.triangles.data(), nt * sizeof(glm::uvec3));
  }
  if (in.error().empty()) {
    p.origin.resize(nv);
    in.bytes(p.origin.data(), nv * sizeof(std::uint32_t));
  }
  if (in.error().empty() && in.fits(np, sizeof(p.parts[0]), "parts")) {
    p.parts.resize(np);
    in.bytes(p.parts.data(), np * sizeof(p.parts[0]));
  }
  stats_fields(in, p.stats);
  if (in.error().empty() && in.remaining()) in.fail(std::to_string(in.remaining()) + " bytes after the statistics");
  for (std::size_t t = 0; in.error().empty() && t < nt; ++t)
    if (glm::any(glm::greaterThanEqual(p.mesh.triangles[t], glm::uvec3(std::uint32_t(nv)))))
      in.fail("triangle " + std::to_string(t) + " names a vertex past the " + std::to_string(nv));
  for (std::size_t v = 0; in.error().empty() && v < nv; ++v) {
    const glm::dvec3& x = p.mesh.positions[v];
    if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z)) in.fail("vertex " + std::to_string(v) + " is not finite");
    if (p.origin[v] != ~0u && p.origin[v] >= inputs) in.fail("vertex " + std::to_string(v) + " comes from past the input");
  }
  why = in.error();
  return why.empty();
}

}  // namespace ht
