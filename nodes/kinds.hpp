// The node kinds of a HybridTree, in one table (X-macro): the scene name of each kind and its
// family. Everything that switches over kinds is generated from or checked against this list.
#pragma once

#include <cstdint>
#include <string_view>

namespace ht {

enum class Family : std::uint8_t { Primitive, Mesh, Operator, Warp };

// X(enum name, scene "type", family)
#define HT_NODE_KINDS(X)                      \
  X(Point, "point", Primitive)                \
  X(Segment, "segment", Primitive)            \
  X(Circle, "circle", Primitive)              \
  X(Disc, "disc", Primitive)                  \
  X(Triangle, "triangle", Primitive)          \
  X(Curve, "curve", Primitive)                \
  X(Box, "box", Primitive)                    \
  X(Cylinder, "cylinder", Primitive)          \
  X(ConeSphere, "cone_sphere", Primitive)     \
  X(Mesh, "mesh", Mesh)                       \
  X(Blend, "blend", Operator)                 \
  X(Union, "union", Operator)                 \
  X(Intersection, "intersection", Operator)   \
  X(Difference, "difference", Operator)       \
  X(LocalBlend, "local_blend", Operator)      \
  X(Crop, "crop", Operator)                   \
  X(Affine, "affine", Warp)                   \
  X(Twist, "twist", Warp)                     \
  X(Taper, "taper", Warp)                     \
  X(Bend, "bend", Warp)                       \
  X(Ffd, "ffd", Warp)

enum class NodeKind : std::uint8_t {
#define HT_X(e, s, f) e,
  HT_NODE_KINDS(HT_X)
#undef HT_X
};

inline constexpr int kNodeKindCount = 0
#define HT_X(e, s, f) +1
    HT_NODE_KINDS(HT_X)
#undef HT_X
    ;

constexpr std::string_view kind_name(NodeKind k) {
  switch (k) {
#define HT_X(e, s, f) \
  case NodeKind::e:   \
    return s;
    HT_NODE_KINDS(HT_X)
#undef HT_X
  }
  return "?";
}

constexpr Family kind_family(NodeKind k) {
  switch (k) {
#define HT_X(e, s, f) \
  case NodeKind::e:   \
    return Family::f;
    HT_NODE_KINDS(HT_X)
#undef HT_X
  }
  return Family::Operator;
}

/// How a Boolean node combines its children (SCENE_FORMAT.md, "Operators").
enum class BooleanMode : std::uint8_t { Auto, MinMax, RFunction };

}  // namespace ht
