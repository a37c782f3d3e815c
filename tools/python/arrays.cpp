#include "tools/python/arrays.hpp"

#include <limits>
#include <string>

namespace hybridtree::python {

namespace {

std::string describe(const py::handle& obj) { return py::str(py::type::handle_of(obj).attr("__name__")); }

py::array checked_array(const py::handle& obj, const char* name, const char* wanted) {
  if (!py::isinstance<py::array>(obj))
    throw py::type_error(std::string(name) + ": expected a NumPy array of shape (N, 3) and dtype " + wanted + ", not " +
                         describe(obj));
  py::array a = py::reinterpret_borrow<py::array>(obj);
  if (a.ndim() != 2 || a.shape(1) != 3) {
    std::string shape = "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i) shape += (i ? ", " : "") + std::to_string(a.shape(i));
    shape += a.ndim() == 1 ? ",)" : ")";
    throw py::value_error(std::string(name) + ": expected an array of shape (N, 3), got shape " + shape);
  }
  return a;
}

}  // namespace

Points points_arg(const py::handle& obj, const char* name) {
  py::array a = checked_array(obj, name, "float64 or float32");
  const py::dtype dt = a.dtype();
  if (dt.kind() != 'f' || (dt.itemsize() != 8 && dt.itemsize() != 4))
    throw py::type_error(std::string(name) + ": expected dtype float64 or float32, got " +
                         std::string(py::str(static_cast<py::handle>(dt))));
  Points p;
  using F64 = py::array_t<double, py::array::c_style | py::array::forcecast>;
  if (py::isinstance<F64>(a))
    p.keep = a;  // the caller's memory, read in place
  else
    p.keep = F64::ensure(a);  // a float64 copy, C-ordered
  if (!p.keep) throw py::error_already_set();
  p.n = static_cast<std::size_t>(a.shape(0));
  p.xyz = {static_cast<const double*>(p.keep.data()), 3 * p.n};
  return p;
}

Indices indices_arg(const py::handle& obj, const char* name) {
  py::array a = checked_array(obj, name, "of integers");
  if (a.dtype().kind() != 'i' && a.dtype().kind() != 'u')
    throw py::type_error(std::string(name) + ": expected an integer dtype, got " +
                         std::string(py::str(static_cast<py::handle>(a.dtype()))));
  using I64 = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
  const I64 wide = I64::ensure(a);
  if (!wide) throw py::error_already_set();
  const std::size_t count = 3 * static_cast<std::size_t>(a.shape(0));
  std::vector<std::uint32_t> out(count);
  const std::int64_t* in = wide.data();
  for (std::size_t i = 0; i < count; ++i) {
    if (in[i] < 0 || in[i] > std::numeric_limits<std::uint32_t>::max())
      throw py::value_error(std::string(name) + "[" + std::to_string(i / 3) + "]: index " + std::to_string(in[i]) +
                            " is out of range");
    out[i] = static_cast<std::uint32_t>(in[i]);
  }
  Indices r;
  r.keep = to_numpy(std::move(out), 3);
  r.ijk = {static_cast<const std::uint32_t*>(r.keep.data()), count};
  return r;
}

}  // namespace hybridtree::python
