// The quality pass on one mesh at once (meshers/quality.hpp): internal to the pass, which runs it
// on each slab and band of a mesh (meshers/quality_pieces.cpp).
#pragma once

#include "meshers/batch_field.hpp"
#include "meshers/quality.hpp"
#include "meshers/triangle_mesh.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace ht {

/// Collapse, flip and relax rounds over all of `mesh` (locked and crease flags per vertex, or
/// empty). `origin` receives, per vertex of the result, its index in the input or ~0u for a new
/// vertex. A mesh OpenMesh cannot hold is left as it is (st.skipped). Deterministic; the field
/// may be called from several threads.
void improve_whole(TriangleMesh& mesh, std::span<const std::uint8_t> locked, std::span<const std::uint8_t> crease,
                   const BatchField& field, double T, double h, const QualityOptions& options, QualityStats& st,
                   std::vector<std::uint32_t>& origin);

}  // namespace ht
