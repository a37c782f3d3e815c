#include "tools/cli_io.hpp"

#include "meshers/mesh_io.hpp"
#include "runtime/tape.hpp"

#include <glm/geometric.hpp>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

namespace ht::cli {

std::vector<glm::dvec3> read_text_points(std::istream& in, const std::string& source) {
  std::vector<glm::dvec3> points;
  std::string line;
  std::size_t number = 0;
  while (std::getline(in, line)) {
    ++number;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream words(line);
    std::vector<std::string> tokens;
    for (std::string w; words >> w;) tokens.push_back(w);
    if (tokens.empty()) continue;
    auto where = [&] { return source + ":" + std::to_string(number) + ": "; };
    if (tokens.size() != 3)
      throw InputError(where() + "expected 3 numbers \"x y z\", found " + std::to_string(tokens.size()) + " values");
    glm::dvec3 p;
    for (int i = 0; i < 3; ++i) {
      const std::string& t = tokens[std::size_t(i)];
      char* end = nullptr;
      const double v = std::strtod(t.c_str(), &end);
      if (end == t.c_str() || *end != '\0') throw InputError(where() + "\"" + t + "\" is not a number");
      if (!std::isfinite(v)) throw InputError(where() + "\"" + t + "\" is not a finite number");
      p[i] = v;
    }
    points.push_back(p);
  }
  if (in.bad()) throw InputError(source + ": read error");
  return points;
}

npy::Points read_points(const std::string& file) {
  if (npy::has_npy_extension(file)) return npy::read_points(file);
  npy::Points in{{}, npy::Dtype::Float32};
  if (file.empty() || file == "-") {
    in.points = read_text_points(std::cin, "<stdin>");
  } else {
    std::ifstream text(file);
    if (!text) throw InputError(file + ": cannot open the points file");
    in.points = read_text_points(text, file);
  }
  return in;
}

std::string format_rows(std::span<const double> table, std::size_t columns) {
  std::string out;
  char buf[32];
  for (std::size_t i = 0; i < table.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%.9g", table[i]);
    out += buf;
    out += (i + 1) % columns == 0 ? '\n' : ' ';
  }
  return out;
}

void write_file_atomically(const std::string& requested, std::string_view bytes, const std::string& what) {
  std::string file;
  try {
    file = output_target(requested).string();
  } catch (const MeshWriteError& e) {
    throw InputError(e.what());
  }
  if (std::filesystem::is_directory(file)) throw InputError(file + ": is a folder, not a file");
  // The process id keeps two runs writing the same file from sharing a temporary.
  const std::string tmp = file + ".partial-" + std::to_string(::getpid());
  std::ofstream out(tmp, std::ios::binary);
  const bool written = out && out.write(bytes.data(), static_cast<std::streamsize>(bytes.size())) && out.flush();
  out.close();
  if (!written || std::rename(tmp.c_str(), file.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw InputError(file + (written ? ": cannot move the " + what + " into place" : ": cannot write the " + what));
  }
}

}  // namespace ht::cli
