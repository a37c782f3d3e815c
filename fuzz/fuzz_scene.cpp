// fuzz_scene: bytes as scene JSON through ht::load_scene_text, then the field of a loaded scene
// at a few points, by the tape and by the reference evaluator.
//
// Mesh leaves resolve their files in fuzz/meshes/ (small committed meshes, each format and a few
// broken ones). An input naming a mesh by anything but a bare file name is skipped: a path could
// name any file of the machine, a huge mesh or a device that never ends, which says nothing
// about the loader. A scene must load or be refused with one SceneError; every value it then
// gives must be finite when its numbers are moderate (see moderate()).
#include "fuzz/fuzz_support.hpp"

#include "runtime/scene.hpp"
#include "runtime/tree.hpp"

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>
#include <pthread.h>

#include <cmath>
#include <string>
#include <typeinfo>
#include <vector>

namespace {

using json = nlohmann::json;

// Every "file" string anywhere in the document is a bare name (an explicit stack: the document
// may nest thousands of levels).
bool mesh_names_stay_in_mesh_dir(const json& doc) {
  std::vector<const json*> todo{&doc};
  while (!todo.empty()) {
    const json& j = *todo.back();
    todo.pop_back();
    if (j.is_object()) {
      for (auto it = j.begin(); it != j.end(); ++it) {
        if (it.key() == "file" && it->is_string() && it->get_ref<const std::string&>().find('/') != std::string::npos)
          return false;
        todo.push_back(&*it);
      }
    } else if (j.is_array()) {
      for (const json& e : j) todo.push_back(&e);
    }
  }
  return true;
}

bool finite(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Parameters whose squares, products and sums stay far inside float's range (the tape runs in
// float): a scene of such numbers must have a finite field. Past them a finite answer is not
// promised (a strength of 1e300 is past what the tape can hold), so only crashes count there.
bool moderate(const ht::Graph& g) {
  for (const double v : g.params)
    if (v != 0.0 && !(std::abs(v) >= 1e-6 && std::abs(v) <= 1e6)) return false;
  return true;
}

// The field and gradient at the origin and at points of the root's support, both evaluators. An
// ffd needs its deformed mesh before it has a field (meshers/ffd.hpp): such scenes stop at load.
void evaluate(const ht::Tree& tree) {
  const ht::Graph& g = tree.graph();
  for (const ht::NodeKind k : g.kind)
    if (k == ht::NodeKind::Ffd) return;
  const bool check = moderate(g);
  std::vector<glm::dvec3> points = {glm::dvec3(0.0)};
  const ht::Aabb box = g.support(tree.root(), false);
  if (box.finite())
    for (const glm::dvec3& t : {glm::dvec3(0.5), glm::dvec3(0.3137, 0.5923, 0.7711), glm::dvec3(0.9, 0.1, 0.45)})
      points.push_back(box.lo + t * box.size());
  for (const glm::dvec3& p : points) {
    const double reference = tree.reference(p), tape = tree.field(p);
    ht::fuzz::require(!check || std::isfinite(reference), "the reference field is not finite");
    ht::fuzz::require(!check || std::isfinite(tape), "the tape's field is not finite");
  }
  const glm::dvec3 gradient = tree.gradient(points.back());
  ht::fuzz::require(!check || finite(gradient), "the tape's gradient is not finite");
}

void load_and_evaluate(const std::string& text) {
  try {
    const ht::Tree tree = ht::load_scene_text(text, ht::fuzz::mesh_dir(), "fuzz.json");
    evaluate(tree);
  } catch (const ht::SceneError& e) {
    const std::string msg = e.what();
    ht::fuzz::require(msg.rfind("fuzz.json: ", 0) == 0, "SceneError without the source name: " + msg);
  } catch (const std::exception& e) {
    ht::fuzz::finding(std::string("threw ") + typeid(e).name() + ": " + e.what());
  } catch (...) {
    ht::fuzz::finding("threw something not derived from std::exception");
  }
}

// The loader recurses once per nesting level, up to ht::kMaxSceneDepth; the sanitizers' redzones
// make that deeper than the main thread's 8 MB (tests/test_scene.cpp DeepNesting), so the input
// runs on a thread with a stack of 64 MB.
void on_big_stack(const std::string& text) {
  struct Job {
    const std::string* text;
  } job{&text};
  pthread_attr_t attr;
  pthread_attr_init(&attr);
  pthread_attr_setstacksize(&attr, std::size_t{64} << 20);
  pthread_t thread;
  const int rc = pthread_create(
      &thread, &attr,
      [](void* p) -> void* {
        load_and_evaluate(*static_cast<Job*>(p)->text);
        return nullptr;
      },
      &job);
  pthread_attr_destroy(&attr);
  ht::fuzz::require(rc == 0, "cannot start the loader's thread");
  pthread_join(thread, nullptr);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > ht::fuzz::kMaxInputBytes) return 0;
  const std::string text(reinterpret_cast<const char*>(data), size);
  // The same parser the loader uses; text it refuses goes to the loader as it is (its error path).
  try {
    const json doc = json::parse(text, nullptr, false);
    if (!doc.is_discarded() && !mesh_names_stay_in_mesh_dir(doc)) return 0;
  } catch (const json::exception&) {
  }
  on_big_stack(text);
  return 0;
}
