// Trimmed crops (meshers/local_ops.hpp): the child's mesh cut by the box one face at a time,
// each opening closed by a planar cap.
#include "meshers/local_ops.hpp"

#include "meshers/local_parts.hpp"
#include "meshers/caps.hpp"
#include "meshers/relax.hpp"
#include "runtime/node_params.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <vector>

namespace ht {

using namespace local;

TriangleMesh trim_crop(const LocalInput& in, LocalStats* stats) {
  LocalStats st;
  const double* box6 = params::crop(*in.graph, in.node).box6;
  const Aabb box{{box6[0], box6[1], box6[2]}, {box6[3], box6[4], box6[5]}};
  st.operand_triangles = operand(in, 0).triangles.size();
  TriangleMesh out = operand(in, 0);
  // One face at a time: cut by its plane, then close the openings, which all lie in that plane,
  // with planar caps. The next plane cuts those caps too, along the box's edge, so openings
  // that cross an edge of the box come out as two caps meeting on it.
  for (int face = 0; face < 6; ++face) {
    const int axis = face / 2;
    const bool hi = face % 2 == 1;
    const double at = hi ? box.hi[axis] : box.lo[axis], sign = hi ? 1.0 : -1.0;
    const BatchField plane = [axis, at, sign](std::span<const glm::dvec3> points, std::span<double> values) {
      for (std::size_t k = 0; k < points.size(); ++k) values[k] = sign * (points[k][axis] - at);
    };
    if (std::none_of(out.positions.begin(), out.positions.end(), [&](const glm::dvec3& p) { return sign * (p[axis] - at) >= 0; }))
      continue;
    out = cut_mesh(out, plane, cut_options(in, true));
    CapStats caps;
    try {
      cap_box_openings(out, box, 1e-6 * std::max(1.0, glm::length(box.size())), 1.5 * in.precision, &caps);
    } catch (const CapError& e) {
      throw LocalFailure(e.what());
    }
    st.patch_triangles += caps.triangles;
  }
  st.kept_triangles = out.triangles.size() - st.patch_triangles;
  // Only the cut and its caps are new: look for intersections next to the box's faces.
  st.self_intersections = intersections_in(out, box.expanded(2.0 * in.precision)).size();
  if (stats) *stats = st;
  return out;
}


}  // namespace ht
