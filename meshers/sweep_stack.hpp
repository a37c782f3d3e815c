// The building blocks of the sweep meshes (meshers/sweep.hpp): stacks of vertex loops zipped
// into bands, surfaces of revolution from a sampled profile, Lawson flips on flat faces, and the
// cube-sphere lattice of rounded boxes. Internal to the sweep mesher; every function appends to
// the mesh it is given and leaves what is already there alone.
#pragma once

#include "meshers/triangle_mesh.hpp"

#include <glm/vec3.hpp>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <span>
#include <vector>

namespace ht::sweep {

using glm::dvec3;

inline constexpr double kPi = std::numbers::pi;
// Rows of equilateral triangles with sides h lie sqrt(3)/2 h apart.
inline constexpr double kRowSpacing = 0.86602540378443865;
// Profile pieces shorter than this fraction of a row are skipped: they would only add rings
// that (nearly) coincide with their neighbours.
inline constexpr double kNegligible = 1e-9;

inline dvec3 vec_at(const double* s, int i) { return {s[i], s[i + 1], s[i + 2]}; }

// Cells of about `step` over `length`, at least `at_least`. The triangle estimate taken before
// building keeps the count far below INT_MAX.
inline int cells_for(double length, double step, int at_least) {
  const double n = std::round(length / step);
  return n > at_least ? static_cast<int>(n) : at_least;
}

inline std::uint32_t vertex_count(const TriangleMesh& m) { return static_cast<std::uint32_t>(m.positions.size()); }

// A closed loop of vertices, consecutive in the mesh: positions[first, first + count). A loop of
// one vertex is a pole.
struct Loop {
  std::uint32_t first, count;
};

// A right-handed frame (u x v = axis): rings turn counter-clockwise around the axis, and a stack
// runs from +axis ("top") to -axis, so that zip() faces its triangles outward.
struct Frame {
  dvec3 origin, axis, u, v;
};

Frame frame_around(const dvec3& origin, const dvec3& axis);

// A ring of radius rho at height z on the frame's axis: a pole when rho is 0, else
// max(3, round(2 pi rho / h)) vertices, turned by half a step when `stagger`.
Loop add_ring(TriangleMesh& m, const Frame& f, double rho, double z, double h, bool stagger);

// Zips loop a (nearer the top) to loop b with a band of a.count + b.count triangles.
void zip(TriangleMesh& m, Loop a, Loop b);

// Zips consecutive loops of a stack, and the last to the first when `closed`.
void zip_stack(TriangleMesh& m, std::span<const Loop> loops, bool closed);

// Lawson flips of the coplanar convex quads among triangles [first, last) of m (one vertex
// range) toward the Delaunay triangulation of the same vertices.
void flip_flat_quads(TriangleMesh& m, std::size_t first, std::size_t last);

// A profile in the half-plane of a frame (rho >= 0 from the axis, z along it), sampled every
// `step`. It runs from the top with the outside on its left (outward first, then down), which is
// what makes zip() face outward. Arcs are parameterized by psi, the angle from +z.
struct Profile {
  double step;
  std::vector<double> rho, z;

  void push(double r, double zz) {
    rho.push_back(r);
    z.push_back(zz);
  }
  // Pieces join end to start: each piece after the first skips its first point.
  void arc(double rc, double zc, double radius, double psi0, double psi1, int at_least = 1) {
    const double length = radius * std::abs(psi1 - psi0);
    if (!rho.empty() && length <= kNegligible * step) return;
    const int n = cells_for(length, step, at_least);
    for (int j = rho.empty() ? 0 : 1; j <= n; ++j) {
      const double psi = psi0 + (psi1 - psi0) * (double(j) / n);
      push(rc + radius * std::sin(psi), zc + radius * std::cos(psi));
    }
  }
  void line(double r0, double z0, double r1, double z1) {
    const double length = std::hypot(r1 - r0, z1 - z0);
    if (!rho.empty() && length <= kNegligible * step) return;
    const int n = cells_for(length, step, 1);
    for (int j = rho.empty() ? 0 : 1; j <= n; ++j) {
      const double t = double(j) / n;
      push(r0 + (r1 - r0) * t, z0 + (z1 - z0) * t);
    }
  }
};

// The surface swept by turning the profile around the frame's axis.
void revolve(TriangleMesh& m, const Frame& f, const Profile& p, double h, bool closed);

// The rounded box of the given centre and half sizes at offset r (exactly at distance r from
// the box), edges about h.
void rounded_box(TriangleMesh& m, const dvec3& center, const dvec3& half, double r, double h);

}  // namespace ht::sweep
