// The OpenMesh triangle mesh type every part of HybridTree exchanges: double-precision points.
#pragma once

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

namespace ht {

struct TriMeshTraits : public OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
  using Normal = OpenMesh::Vec3d;
};
using TriMesh = OpenMesh::TriMesh_ArrayKernelT<TriMeshTraits>;

}  // namespace ht

namespace ht {
/// Holds a TriMesh behind a forward-declarable name, so headers need not include OpenMesh.
class TriMeshHolder {
 public:
  TriMesh mesh;
};
}  // namespace ht
