#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <array>
#include <cmath>
#include <map>
#include <utility>
#include <vector>
#include <atomic>
#include <cstdio>
#include <cstring>
#include <exception>
#include <fstream>
#include <pthread.h>
#include <sstream>
#include <system_error>
#include <sys/wait.h>
#include <unistd.h>

namespace ht::test {

std::filesystem::path cgal_mesh(const std::string& name) {
  auto p = std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / "data" / "meshes" / name;
  if (!std::filesystem::exists(p))
    ADD_FAILURE() << p << " is missing: run tools/setup.sh to extract the libcgal-demo meshes";
  return p;
}

std::filesystem::path shared_mesh(const std::string& name) {
  auto p = std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / ".." / "shared" / "data" / "meshes" / name;
  return std::filesystem::exists(p) ? p : std::filesystem::path();
}

bool igea_available() {
  return std::filesystem::exists(std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / "data/meshes/igea-67k.ply") ||
         !shared_mesh("igea-67k.ply").empty();
}

std::filesystem::path temp_dir(const std::string& tag) {
  auto p = std::filesystem::temp_directory_path() / ("hybridtree-test-" + tag + "-" +
                                                     std::to_string(::getpid()));
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p;
}

void write_file(const std::filesystem::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary);
  out << text;
}

std::string read_file(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

bool same_bytes(const TriangleMesh& a, const TriangleMesh& b) {
  // memcmp is not called on empty arrays (their data() may be null).
  return a.positions.size() == b.positions.size() && a.triangles == b.triangles &&
         (a.positions.empty() ||
          std::memcmp(a.positions.data(), b.positions.data(), a.positions.size() * sizeof(glm::dvec3)) == 0);
}

CliResult run_cli(const std::string& args, const std::string& input) {
  static std::atomic<int> calls{0};  // a folder per call: calls from several threads at once
  auto dir = temp_dir("cli-" + std::to_string(calls++));
  write_file(dir / "stdin", input);
  std::string cmd = std::string("'") + HYBRIDTREE_CLI + "' " + args + " < '" + (dir / "stdin").string() +
                    "' > '" + (dir / "stdout").string() + "' 2> '" + (dir / "stderr").string() + "'";
  int status = std::system(cmd.c_str());
  CliResult r{WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status), read_file(dir / "stdout"),
              read_file(dir / "stderr")};
  std::filesystem::remove_all(dir);
  return r;
}

Rng seeded() {
  std::uint64_t h = 1469598103934665603ull;
  for (const char* s = ::testing::UnitTest::GetInstance()->current_test_info()->name(); *s; ++s)
    h = (h ^ static_cast<unsigned char>(*s)) * 1099511628211ull;
  return Rng(h);
}

MeshOptions mesh_options(double h, MeshStrategy s) {
  MeshOptions o;
  o.precision = h;
  o.strategy = s;
  return o;
}

Polygonized polygonize_checked(const Tree& tree, const PolygonizeOptions& options) {
  Polygonized r;
  r.mesh = polygonize(tree.graph_ptr(), tree.root(), tree.threshold(), options, &r.stats);
  r.checks = check_mesh(r.mesh);
  if (!r.mesh.triangles.empty()) measure_surface_error(r.mesh, tree.evaluator(), tree.threshold(), r.checks);
  return r;
}

MeshChecks checks_with_surface(const MeshResult& r, double threshold) {
  MeshChecks c = check_mesh(*r.mesh);
  if (!r.mesh->triangles.empty()) measure_surface_error(*r.mesh, r.tree->evaluator(), threshold, c);
  return c;
}

void run_on_stack(std::size_t bytes, const std::function<void()>& fn) {
  struct Job {
    const std::function<void()>* fn;
    std::exception_ptr error;
  } job{&fn, nullptr};
  pthread_attr_t attr;
  pthread_attr_init(&attr);
  pthread_attr_setstacksize(&attr, bytes);
  pthread_t thread;
  const int rc = pthread_create(
      &thread, &attr,
      [](void* p) -> void* {
        auto* j = static_cast<Job*>(p);
        try {
          (*j->fn)();
        } catch (...) {
          j->error = std::current_exception();
        }
        return nullptr;
      },
      &job);
  pthread_attr_destroy(&attr);
  if (rc != 0) throw std::system_error(rc, std::generic_category(), "pthread_create");
  pthread_join(thread, nullptr);
  if (job.error) std::rethrow_exception(job.error);
}

TriangleMesh icosphere(int levels, double radius, glm::dvec3 centre) {
  const double g = (1 + std::sqrt(5.0)) / 2;
  TriangleMesh m;
  m.positions = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                 {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},   {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (auto& p : m.positions) p = glm::normalize(p);
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<unsigned, unsigned>, unsigned> mid;
    auto midpoint = [&](unsigned a, unsigned b) {
      const auto key = std::minmax(a, b);
      auto [it, fresh] = mid.try_emplace(key, static_cast<unsigned>(m.positions.size()));
      if (fresh) m.positions.push_back(glm::normalize(m.positions[a] + m.positions[b]));
      return it->second;
    };
    std::vector<glm::uvec3> next;
    for (const auto& t : m.triangles) {
      const unsigned a = midpoint(t[0], t[1]), b = midpoint(t[1], t[2]), c = midpoint(t[2], t[0]);
      next.insert(next.end(), {{t[0], a, c}, {t[1], b, a}, {t[2], c, b}, {a, b, c}});
    }
    m.triangles = std::move(next);
  }
  for (auto& p : m.positions) p = centre + radius * p;
  return m;
}

}  // namespace ht::test
