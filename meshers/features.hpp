// Sharp features for the global polygonizer (meshers/polygonize.hpp).
//
// Marching tetrahedra puts every vertex on a grid edge, so where two sheets of a surface meet at
// an angle (min/max Booleans, crop, sharp mesh leaves) the triangles that span the crease cut it
// off: a chamfer up to a third of a cell deep. In the spirit of Extended Marching Cubes (Kobbelt,
// Botsch, Schwanecke & Seidel 2001), which inserts feature points where normals disagree, the
// crease is put back by splitting those edges:
//
//  - An edge whose end normals differ by more than `sharp_angle` crosses a crease (or a ridge
//    too tight for the precision). The tangent planes at its two ends meet in a line; the point
//    of that line nearest the edge's midpoint is where the crease crosses between them. The
//    point is used only when it lies between the ends and on the surface (|f - T| / |grad f| at
//    most `max_error` cells), so smooth regions are left alone.
//  - With mesh leaves in the field (their pseudo-normals are piecewise constant), the bend must
//    be where that point says: the sheets' normals probed a third of the way from
//    it toward each end must still differ by most of the ends' difference and by more than
//    `sharp_angle`. A surface that turns along the whole edge (a faceted scan such as bunny00,
//    whose facets turn 10-25 degrees each: its pseudo-normals jump from facet to facet) fails
//    this and keeps the edge whole. And the normal must jump at the
//    crease point: there it is one sheet's (a Boolean's or a crop's seam: one operand wins), a
//    third sheet's (a corner) or, on a mesh leaf's own sharp edge, the two facets' bisector with
//    the point on the surface; just off it on either side, again not one in between.
//  - A crease point within `snap` of an edge's end moves that end onto the crease instead (no
//    sliver), and the edges at a moved vertex are no longer split.
//  - Every triangle is cut along its split edges (one, two or three). A triangle with two split
//    edges gets the segment between the two crease points as an edge, so the crease becomes a
//    chain of mesh edges; one with three (a corner, three sheets meeting) gets a fourth vertex at
//    the point of its three tangent planes when that point is valid. A cut whose sizeable piece
//    would face against its vertices' normals gives back a split (or a move) until none does.
//
// Splitting an edge is a purely local change that both triangles of the edge see, so the mesh
// stays a closed, oriented 2-manifold of the same topology. Normals are needed only near
// creases: the polygonizer looks for them only in bricks whose specialized tape has an operator
// that makes creases, mark_suspect_cells finds the cells whose grid gradients disagree there,
// and only their vertices get exact (forward-mode) gradients.
#pragma once

#include "meshers/triangle_mesh.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace ht {

class TapeEvaluator;
struct Tape;

struct FeatureOptions {
  double sharp_angle_degrees = 25.0;    ///< end normals further apart than this: the edge crosses a crease
  double suspect_angle_degrees = 12.0;  ///< grid gradients of a cell further apart: its vertices get normals
  double max_error = 0.05;              ///< crease points off the surface by at most this many cells
  int refine_rounds = 2;                ///< re-linearisations of the two sheets nearer the crease
  double snap = 0.15;                   ///< a crease point this near an edge's end (in edge lengths) moves the end
};

/// Whether a tape can make creases at all: min/max and R-function operators, crop and mesh
/// leaves can; blends of skeletal primitives under warps are smooth, and need no normals.
bool may_have_creases(const Tape& tape);

/// Marks the cells of a brick whose corner gradients (central differences of the samples,
/// one-sided on the brick's faces) spread by more than options.suspect_angle_degrees.
/// `values` holds (cells + 1)^3 samples, x fastest; `suspect` receives cells^3 flags, x fastest.
void mark_suspect_cells(std::span<const float> values, int cells, const FeatureOptions& options,
                        std::span<std::uint8_t> suspect);

struct CreaseStats {
  std::size_t candidate_edges = 0;  ///< edges whose end normals disagree
  std::size_t spread_edges = 0;     ///< of those, found to bend rather than crease: left whole
  std::size_t split_edges = 0;      ///< of those, split at a valid crease point
  std::size_t moved_vertices = 0;   ///< vertices moved onto a crease point near them
  std::size_t corners = 0;          ///< corner vertices added inside triangles
};

/// Splits the mesh's edges along creases. normals[v] is vertex v's outward unit normal, or zero
/// where unknown (such vertices' edges are left alone). `eval` is a tape of the surface's field
/// (threshold T) used to check the new points; h the precision. With `on_crease`, receives one
/// flag per vertex of the result: set on the crease points (new and moved vertices, and those the
/// caller flagged already, such as snapped grid points: meshers/snap.hpp), which later passes
/// must keep where they are. Deterministic.
CreaseStats split_creases(TriangleMesh& mesh, std::span<const glm::vec3> normals, const TapeEvaluator& eval,
                          double threshold, double h, const FeatureOptions& options = {},
                          std::vector<std::uint8_t>* on_crease = nullptr);

}  // namespace ht
