// `import hybridtree`: the embedding API (runtime/api.hpp, installed as <hybridtree/api.hpp>) for
// Python. Points and meshes are NumPy arrays; field(), gradient() and mesh() release the GIL
// while they compute, so Python threads may evaluate one tree at once (the API's contract), and
// take `threads` as the C++ calls do. hybridtree.Error and its subclasses carry the C++ messages
// and their `file` and `path`; InputError is also a ValueError.
#include "tools/python/arrays.hpp"

#include <hybridtree/api.hpp>
#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include <atomic>
#include <exception>
#include <mutex>

namespace py = pybind11;
using namespace hybridtree;
using hybridtree::python::indices_arg;
using hybridtree::python::points_arg;
using hybridtree::python::to_numpy;

namespace {

// Raises the Python twin of a hybridtree::Error, with `file` and `path` attributes.
void raise(const py::object& type, const Error& e) {
  py::object instance = type(e.what());
  instance.attr("file") = e.file();
  instance.attr("path") = e.path();
  PyErr_SetObject(type.ptr(), instance.ptr());
}

void register_errors(py::module_& m) {
  auto make = [&m](const char* name, py::handle base) {
    py::object type = py::reinterpret_steal<py::object>(
        PyErr_NewException((std::string("hybridtree.") + name).c_str(), base.ptr(), nullptr));
    m.attr(name) = type;
    return type;
  };
  static py::object error = make("Error", PyExc_RuntimeError);
  static py::object scene = make("SceneError", error);
  static py::object input = make("InputError", py::make_tuple(error, py::handle(PyExc_ValueError)));
  static py::object meshing = make("MeshingError", error);
  static py::object budget = make("MemoryBudgetError", meshing);
  static py::object cancelled = make("CancelledError", error);
  static py::object write = make("WriteError", error);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const MemoryBudgetError& e) {
      raise(budget, e);
    } catch (const MeshingError& e) {
      raise(meshing, e);
    } catch (const SceneError& e) {
      raise(scene, e);
    } catch (const InputError& e) {
      raise(input, e);
    } catch (const CancelledError& e) {
      raise(cancelled, e);
    } catch (const WriteError& e) {
      raise(write, e);
    } catch (const Error& e) {
      raise(error, e);
    }
  });
}

Strategy strategy_arg(const std::string& s) {
  if (s == "scene") return Strategy::Scene;
  if (s == "auto") return Strategy::Auto;
  if (s == "global") return Strategy::Global;
  if (s == "local") return Strategy::Local;
  throw py::value_error("strategy: expected \"scene\", \"auto\", \"global\" or \"local\", not \"" + s + "\"");
}

py::array_t<double> field(const Tree& tree, const py::handle& points, int threads) {
  const auto p = points_arg(points, "points");
  std::vector<double> values(p.n);
  {
    py::gil_scoped_release unlocked;
    tree.field(p.xyz, values, {.threads = threads});
  }
  return to_numpy(std::move(values), 0);
}

py::array_t<double> gradient(const Tree& tree, const py::handle& points, int threads) {
  const auto p = points_arg(points, "points");
  std::vector<double> g(3 * p.n);
  {
    py::gil_scoped_release unlocked;
    tree.gradient(p.xyz, g, {}, {.threads = threads});
  }
  return to_numpy(std::move(g), 3);
}

// The run's progress goes to `callback` (when given) with the GIL held; a callback that raises or
// returns False cancels the run, and so does Ctrl-C when a report runs on the main thread (Python
// only sees signals there); what stopped it is raised once the run is back.
struct Progress {
  py::object callback;
  std::atomic<bool> cancel{false};
  std::mutex mutex;
  std::exception_ptr stop;

  void operator()(double fraction) {
    py::gil_scoped_acquire locked;
    try {
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
      if (!callback.is_none()) {
        py::object r = callback(fraction);
        if (!r.is_none() && !r.cast<bool>()) cancel = true;
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex);
      if (!stop) stop = std::current_exception();
      cancel = true;
    }
  }
};

// Tree.mesh (session null) and Session.mesh.
py::tuple mesh_in(Session* session, const Tree& tree, double precision, const std::string& strategy, int threads,
                  double memory_budget_gib, bool sharp_features, bool quality, py::object progress) {
  MeshOptions o;
  o.precision = precision;
  o.strategy = strategy_arg(strategy);
  o.threads = threads;
  o.memory_budget_gib = memory_budget_gib;
  o.sharp_features = sharp_features;
  o.quality = quality;
  Progress watch;
  watch.callback = std::move(progress);
  o.progress = [&watch](double f) { watch(f); };
  o.cancel = &watch.cancel;
  Mesh m;
  try {
    py::gil_scoped_release unlocked;
    m = session ? session->mesh(tree, o) : tree.mesh(o);
  } catch (const CancelledError&) {
    if (watch.stop) std::rethrow_exception(watch.stop);
    throw;
  }
  if (watch.stop) std::rethrow_exception(watch.stop);
  py::dict stats = py::module_::import("json").attr("loads")(m.stats.json);
  stats["root_strategy"] = m.stats.root_strategy;
  return py::make_tuple(to_numpy(std::move(m.vertices), 3), to_numpy(std::move(m.triangles), 3), stats);
}

py::tuple mesh(const Tree& tree, double precision, const std::string& strategy, int threads,
               double memory_budget_gib, bool sharp_features, bool quality, py::object progress) {
  return mesh_in(nullptr, tree, precision, strategy, threads, memory_budget_gib, sharp_features, quality,
                 std::move(progress));
}

py::tuple session_mesh(Session& session, const Tree& tree, double precision, const std::string& strategy,
                       int threads, double memory_budget_gib, bool sharp_features, bool quality,
                       py::object progress) {
  return mesh_in(&session, tree, precision, strategy, threads, memory_budget_gib, sharp_features, quality,
                 std::move(progress));
}

void write_arrays(const std::string& file, const py::handle& vertices, const py::handle& triangles) {
  const auto v = points_arg(vertices, "vertices");
  const auto t = indices_arg(triangles, "triangles");
  py::gil_scoped_release unlocked;
  write_mesh(v.xyz, t.ijk, file);
}

void bind_tree(py::module_& m) {
  py::class_<Tree>(m, "Tree", "An immutable HybridTree: evaluate its field, mesh its surface. Thread-safe.")
      .def_property_readonly("threshold", &Tree::threshold, "T: the surface is {field = T}")
      .def("to_json", &Tree::to_json, py::arg("scene_dir") = ".",
           "The tree as scene format v1 JSON text (mesh files relative to scene_dir)")
      .def_property_readonly("bounds", &Tree::bounds, "(lo x, lo y, lo z, hi x, hi y, hi z): the field is 0 outside")
      .def("field", &field, py::arg("points"), py::kw_only(), py::arg("threads") = 0,
           "The field at an (N, 3) float64 or float32 array of points, as an (N,) float64 array")
      .def("gradient", &gradient, py::arg("points"), py::kw_only(), py::arg("threads") = 0,
           "The gradient at an (N, 3) array of points, as an (N, 3) float64 array")
      .def("mesh", &mesh, py::kw_only(), py::arg("precision") = 0.0, py::arg("strategy") = "scene",
           py::arg("threads") = 0, py::arg("memory_budget_gib") = 4.0, py::arg("sharp_features") = true,
           py::arg("quality") = true, py::arg("progress") = py::none(),
           "(vertices (V, 3) float64, triangles (T, 3) uint32, statistics dict) of the surface");
}

void bind_session(py::module_& m) {
  py::class_<Session>(m, "Session",
                      "Keeps node results across mesh calls (bounded, LRU): re-meshing an edited tree runs only "
                      "the jobs whose subtree changed; the mesh is the same as Tree.mesh's. Thread-safe.")
      .def(py::init([](std::size_t cache_bytes, const py::object& folder, std::uint64_t folder_bytes) {
             if (folder.is_none()) return std::make_unique<Session>(cache_bytes);
             // str, bytes or any os.PathLike (pathlib.Path)
             const py::object path = py::module_::import("os").attr("fsdecode")(folder);
             return std::make_unique<Session>(cache_bytes, path.cast<std::string>(), folder_bytes);
           }),
           py::arg("cache_bytes") = std::size_t(1) << 30, py::kw_only(), py::arg("folder") = py::none(),
           py::arg("folder_bytes") = std::uint64_t(1) << 30,
           "folder: a cache folder on disk as `hybridtree mesh --cache` keeps, shared with other sessions and "
           "processes (made if missing); folder_bytes bounds it after each mesh")
      .def("mesh", &session_mesh, py::arg("tree"), py::kw_only(), py::arg("precision") = 0.0,
           py::arg("strategy") = "scene", py::arg("threads") = 0, py::arg("memory_budget_gib") = 4.0,
           py::arg("sharp_features") = true, py::arg("quality") = true, py::arg("progress") = py::none(),
           "As Tree.mesh, with the session's cache; statistics[\"cache\"] has hits, misses, reused_nodes")
      .def_property_readonly("cache_bytes", &Session::cache_bytes, "bytes the cache holds now")
      .def_property_readonly("cache_entries", &Session::cache_entries, "entries the cache holds now")
      .def("clear", &Session::clear, "Empty the cache in memory (not the folder)");
}

}  // namespace

void bind_builder(py::module_& m);  // tools/python/builder.cpp

PYBIND11_MODULE(hybridtree, m) {
  m.doc() = "HybridTree: hybrid implicit/mesh modeling (Allegre et al. 2004). See README.md, \"Python\".";
  m.attr("__version__") = version();
  register_errors(m);
  bind_tree(m);
  bind_session(m);
  m.def("load", &Tree::load, py::arg("file"), "Load a scene file (JSON); mesh paths are relative to its folder");
  m.def("loads", &Tree::from_json, py::arg("text"), py::arg("base_dir") = ".", py::arg("source") = "<text>",
        "Load a scene from JSON text");
  m.def("write_mesh", &write_arrays, py::arg("file"), py::arg("vertices"), py::arg("triangles"),
        "Write a mesh (.ply, .obj, .off, .stl) atomically, the bytes `hybridtree mesh` writes");
  bind_builder(m);
}
