// NumPy arrays in and out of the Python module (tools/python/module.cpp): (N, 3) points checked
// for shape and dtype and passed to the C++ API without a copy when they are C-ordered native
// float64, and C++ vectors handed to NumPy without a copy.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <span>
#include <vector>

namespace hybridtree::python {

namespace py = pybind11;

/// An (N, 3) array of floating-point numbers, as N x y z doubles. `keep` holds the memory `xyz`
/// points to: the caller's own array for C-ordered native float64 (no copy), else a float64 copy
/// (float32, other byte orders, strides). Throws TypeError for anything but a NumPy array of
/// float32 or float64, ValueError for another shape; `name` names the argument.
struct Points {
  py::array keep;
  std::span<const double> xyz;
  std::size_t n = 0;
};
Points points_arg(const py::handle& obj, const char* name);

/// An (N, 3) array of integers >= 0 (any integer dtype), as uint32 (a copy when it is not
/// already C-ordered uint32). Throws TypeError, ValueError as points_arg(), ValueError for
/// negative or too large values.
struct Indices {
  py::array keep;
  std::span<const std::uint32_t> ijk;
};
Indices indices_arg(const py::handle& obj, const char* name);

/// The vector as a NumPy array of shape (size / columns, columns) (or (size,) for columns 0),
/// owning the vector's memory: no copy.
template <class T>
py::array_t<T> to_numpy(std::vector<T>&& v, std::size_t columns) {
  auto* owned = new std::vector<T>(std::move(v));
  py::capsule free_it(owned, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  const auto size = static_cast<py::ssize_t>(owned->size());
  if (columns == 0) return py::array_t<T>({size}, owned->data(), free_it);
  const auto cols = static_cast<py::ssize_t>(columns);
  return py::array_t<T>({size / cols, cols}, owned->data(), free_it);
}

}  // namespace hybridtree::python
