// The sweep mesher: the paper's "optimal mesh" of a lone skeletal primitive (section 3.1.1).
//
// A lone primitive's surface {g(d) = T} is the offset of its skeleton at the constant distance
// r0 = g^-1(T) (primitive_r0): a sphere of radius r0 swept along the skeleton. That surface is
// known in closed form, so it is meshed directly, without sampling any field: every vertex is
// placed on it exactly (to rounding), and the triangles are laid out to be near-equilateral with
// edges about `precision` (h) long.
//
// Two layouts cover the nine skeletons:
//   loop stack  The surface is a stack of closed loops of vertices from a "top" pole to a
//               "bottom" pole (or, for a ring torus, closed on itself); neighbouring loops are
//               zipped into a band of triangles by the shorter diagonal. Loops are sqrt(3)/2 h
//               apart and sampled every h (a circle of radius s gets max(3, round(2 pi s / h))
//               vertices), and alternate circles are turned by half a step, so bands are strips
//               of near-equilateral triangles. Used by the surfaces of revolution (point,
//               segment, circle, disc, cylinder, cone_sphere), the triangle (loops are the
//               triangle shrunk toward its incentre on the flat faces, and the triangle offset in
//               its plane by r sin(psi) at height r cos(psi) around its rim; the flat faces are
//               then made Delaunay by edge flips, which removes the thin triangles the shrunk
//               loops leave at acute corners) and the curve (circles swept along it).
//   lattice     The box: a cube-sphere split along its three mid-planes, its eight octants moved
//               to the box's corners and the gaps filled with flat strips. Each surface point of
//               an N0 x N1 x N2 lattice maps to (its box point) + r0 * (its equiangular
//               cube-sphere direction); quads are split along their shorter diagonal.
//
// The surfaces, with r = r0 (all closed; genus 0 unless said):
//   point        sphere of radius r
//   segment      capsule: a cylinder of radius r on a-b and two hemispheres
//   circle       r < rho: torus with tube radius r (genus 1). r >= rho: the boundary of the solid
//                {d <= r} is an "apple": the arc of the tube's cross-section outside the axis,
//                from where it meets the axis above the centre to where it meets it below,
//                revolved (the self-intersecting inner part of a spindle torus lies inside the
//                solid). At r == rho exactly the two poles coincide at the centre (two vertices,
//                one position): the horn torus's pinch.
//   disc         flat discs at +-r joined by a half torus around the rim
//   triangle     flat triangles at +-r along the normal, half cylinders on the edges, spherical
//                lunes at the corners. A degenerate skeleton (height at most 1e-10 (L + r), L its
//                longest edge) is meshed as the capsule of its longest edge, which it then is.
//   curve        a tube of radius r with hemispherical caps around the polyline
//                graph.skeleton_of(node), resampled every sqrt(3)/2 h of its length; frames are
//                rotation-minimizing (double reflection) on tangents interpolated between the
//                polyline's points; see "Curves" below
//   box          rounded box: faces offset by r, quarter cylinders on the edges, sphere octants
//   cylinder     flat caps (discs of radius rho offset by r along the axis), a side of radius
//                rho + r, quarter tori around both rims
//   cone_sphere  the hull of the balls of radii ra + r and rb + r: two sphere caps joined by the
//                cone frustum tangent to both (just the bigger sphere when it holds the other)
// A zero-length segment or curve is meshed as the sphere around its point.
//
// Curves: vertices are first laid on circles of radius r around points of the polyline, then
// each is moved along its ray from the circle's centre to the distance r from the polyline's
// segments within pi r + 2 h of arc length (safeguarded Newton). Where the curvature radius
// stays above r and the curve does not come back within 2 r of itself, that is the exact offset
// of the whole polyline. Where the polyline bends more sharply than r, neighbouring loops cross
// and the tube folds: the mesh is still a closed, oriented 2-manifold topologically, but it
// self-intersects there, and vertices are only at distance r from the *local* part of the
// polyline (a vertex whose ray finds no such point within 4 r stays on its circle). Triangles
// thin toward the inside of bends (their height scales by 1 - r / curvature radius).
//
// Quality, measured by tests/test_sweep.cpp at h = r/3 .. r/10 on random skeletons whose features
// are not smaller than h (smallest angle over all meshes; degrees): point, segment, torus,
// cylinder, cone_sphere about 40; disc 39; box 35 (right triangles on its flat faces); apple 32;
// triangle 26 (skeleton angles above 20 degrees); curve 22 (bends of curvature radius near 1.3 r).
// Every patch gets at least one row of cells, so a feature far smaller than h (a rim radius r,
// a box side, a very acute corner) leaves triangles as thin as that feature.
// Cost: linear in the output, e.g. 5 million triangles of a box in 0.6 s, of a triangle in 0.7 s;
// a curve's vertices also measure their distance to the polyline's segments within pi r + 2 h of
// arc length (2.4 million triangles in 0.65 s on two cores, TBB over loops). The output is
// deterministic.
#pragma once

#include "meshers/triangle_mesh.hpp"
#include "nodes/kinds.hpp"
#include "runtime/graph.hpp"

namespace ht {

/// The most triangles sweep_mesh builds, by an upper estimate from the surface's area and the
/// skeleton's length, taken before building anything.
inline constexpr double kSweepMaxTriangles = 50e6;

/// The optimal mesh of the lone skeletal primitive `node` at threshold T: a closed, consistently
/// oriented (counter-clockwise seen from outside) 2-manifold of one component, without
/// degenerate triangles, unused or duplicate vertices (seams share their vertices: no
/// T-junctions), Euler characteristic 2 (0 for a ring torus), every vertex at distance
/// r0 = primitive_r0(R, F, T) from the skeleton (to rounding; for curves see above), edges about
/// `precision` long.
/// Returns an empty mesh when F <= T (the primitive is not visible on its own).
/// Throws std::invalid_argument when `node` is not a skeletal primitive of `graph`, or when
/// `precision` or `threshold` is not a finite number > 0; PolygonizeError (a
/// std::runtime_error, meshers/polygonize.hpp) when the mesh would need more than
/// kSweepMaxTriangles triangles.
TriangleMesh sweep_mesh(const Graph& graph, NodeId node, double threshold, double precision);

/// sweep_mesh's upper estimate of its triangle count (0 when F <= T), without building
/// anything: what memory budgets take before the mesh is built. Same exceptions as sweep_mesh
/// for a node or numbers it refuses, none for the count.
double sweep_triangle_estimate(const Graph& graph, NodeId node, double threshold, double precision);

/// True for the kinds sweep_mesh handles: the nine skeletal primitives.
bool has_sweep_mesh(NodeKind kind);

}  // namespace ht
