// OpenMesh IO from many threads: meshers/mesh_io.hpp's writes and MeshLeaf::load's reads take
// the one lock of nodes/openmesh_io.hpp, and meshes written and read concurrently come back
// whole and correct.
#include "meshers/mesh_io.hpp"
#include "nodes/mesh_leaf.hpp"
#include "nodes/openmesh_io.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include <array>
#include <chrono>
#include <fstream>
#include <sstream>
#include <future>
#include <latch>
#include <string>
#include <thread>
#include <vector>

namespace ht {
namespace {

// A closed octahedron of the given size around `centre`, counter-clockwise from outside.
TriangleMesh octahedron(const glm::dvec3& centre, double size) {
  TriangleMesh m;
  for (const glm::dvec3& d : {glm::dvec3(1, 0, 0), glm::dvec3(-1, 0, 0), glm::dvec3(0, 1, 0),
                              glm::dvec3(0, -1, 0), glm::dvec3(0, 0, 1), glm::dvec3(0, 0, -1)})
    m.positions.push_back(centre + size * d);
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  return m;
}

// Empty when the leaf holds the same octahedron (positions to float precision, any order), else
// what differs.
std::string compare(const MeshLeaf& leaf, const TriangleMesh& written) {
  if (leaf.report().triangles != written.triangles.size())
    return std::to_string(leaf.report().triangles) + " triangles";
  if (leaf.positions().size() != written.positions.size())
    return std::to_string(leaf.positions().size()) + " vertices";
  for (const glm::dvec3& p : written.positions) {
    bool found = false;
    for (const glm::dvec3& q : leaf.positions()) found = found || glm::length(p - q) < 1e-5;
    if (!found) return "a vertex moved";
  }
  return {};
}

// OFF and OBJ keep every bit of the doubles, read back as doubles (our own mesh leaves read
// coordinates as floats, as OpenMesh did; other tools read them whole). OpenMesh's writer
// rounded them to float first: 0.45420201894740647 came out as 0.45420202612876892.
TEST(MeshIo, TextFormatsKeepEveryBit) {
  const auto dir = test::temp_dir("mesh-io-bits");
  TriangleMesh m = octahedron(glm::dvec3(0.1, 1.0 / 3.0, -0.2646415), 0.7);
  m.positions[0].x += 1e-13;  // a bit a float cannot hold
  for (const char* name : {"m.off", "m.obj"}) {
    write_mesh(m, dir / name);
    std::ifstream in(dir / name);
    std::string line;
    std::vector<glm::dvec3> read;
    std::vector<glm::uvec3> faces;
    const bool off = std::string(name) == "m.off";
    for (int n = 0; std::getline(in, line); ++n) {
      std::istringstream words(line);
      std::string tag;
      if (off && n < 2) continue;  // "OFF", then the counts
      if (!off) words >> tag;
      if (off ? read.size() < m.positions.size() : tag == "v") {
        glm::dvec3 p;
        words >> p.x >> p.y >> p.z;
        read.push_back(p);
      } else {
        unsigned k = 0;
        glm::uvec3 t;
        if (off) words >> k;
        words >> t[0] >> t[1] >> t[2];
        faces.push_back(off ? t : t - glm::uvec3(1));
      }
    }
    EXPECT_EQ(read, m.positions) << name;
    EXPECT_EQ(faces, m.triangles) << name;
  }
  std::filesystem::remove_all(dir);
}

TEST(MeshIoThreads, ConcurrentWritesAndLoadsComeBackWhole) {
  const auto dir = test::temp_dir("mesh-io-threads");
  constexpr int kThreads = 8;
  constexpr int kRounds = 20;
  const std::array<const char*, 4> extensions = {".off", ".obj", ".ply", ".stl"};
  std::latch start(kThreads);
  std::vector<std::vector<std::string>> failures(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      start.arrive_and_wait();  // every thread in its first write at once
      for (int r = 0; r < kRounds; ++r) {
        const auto file = dir / (std::to_string(t) + extensions[(t + r) % extensions.size()]);
        const glm::dvec3 centre(t, r, 0.5 * t - r);
        const TriangleMesh mesh = octahedron(centre, 1.0 + 0.25 * t);
        try {
          write_mesh(mesh, file);
          const auto leaf = MeshLeaf::load(file);
          std::string what = compare(*leaf, mesh);
          if (what.empty() && (!leaf->inside(centre) || leaf->inside(centre + glm::dvec3(0, 0, 3.0 + t))))
            what = "wrong inside test";
          if (!what.empty()) failures[t].push_back(file.filename().string() + ": " + what);
        } catch (const std::exception& e) {
          failures[t].push_back(e.what());
        }
      }
    });
  }
  for (auto& th : threads) th.join();
  for (int t = 0; t < kThreads; ++t) EXPECT_TRUE(failures[t].empty()) << "thread " << t << ": " << failures[t].front();
  std::filesystem::remove_all(dir);
}

// While the shared lock is held elsewhere, neither a write nor a load may reach OpenMesh: both
// wait for it, so they are serialised against each other and against any other OpenMesh IO. Both
// are of PLY: OFF is read and written without OpenMesh (nodes/mesh_text.hpp, write_text) and
// takes no lock.
TEST(MeshIoThreads, WritesAndLoadsWaitForTheOneLock) {
  const auto dir = test::temp_dir("mesh-io-lock");
  const TriangleMesh mesh = octahedron(glm::dvec3(0.0), 1.0);
  write_mesh(mesh, dir / "ready.ply");
  std::unique_lock lock(openmesh_io_mutex());
  auto write = std::async(std::launch::async, [&] { write_mesh(mesh, dir / "written.ply"); });
  auto load = std::async(std::launch::async, [&] { return MeshLeaf::load(dir / "ready.ply"); });
  EXPECT_EQ(write.wait_for(std::chrono::milliseconds(300)), std::future_status::timeout);
  EXPECT_EQ(load.wait_for(std::chrono::milliseconds(0)), std::future_status::timeout);
  lock.unlock();
  write.get();
  EXPECT_EQ(compare(*load.get(), mesh), "");
  EXPECT_EQ(compare(*MeshLeaf::load(dir / "written.ply"), mesh), "");
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace ht
