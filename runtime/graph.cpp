#include "runtime/graph.hpp"

namespace ht {

std::string Graph::label(NodeId n) const {
  if (name[n] != kNone) return "\"" + names[name[n]] + "\"";
  return std::string(kind_name(kind[n])) + " #" + std::to_string(n);
}

std::size_t Graph::bytes() const {
  auto vec = [](const auto& v) { return v.size() * sizeof(v[0]); };
  std::size_t total = vec(kind) + vec(boolean) + vec(mesher) + vec(param_begin) + vec(param_count) +
                      vec(child_begin) + vec(child_count) + vec(mesh) + vec(name) + vec(params) + vec(children) +
                      vec(meshes);
  for (const auto& s : names) total += s.size();
  return total;
}

std::size_t Graph::derived_bytes() const {
  auto vec = [](const auto& v) { return v.size() * sizeof(v[0]); };
  return vec(derived) + vec(derived_begin) + vec(derived_count) + vec(support_alone) + vec(support_blended) +
         vec(nonnegative);
}

}  // namespace ht
