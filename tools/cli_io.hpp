// What the command-line tool reads and writes besides scenes and meshes: points as text lines or
// .npy, rows of numbers as text, and files written whole or not at all.
#pragma once

#include "runtime/tree.hpp"
#include "tools/npy.hpp"

#include <glm/vec3.hpp>

#include <istream>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace ht::cli {

/// Bad input from the user (a points file, an argument, an output path): the CLI prints the
/// message, which starts with the file or stream it is about, and exits with status 2.
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Points as text: whitespace-separated x y z, one point per line; blank lines and '#' comments
/// skipped. Throws InputError naming `source` and the line for anything else, NaN and infinities
/// included.
std::vector<glm::dvec3> read_text_points(std::istream& in, const std::string& source);

/// Points from `file`: .npy (npy::read_points, which throws npy::Error) or text; empty or "-" is
/// text on stdin. Text points report Dtype::Float32, the precision the tape evaluates in.
npy::Points read_points(const std::string& file);

/// Rows of `columns` numbers, space-separated, one row per line, 9 significant digits (which
/// give back a float exactly). table.size() is a multiple of columns.
std::string format_rows(std::span<const double> table, std::size_t columns);

/// Writes `bytes` to a temporary file beside `file`, then renames it into place, so a failure
/// never leaves a half-written `file` (nor the temporary). Throws InputError naming `file` and
/// `what` ("stats file") when the folder is missing or not writable.
void write_file_atomically(const std::string& file, std::string_view bytes, const std::string& what);

}  // namespace ht::cli
