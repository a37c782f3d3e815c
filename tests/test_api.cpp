// The embedding API (runtime/api.hpp): the same values as the library's tape, many threads on
// one shared tree giving the single-thread results, meshes the same at any thread count, and one
// error hierarchy carrying the file and JSON path.
#include "runtime/api.hpp"

#include "runtime/scene.hpp"
#include "tests/support/test_support.hpp"
#include "tools/scenes.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <atomic>
#include <cstring>
#include <filesystem>
#include <random>
#include <thread>
#include <vector>

namespace {

const std::string kGarden = std::string(HYBRIDTREE_SOURCE_DIR) + "/examples/bunny_garden.json";

std::vector<double> random_points(std::size_t n, double extent, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-extent, extent);
  std::vector<double> xyz(3 * n);
  for (double& x : xyz) x = u(rng);
  return xyz;
}

TEST(Api, FieldAndGradientAreTheLibrarysTape) {
  const hybridtree::Tree api = hybridtree::Tree::load(kGarden);
  const ht::Tree tree = ht::load_scene(kGarden);
  const std::vector<double> xyz = random_points(5000, 1.0, 1);
  const std::span<const glm::dvec3> p(reinterpret_cast<const glm::dvec3*>(xyz.data()), xyz.size() / 3);
  std::vector<double> want(p.size()), got(p.size()), got_values(p.size()), got_grad(xyz.size());
  std::vector<glm::dvec3> want_grad(p.size());
  tree.field(p, want);
  api.field(xyz, got);
  EXPECT_EQ(got, want);
  tree.gradient(p, want_grad);
  api.gradient(xyz, got_grad, got_values);
  EXPECT_EQ(got_values, want);
  for (std::size_t i = 0; i < p.size(); ++i)
    for (int k = 0; k < 3; ++k) ASSERT_EQ(got_grad[3 * i + std::size_t(k)], want_grad[i][k]) << i;
}

// The contract of the header: any number of threads on one tree, no locking, the same results.
TEST(Api, ManyThreadsOnOneTreeGiveTheSingleThreadResults) {
  const hybridtree::Tree garden = hybridtree::Tree::load(kGarden);
  const hybridtree::Tree snake = hybridtree::Tree::from_json(ht::scenes::snake_json(60, 3), ".", "snake");
  for (const hybridtree::Tree* tree : {&garden, &snake}) {
    const std::vector<double> xyz = random_points(ht::test::kSanitized ? 2000 : 20000, 1.5, 2);
    std::vector<double> values(xyz.size() / 3), grads(xyz.size());
    tree->field(xyz, values, {.threads = 1});
    tree->gradient(xyz, grads, {}, {.threads = 1});
    std::atomic<int> mismatches{0};
    std::vector<std::thread> callers;
    for (int t = 0; t < 8; ++t)
      callers.emplace_back([&, t] {
        std::vector<double> v(values.size()), g(grads.size());
        for (int round = 0; round < 3; ++round) {
          tree->field(xyz, v, {.threads = t % 3});  // all cores, one, two
          tree->gradient(xyz, g, {}, {.threads = t % 3});
          if (v != values || g != grads) ++mismatches;
        }
      });
    for (std::thread& c : callers) c.join();
    EXPECT_EQ(mismatches.load(), 0);
  }
}

TEST(Api, MeshIsTheSameAtAnyThreadCountAndFromThreadsAtOnce) {
  const hybridtree::Tree tree = hybridtree::Tree::load(kGarden);
  hybridtree::MeshOptions o;
  o.precision = 0.05;
  o.threads = 1;
  const hybridtree::Mesh one = tree.mesh(o);
  EXPECT_TRUE(one.stats.watertight);
  EXPECT_EQ(one.stats.triangles * 3, one.triangles.size());
  EXPECT_EQ(one.stats.precision, 0.05);
  EXPECT_NE(one.stats.json.find("\"checks\""), std::string::npos);
  std::vector<hybridtree::Mesh> runs(2);
  std::vector<std::thread> callers;
  for (int i = 0; i < 2; ++i)
    callers.emplace_back([&, i] {
      hybridtree::MeshOptions p = o;
      p.threads = 2 * i;  // two, all cores; both at once
      runs[std::size_t(i)] = tree.mesh(p);
    });
  for (std::thread& c : callers) c.join();
  for (const hybridtree::Mesh& m : runs) {
    EXPECT_EQ(m.vertices, one.vertices);
    EXPECT_EQ(m.triangles, one.triangles);
  }
}

template <class E, class F>
E caught(F&& f) {
  try {
    f();
  } catch (const E& e) {
    return e;
  }
  ADD_FAILURE() << "nothing thrown";
  return E("", "", "");
}

TEST(Api, ErrorsCarryTheFileAndThePath) {
  const auto dir = ht::test::temp_dir("api_errors");
  ht::test::write_file(dir / "bad.json", R"({"hybridtree": 1, "root": {"type": "point", "center": [0, 0, 0], "radius": -1}})");
  const auto scene = caught<hybridtree::SceneError>([&] { hybridtree::Tree::load((dir / "bad.json").string()); });
  EXPECT_EQ(std::string(scene.what()), (dir / "bad.json").string() + ": root.radius: must be > 0");
  EXPECT_EQ(scene.file(), (dir / "bad.json").string());
  EXPECT_EQ(scene.path(), "root.radius");
  const auto missing = caught<hybridtree::SceneError>([&] { hybridtree::Tree::load((dir / "none.json").string()); });
  EXPECT_EQ(missing.file(), (dir / "none.json").string());
  EXPECT_EQ(missing.path(), "");
  EXPECT_THROW(hybridtree::Tree::load((dir / "none.json").string()), hybridtree::Error);

  const hybridtree::Tree tree = hybridtree::Tree::load(kGarden);
  std::vector<double> xyz = {0, 0, 0, 1, std::nan(""), 0}, values(2), two(3);
  const auto nan = caught<hybridtree::InputError>([&] { tree.field(xyz, values); });
  EXPECT_EQ(std::string(nan.what()), "points[1]: coordinate 1 is not a finite number");
  EXPECT_EQ(nan.path(), "points[1]");
  xyz[4] = 0;
  caught<hybridtree::InputError>([&] { tree.field(xyz, two); });
  caught<hybridtree::InputError>([&] { tree.field(std::span<const double>(xyz).first(4), values); });
  hybridtree::MeshOptions negative;
  negative.precision = -1;
  caught<hybridtree::InputError>([&] { tree.mesh(negative); });
  hybridtree::MeshOptions coarse;  // coarser than the whole garden: nothing could be resolved
  coarse.precision = 1e6;
  const auto too_coarse = caught<hybridtree::MeshingError>([&] { tree.mesh(coarse); });
  EXPECT_NE(std::string(too_coarse.what()).find("coarser than the whole scene"), std::string::npos) << too_coarse.what();
  hybridtree::MeshOptions tight;
  tight.precision = 0.002;
  tight.memory_budget_gib = 1e-3;
  EXPECT_THROW(tree.mesh(tight), hybridtree::MemoryBudgetError);
  const auto budget = caught<hybridtree::MeshingError>([&] { tree.mesh(tight); });
  EXPECT_EQ(budget.file(), kGarden);
  std::atomic<bool> stop{true};
  hybridtree::MeshOptions cancelled;
  cancelled.precision = 0.05;
  cancelled.cancel = &stop;
  caught<hybridtree::CancelledError>([&] { tree.mesh(cancelled); });

  hybridtree::Builder b;
  const auto key = caught<hybridtree::InputError>([&] { b.point({0, 0, 0}, {.radius = 0}); });
  EXPECT_EQ(std::string(key.what()), "radius: must be > 0");
  EXPECT_EQ(key.path(), "radius");
  const std::vector<hybridtree::Node> none = {42};
  caught<hybridtree::InputError>([&] { b.blend(none); });

  const std::vector<double> v = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::vector<std::uint32_t> t = {0, 1, 2};
  caught<hybridtree::InputError>([&] { hybridtree::write_mesh(v, t, (dir / "a.xyz").string()); });
  caught<hybridtree::WriteError>([&] { hybridtree::write_mesh(v, t, (dir / "no" / "a.ply").string()); });
}

}  // namespace

TEST(Api, SessionReusesUnchangedJobsAndGivesTheSameMesh) {
  auto scene = [](double radius) {
    hybridtree::Builder b;
    const auto left = b.segment({-1, 0, 0}, {0, 0, 0}, {0.5, 1.0});
    const auto right = b.segment({0.6, 0, 0}, {1.6, 0, 0}, {radius, 1.0});
    b.set_name(right, "right");
    const std::vector<hybridtree::Node> both = {left, right};
    return b.build(b.unite(both));
  };
  hybridtree::MeshOptions o;
  o.precision = 0.05;
  hybridtree::Session session(64u << 20);
  const hybridtree::Mesh first = session.mesh(scene(0.5), o);
  EXPECT_TRUE(first.stats.reused_nodes.empty());
  EXPECT_GT(first.stats.cache_misses, 0u);
  const hybridtree::Tree edited = scene(0.55);
  const hybridtree::Mesh again = session.mesh(edited, o);
  const hybridtree::Mesh scratch = edited.mesh(o);
  ASSERT_FALSE(again.stats.reused_nodes.empty());
  for (const std::string& n : again.stats.reused_nodes) EXPECT_NE(n, "right");
  EXPECT_EQ(again.triangles, scratch.triangles);
  ASSERT_EQ(again.vertices.size(), scratch.vertices.size());
  EXPECT_EQ(std::memcmp(again.vertices.data(), scratch.vertices.data(), 8 * again.vertices.size()), 0);
  EXPECT_NE(again.stats.json.find("\"cache\""), std::string::npos);
  EXPECT_GT(session.cache_entries(), 0u);
}

TEST(Api, SessionsOverOneFolderShareTheirResultsAcrossSessions) {
  // Two sessions over one folder, as two processes would be: the second takes every job of the
  // first from disk, and an edit inside the snake's global job takes its unchanged bricks.
  const std::filesystem::path dir = ht::test::temp_dir("api_folder");
  const std::string text = ht::scenes::snake_json(40, 3);
  std::size_t at = 0;
  for (int i = 0; i <= 20; ++i) at = text.find("\"points\": [[", at + 1);
  std::string moved = text;  // curve 20's first point moved by 0.01 in x
  {
    char* end = nullptr;
    const double x = std::strtod(text.c_str() + at + 12, &end);
    moved.replace(at + 12, std::size_t(end - (text.c_str() + at + 12)), std::to_string(x + 0.01));
  }
  const hybridtree::Tree before = hybridtree::Tree::from_json(text), after = hybridtree::Tree::from_json(moved);
  hybridtree::MeshOptions o;
  o.precision = 0.2;
  {
    hybridtree::Session first(64u << 20, (dir / "cache").string());
    EXPECT_TRUE(first.mesh(before, o).stats.reused_nodes.empty());
  }
  hybridtree::Session second(64u << 20, (dir / "cache").string());
  const hybridtree::Mesh same = second.mesh(before, o);
  EXPECT_EQ(same.stats.cache_misses, 0u);
  EXPECT_FALSE(same.stats.reused_nodes.empty());
  hybridtree::Session third(64u << 20, (dir / "cache").string());
  const hybridtree::Mesh edited = third.mesh(after, o);
  const hybridtree::Mesh scratch = after.mesh(o);
  EXPECT_EQ(edited.triangles, scratch.triangles);
  ASSERT_EQ(edited.vertices.size(), scratch.vertices.size());
  EXPECT_EQ(std::memcmp(edited.vertices.data(), scratch.vertices.data(), 8 * edited.vertices.size()), 0);
  const auto json = nlohmann::json::parse(edited.stats.json);
  EXPECT_GT(json["cache"]["disk"]["parts"]["hits"].get<int>(), 0) << json["cache"].dump();
  ht::test::write_file(dir / "a_file", "x");
  EXPECT_THROW(hybridtree::Session(1u << 20, (dir / "a_file").string()), hybridtree::InputError);
  std::filesystem::remove_all(dir);
}
