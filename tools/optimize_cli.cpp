#include "tools/optimize_cli.hpp"

#include "runtime/scene.hpp"
#include "runtime/scene_write.hpp"
#include "tools/cli_io.hpp"

#include <cstdio>
#include <filesystem>

namespace ht::cli {

Tree load_tree(const std::string& scene, bool optimize, OptimizeStats* stats) {
  Tree tree = load_scene(scene);
  if (!optimize) return tree;
  return ht::optimize(tree, {}, stats);
}

std::string optimizer_report(const OptimizeStats& s) {
  char buf[512];
  std::string out;
  std::snprintf(buf, sizeof buf, "optimizer      %zu -> %zu nodes, overlap volume %.4g -> %.4g, in %.3f s\n", s.nodes_before,
                s.nodes_after, s.overlap_before, s.overlap_after, s.seconds);
  out += buf;
  if (s.tape_before || s.tape_after) {
    std::snprintf(buf, sizeof buf, "               tape %zu -> %zu instructions, %zu -> %zu registers\n", s.tape_before,
                  s.tape_after, s.registers_before, s.registers_after);
    out += buf;
  }
  std::snprintf(buf, sizeof buf,
                "               flattened %zu, groups %zu, warps pushed %zu, affines composed %zu, folded into "
                "primitives %zu, identities removed %zu, merged %zu, pruned %zu, one-operand nodes folded %zu, "
                "subtrees as tasks %zu\n",
                s.flattened, s.groups, s.warps_pushed, s.affines_composed, s.affines_folded, s.identities_removed,
                s.merged, s.pruned, s.folded, s.tasks);
  out += buf;
  return out;
}

int cmd_optimize(const OptimizeArgs& a) {
  OptimizeStats stats;
  const Tree tree = load_tree(a.scene, true, &stats);
  const bool to_stdout = a.out.empty() || a.out == "-";
  const std::filesystem::path dir =
      to_stdout ? std::filesystem::current_path() : std::filesystem::absolute(a.out).parent_path();
  std::string text;
  try {
    text = write_scene_text(tree, dir);
  } catch (const SceneWriteError& e) {
    throw InputError(a.scene + ": " + e.what());
  }
  if (to_stdout) {
    std::fwrite(text.data(), 1, text.size(), stdout);
    std::fputs(optimizer_report(stats).c_str(), stderr);
    return std::fflush(stdout) == 0 ? 0 : 1;
  }
  write_file_atomically(a.out, text, "output file");
  std::fputs(optimizer_report(stats).c_str(), stdout);
  return 0;
}

}  // namespace ht::cli
