// NumPy .npy files for `hybridtree eval`: points in, values (and gradients) out, so that a
// pipeline can pass millions of points without printing and parsing decimal text.
//
// Read: format 1.0 or 2.0, dtype '<f4' (float32) or '<f8' (float64), C order, shape (N, 3).
// Written: format 1.0, the same dtypes, C order, shape (N,) or (N, columns). The header is
// padded so that the data starts at a multiple of 64 bytes, as numpy.save does.
// The format: https://numpy.org/doc/stable/reference/generated/numpy.lib.format.html
//
// Everything here is a plain function of its arguments: safe to call from several threads.
#pragma once

#include <glm/vec3.hpp>

#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace ht::npy {

/// A file that cannot be read, or is not an .npy array of the kind asked for. The message
/// starts with the file's name and says what is wrong ("pts.npy: shape (4, 2) is not (N, 3)").
struct Error : std::runtime_error {
  using std::runtime_error::runtime_error;
};

enum class Dtype : std::uint8_t { Float32, Float64 };

/// "<f4" or "<f8", as the header spells it.
const char* descr(Dtype dtype);

/// Whether `path` ends in ".npy" (any case): the CLI picks the format by extension.
bool has_npy_extension(std::string_view path);

struct Points {
  std::vector<glm::dvec3> points;
  Dtype dtype = Dtype::Float64;  ///< what the file held (float32 coordinates are exact in double)
};

/// Reads an (N, 3) array from `file`. Throws Error for a file that cannot be opened, a bad magic
/// string, a format version other than 1.0 and 2.0, a header that does not parse, a dtype other
/// than '<f4' and '<f8', fortran_order True, a shape other than (N, 3), data shorter or longer
/// than the shape says, and any coordinate that is NaN or infinite (as the text reader does).
Points read_points(const std::string& file);

/// The bytes of a format 1.0 file holding `data` as rows of `columns` values (row-major),
/// converted to `dtype`; columns == 1 gives shape (rows,). data.size() must be a multiple of
/// columns (std::invalid_argument otherwise). Large arrays are converted in parallel (TBB).
std::string encode(Dtype dtype, std::span<const double> data, std::size_t columns);

}  // namespace ht::npy
