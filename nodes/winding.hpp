// Generalized winding numbers of triangle soups (Jacobson, Kavan, Sorkine-Hornung 2013,
// "Robust inside-outside segmentation using generalized winding numbers"): w(p) is the signed
// solid angle the triangles subtend at p, over 4 pi. It is 1 inside and 0 outside a closed,
// outward-oriented mesh and degrades gracefully on open, non-manifold and self-intersecting
// ones; the mesh leaf's "inside": "winding" mode calls p inside when w(p) > 1/2.
//
// Evaluation is hierarchical, after Barill, Dickson, Schmidt, Levin, Jacobson 2018 ("Fast winding
// numbers for soups and clouds"): a bounding-volume hierarchy over the triangles, each node
// with its area-weighted normal N = sum a_t n_t and first moments M = sum a_t n_t (g_t - c)^T
// about its expansion centre c (g_t: centroids). Far from a node (distance R from c, node radius
// r: every point of its triangles within r of c), its solid angle is the first-order expansion
//     Omega ~ N . y/|y|^3 + tr(M)/|y|^3 - 3 y^T M y/|y|^5,   y = c - p,
// whose error is at most 3 Q/(R - r)^4, Q the integral of |x - c|^2 over the node's triangles
// (at most A r^2, A the node's unsigned area; the bound follows from |D^k (1/|y|)| <=
// k!/|y|^(k+1)). Over a ball of radius rho about p the node's solid angle also varies by at most
// A * 2 rho/(R - r - rho)^3. A node is expanded only when that bound, over 4 pi, is within
// tau * A / A_total; otherwise it is opened, and leaf triangles are summed exactly (Van
// Oosterom and Strackee's formula). So an estimate carries a rigorous bound B <= tau on
// |w - estimate| (over the whole ball when rho > 0; leaf triangles then add their variation).
//
// inside() is exact where it matters: it accepts an estimate only when |w~ - 1/2| > B, and
// otherwise refines (tau / 16, then tau = 0: every triangle exactly), so its answer is the
// exact sum's (up to the rounding of about 1e-15 per triangle), whatever tau.
//
// Thread safety: built once, then read-only; every query is safe from any number of threads and
// allocates nothing. Results are deterministic (fixed traversal and summation order).
#pragma once

#include "runtime/aabb.hpp"

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace ht {

class WindingTree {
 public:
  /// Triangles of `positions` (indices must be valid; degenerate triangles are allowed and
  /// contribute nothing). O(n log n).
  WindingTree(const std::vector<glm::dvec3>& positions, const std::vector<glm::uvec3>& triangles);

  struct Estimate {
    double w;      ///< the winding number at the ball's centre, approximately
    double bound;  ///< |w(x) - w| <= bound for every x in the ball; +infinity when the ball
                   ///< meets a triangle's bounding sphere (no bound then)
  };
  /// The hierarchical estimate at p, valid over the ball of radius rho >= 0 about p, with error
  /// budget tau >= 0 (tau = 0: the exact sum at p). With opening > 0, a node whose triangles lie
  /// at least opening times its radius beyond the ball is expanded too, whatever the budget: the
  /// bound is as rigorous, but no longer held to tau.
  Estimate estimate(const glm::dvec3& p, double rho, double tau, double opening = 0.0) const;
  /// The exact sum over every triangle (the reference; O(n)).
  double exact(const glm::dvec3& p) const;
  /// w(p) > 1/2, decided exactly (see the top of this file). A non-finite p is outside.
  bool inside(const glm::dvec3& p) const;
  /// +1 when w > 1/2 on the whole box, 0 when w <= 1/2 on the whole box, -1 when that cannot
  /// be certified cheaply (the box is near the triangles or the 1/2 level set).
  int box_side(const Aabb& box) const;

  static constexpr double kTau = 0.25;      ///< inside()'s error budget after its first try
  static constexpr double kOpening = 2.0;   ///< inside()'s first try: estimate(p, 0, 0, kOpening)
  std::size_t bytes() const;

 private:
  struct Node {
    glm::dvec3 c;           // expansion centre: the area-weighted centroid
    double r = 0;           // every point of the node's triangles is within r of c
    glm::dvec3 n{0.0};      // sum a_t n_t (the area vector)
    double m[9] = {};       // sum a_t n_t (g_t - c)^T, row-major
    double area = 0;        // sum a_t
    double q = 0;           // the integral of |x - c|^2 over the node's triangles
    std::uint32_t first = 0, count = 0;  // leaf: triangles [first, first + count); inner: count 0
    std::uint32_t left = 0, right = 0;   // inner: children
  };
  struct Tri {
    glm::dvec3 a, b, c;
    glm::dvec3 centre;  // centroid
    double reach;       // max distance from the centroid to a corner
    double area;
  };
  std::uint32_t build(std::vector<std::uint32_t>& order, std::uint32_t first, std::uint32_t count,
                      const std::vector<Tri>& input);
  void summarize(Node& node) const;
  std::vector<Node> nodes_;
  std::vector<Tri> tris_;  // in leaf order
  double total_area_ = 0;
};

}  // namespace ht
