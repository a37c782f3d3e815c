// hybridtree.Builder: the scene format's nodes from Python (runtime/api.hpp Builder). Points are
// 3-sequences, falloffs the keywords radius= and strength=, nodes the ints the calls return.
#include "tools/python/arrays.hpp"

#include <hybridtree/api.hpp>
#include <pybind11/stl.h>

namespace py = pybind11;
using namespace hybridtree;

namespace {

using Nodes = std::vector<Node>;

Axis axis_arg(const std::string& a) {
  if (a == "x") return Axis::X;
  if (a == "y") return Axis::Y;
  if (a == "z") return Axis::Z;
  throw py::value_error("axis: expected \"x\", \"y\" or \"z\", not \"" + a + "\"");
}

BooleanMode mode_arg(const std::string& m) {
  if (m == "auto") return BooleanMode::Auto;
  if (m == "minmax") return BooleanMode::MinMax;
  if (m == "rfunction") return BooleanMode::RFunction;
  throw py::value_error("boolean: expected \"auto\", \"minmax\" or \"rfunction\", not \"" + m + "\"");
}

MesherHint hint_arg(const std::string& h) {
  if (h == "auto") return MesherHint::Auto;
  if (h == "global") return MesherHint::Global;
  if (h == "local") return MesherHint::Local;
  throw py::value_error("mesher: expected \"auto\", \"global\" or \"local\", not \"" + h + "\"");
}

}  // namespace

void bind_builder(py::module_& m) {
  auto R = [] { return py::arg("radius") = 1.0; };
  auto F = [] { return py::arg("strength") = 1.0; };
  py::class_<Builder>(m, "Builder", "Builds a tree node by node; every call checks its arguments (InputError)")
      .def(py::init<double>(), py::arg("threshold") = 0.5)
      .def("point", [](Builder& b, Vec3 c, double r, double s) { return b.point(c, {r, s}); },
           py::arg("center"), py::kw_only(), R(), F())
      .def("segment", [](Builder& b, Vec3 a, Vec3 e, double r, double s) { return b.segment(a, e, {r, s}); },
           py::arg("a"), py::arg("b"), py::kw_only(), R(), F())
      .def("circle", [](Builder& b, Vec3 c, Vec3 n, double cr, double r, double s) { return b.circle(c, n, cr, {r, s}); },
           py::arg("center"), py::arg("normal"), py::arg("circle_radius"), py::kw_only(), R(), F())
      .def("disc", [](Builder& b, Vec3 c, Vec3 n, double dr, double r, double s) { return b.disc(c, n, dr, {r, s}); },
           py::arg("center"), py::arg("normal"), py::arg("disc_radius"), py::kw_only(), R(), F())
      .def("triangle", [](Builder& b, Vec3 p, Vec3 q, Vec3 t, double r, double s) { return b.triangle(p, q, t, {r, s}); },
           py::arg("a"), py::arg("b"), py::arg("c"), py::kw_only(), R(), F())
      .def("curve", [](Builder& b, const py::handle& points, double r, double s) {
             const auto p = python::points_arg(points, "points");
             return b.curve(p.xyz, {r, s});
           }, py::arg("points"), py::kw_only(), R(), F())
      .def("box", [](Builder& b, Vec3 lo, Vec3 hi, double r, double s) { return b.box(lo, hi, {r, s}); },
           py::arg("min"), py::arg("max"), py::kw_only(), R(), F())
      .def("cylinder", [](Builder& b, Vec3 p, Vec3 q, double cr, double r, double s) { return b.cylinder(p, q, cr, {r, s}); },
           py::arg("a"), py::arg("b"), py::arg("cylinder_radius"), py::kw_only(), R(), F())
      .def("cone_sphere", [](Builder& b, Vec3 p, Vec3 q, double ra, double rb, double r, double s) {
             return b.cone_sphere(p, q, ra, rb, {r, s});
           }, py::arg("a"), py::arg("b"), py::arg("radius_a"), py::arg("radius_b"), py::kw_only(), R(), F())
      .def("mesh", [](Builder& b, const std::string& file, double r, double s, bool repair, bool winding) {
             return b.mesh(file, {r, s}, repair, winding);
           }, py::arg("file"), py::kw_only(), R(), F(), py::arg("repair") = false, py::arg("winding") = false)
      .def("blend", [](Builder& b, const Nodes& c) { return b.blend(c); }, py::arg("children"))
      .def("unite", [](Builder& b, const Nodes& c, const std::string& mode) { return b.unite(c, mode_arg(mode)); },
           py::arg("children"), py::kw_only(), py::arg("boolean") = "auto")
      .def("intersect", [](Builder& b, const Nodes& c, const std::string& mode) { return b.intersect(c, mode_arg(mode)); },
           py::arg("children"), py::kw_only(), py::arg("boolean") = "auto")
      .def("subtract", [](Builder& b, const Nodes& c, const std::string& mode) { return b.subtract(c, mode_arg(mode)); },
           py::arg("children"), py::kw_only(), py::arg("boolean") = "auto")
      .def("local_blend", [](Builder& b, Node a, Node c, Node r, const std::string& mode) {
             return b.local_blend(a, c, r, mode_arg(mode));
           }, py::arg("a"), py::arg("b"), py::arg("region"), py::kw_only(), py::arg("boolean") = "auto")
      .def("crop", &Builder::crop, py::arg("child"), py::arg("min"), py::arg("max"))
      .def("affine", &Builder::affine, py::arg("child"), py::arg("forward"),
           "forward: the 16 numbers of the 4 x 4 map, row by row")
      .def("twist", [](Builder& b, Node c, const std::string& a, Vec3 o, double rate) { return b.twist(c, axis_arg(a), o, rate); },
           py::arg("child"), py::arg("axis"), py::arg("center"), py::arg("rate"))
      .def("taper", [](Builder& b, Node c, const std::string& a, Vec3 o, double h0, double h1, double s0, double s1) {
             return b.taper(c, axis_arg(a), o, h0, h1, s0, s1);
           }, py::arg("child"), py::arg("axis"), py::arg("center"), py::arg("h0"), py::arg("h1"), py::arg("s0"), py::arg("s1"))
      .def("bend", [](Builder& b, Node c, const std::string& a, Vec3 o, double h0, double h1, double rate) {
             return b.bend(c, axis_arg(a), o, h0, h1, rate);
           }, py::arg("child"), py::arg("axis"), py::arg("center"), py::arg("h0"), py::arg("h1"), py::arg("rate"))
      .def("ffd", [](Builder& b, Node c, Vec3 lo, Vec3 hi, std::array<int, 3> dims, const py::handle& points, double r,
                     double s) {
             const auto p = python::points_arg(points, "points");
             return b.ffd(c, lo, hi, dims, p.xyz, {r, s});
           }, py::arg("child"), py::arg("min"), py::arg("max"), py::arg("dims"), py::arg("points"), py::kw_only(), R(), F(),
           "Free-form deformation: (l+1)(m+1)(n+1) control points, x fastest")
      .def("set_name", &Builder::set_name, py::arg("node"), py::arg("name"))
      .def("set_mesher", [](Builder& b, Node n, const std::string& h) { b.set_mesher(n, hint_arg(h)); }, py::arg("node"),
           py::arg("hint"), "\"auto\", \"global\" or \"local\"")
      .def("build", &Builder::build, py::arg("root"), "The tree rooted at `root`");
}
