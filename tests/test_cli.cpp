// The command-line tool end to end: output formats, exit codes and messages for bad input.
#include "tests/support/test_support.hpp"
#include "nodes/mesh_leaf.hpp"
#include "tools/scenes.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <map>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

using namespace ht;

namespace {

std::string write_scene(const std::filesystem::path& dir, const std::string& name, const std::string& text) {
  test::write_file(dir / name, text);
  return (dir / name).string();
}

const char* kBall = R"({"hybridtree": 1, "root": {"type": "point", "center": [0,0,0], "radius": 2}})";

}  // namespace

TEST(Cli, EvalPrintsOneValuePerPointWithNineDigits) {
  const auto dir = test::temp_dir("cli-eval");
  const std::string s = write_scene(dir, "ball.json", kBall);
  const auto r = test::run_cli("eval " + s, "0 0 0\n1 0 0\n\n# comment\n3 0 0\n");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out, "1\n0.421875\n0\n");
  const auto g = test::run_cli("eval " + s + " --gradient --engine tree", "1 0 0\n");
  ASSERT_EQ(g.code, 0) << g.err;
  std::istringstream in(g.out);
  double f, gx, gy, gz;
  in >> f >> gx >> gy >> gz;
  EXPECT_DOUBLE_EQ(f, 0.421875);
  EXPECT_NEAR(gx, -6.0 * 0.75 * 0.75 * 1.0 / 4.0, 1e-6);  // -6F(1-d²/R²)² x/R²
  EXPECT_NEAR(gy, 0.0, 1e-9);
  const auto p = test::run_cli("eval " + s + " --points " + (dir / "missing.txt").string());
  EXPECT_EQ(p.code, 2);
  EXPECT_NE(p.err.find("cannot open the points file"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(Cli, BadPointsNameTheLine) {
  const auto dir = test::temp_dir("cli-points");
  const std::string s = write_scene(dir, "ball.json", kBall);
  struct Case {
    std::string input, expected;
  };
  for (const Case& c : std::vector<Case>{{"0 0 0\n1 2\n", "<stdin>:2: expected 3 numbers"},
                                         {"0 0 0\n\n1 2 x\n", "<stdin>:3: \"x\" is not a number"},
                                         {"nan 0 0\n", "<stdin>:1: \"nan\" is not a finite number"},
                                         {"1 1 inf\n", "<stdin>:1: \"inf\" is not a finite number"},
                                         {"1 1 1e999\n", "<stdin>:1: \"1e999\" is not a finite number"},
                                         {"1 2 3 4\n", "<stdin>:1: expected 3 numbers"}}) {
    const auto r = test::run_cli("eval " + s, c.input);
    EXPECT_EQ(r.code, 2) << c.input;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << r.err;
    EXPECT_EQ(r.out, "") << "no partial output on bad input";
  }
  std::filesystem::remove_all(dir);
}

TEST(Cli, BadScenesExitTwoWithPathAndRule) {
  const auto dir = test::temp_dir("cli-scene");
  const std::string bad = write_scene(dir, "bad.json", R"({"hybridtree": 1, "root": {"type": "point", "center": [0,0,0], "radius": -1}})");
  for (const char* cmd : {"info ", "eval "}) {
    const auto r = test::run_cli(cmd + bad, "0 0 0\n");
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("bad.json: root.radius: must be > 0"), std::string::npos) << r.err;
  }
  const auto missing = test::run_cli("info " + (dir / "nope.json").string());
  EXPECT_EQ(missing.code, 2);
  EXPECT_NE(missing.err.find("cannot open the scene file"), std::string::npos);
  const auto garbage = test::run_cli("info " + write_scene(dir, "g.json", "\x01\x02garbage"));
  EXPECT_EQ(garbage.code, 2);
  EXPECT_NE(garbage.err.find("g.json: is not a scene: a scene is a JSON object, which starts with '{', and byte 0 is 0x01"),
            std::string::npos)
      << garbage.err;
  const auto broken = test::run_cli("info " + write_scene(dir, "b.json", "{\"hybridtree\": 1,"));
  EXPECT_EQ(broken.code, 2);
  EXPECT_NE(broken.err.find("not valid JSON"), std::string::npos) << broken.err;
  const auto usage = test::run_cli("frobnicate");
  EXPECT_EQ(usage.code, 2);
  std::filesystem::remove_all(dir);
}

TEST(Cli, InfoDescribesTheScene) {
  const auto dir = test::temp_dir("cli-info");
  std::filesystem::copy_file(test::cgal_mesh("eight.off"), dir / "eight.off");
  const std::string s = write_scene(dir, "s.json", R"({"hybridtree": 1, "root": {"type": "blend", "children": [
      {"type": "mesh", "file": "eight.off", "radius": 0.1},
      {"type": "twist", "rate": 1, "child": {"type": "mesh", "file": "eight.off", "radius": 0.2}},
      {"type": "segment", "a": [0,0,0], "b": [1,0,0], "radius": 0.5}]}})");
  const auto r = test::run_cli("info " + s);
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* needle : {"nodes          5 (depth 3)", "mesh         2", "634 triangles", "tree bytes", "load time",
                             "support        [", "tape           6 instructions"})
    EXPECT_NE(r.out.find(needle), std::string::npos) << needle << "\n" << r.out;
  // Loaded once: one mesh line.
  EXPECT_EQ(r.out.find("634 triangles"), r.out.rfind("634 triangles"));
  std::filesystem::remove_all(dir);
}

TEST(Cli, SnakeSceneRoundTripsThroughJson) {
  const auto dir = test::temp_dir("cli-snake");
  const std::string s = write_scene(dir, "snake.json", scenes::snake_json(250));
  const auto r = test::run_cli("info " + s);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("curve        250"), std::string::npos) << r.out;
  // The JSON and the builder give the same field.
  Builder b(0.5);
  const Tree t = b.build(scenes::snake(b, 250));
  for (const char* engine : {"tree", "tape"}) {
    const auto e = test::run_cli("eval " + s + " --engine " + engine, "1 0 0.5\n5 0.5 0\n");
    ASSERT_EQ(e.code, 0) << e.err;
    std::istringstream in(e.out);
    double f1, f2;
    in >> f1 >> f2;
    // 9 significant digits from the tree; float precision from the tape.
    const double tol = std::string(engine) == "tree" ? 1e-8 : 1e-5;
    EXPECT_NEAR(f1, t.reference({1, 0, 0.5}), tol * std::max(1.0, std::abs(f1))) << engine;
    EXPECT_NEAR(f2, t.reference({5, 0.5, 0}), tol * std::max(1.0, std::abs(f2))) << engine;
  }
  std::filesystem::remove_all(dir);
}

TEST(Cli, MeshWritesAClosedMeshAndItsStatistics) {
  const auto dir = test::temp_dir("cli-mesh");
  const std::string s = write_scene(dir, "s.json", R"({"hybridtree": 1, "mesher": {"precision": 0.05},
      "root": {"type": "blend", "children": [{"type": "point", "center": [0,0,0], "radius": 1},
                                             {"type": "segment", "a": [0,0,0], "b": [1,0,0], "radius": 0.6}]}})");
  for (const char* ext : {".off", ".ply", ".obj", ".stl"}) {
    const std::string out = (dir / (std::string("m") + ext)).string();
    const auto r = test::run_cli("mesh " + s + " -o " + out + " --stats-json " + (dir / "stats.json").string() + " --threads 1");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
    // The file reads back as a closed mesh (the mesh leaf's loader rejects anything else).
    const auto leaf = MeshLeaf::load(out);
    EXPECT_GT(leaf->report().triangles, 100u) << ext;
    EXPECT_EQ(leaf->report().components, 1u) << ext;
  }
  std::ifstream in(dir / "stats.json");
  const auto stats = nlohmann::json::parse(in);
  EXPECT_EQ(stats["checks"]["watertight"], true);
  EXPECT_EQ(stats["checks"]["genus"], 0);
  EXPECT_EQ(stats["precision"], 0.05);
  EXPECT_GT(stats["triangles"].get<int>(), 100);
  EXPECT_TRUE(stats["seconds"].contains("sample"));
  std::filesystem::remove_all(dir);
}

// A needle 2e11 long and 1 thick meshes closed at the default precision, its triangles of no
// area against its length: the summary says "NOT watertight" and stderr says why.
TEST(Cli, DegenerateTrianglesAreWarnedOf) {
  const auto dir = test::temp_dir("cli-degenerate");
  const std::string s = write_scene(dir, "s.json", R"({"hybridtree": 1, "root": {"type": "affine", "scale": [1e11, 1, 1],
      "child": {"type": "point", "center": [0,0,0], "radius": 1}}})");
  const std::string out = (dir / "m.off").string();
  const auto r = test::run_cli("mesh " + s + " -o " + out + " --threads 1");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("NOT watertight"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("degenerate triangles"), std::string::npos) << r.err;
  std::filesystem::remove_all(dir);
}

TEST(Cli, MeshRefusesCleanlyAndLeavesNoFile) {
  const auto dir = test::temp_dir("cli-mesh-bad");
  const std::string s = write_scene(dir, "s.json", kBall);
  const auto ext = test::run_cli("mesh " + s + " -o " + (dir / "m.xyz").string());
  EXPECT_EQ(ext.code, 2);
  EXPECT_NE(ext.err.find("unsupported output extension"), std::string::npos) << ext.err;
  const auto budget = test::run_cli("mesh " + s + " -o " + (dir / "m.ply").string() + " --precision 1e-6");
  EXPECT_EQ(budget.code, 2);
  EXPECT_NE(budget.err.find("need"), std::string::npos) << budget.err;  // "needs" or "would need"
  // A budget too small for the run: it stops before the stage that would pass it, and says so.
  const auto quality = test::run_cli("mesh " + s + " -o " + (dir / "m.ply").string() + " --precision 0.01 --memory-budget 0.001");
  EXPECT_EQ(quality.code, 2);
  EXPECT_NE(quality.err.find("over the memory budget"), std::string::npos) << quality.err;
  EXPECT_NE(quality.err.find("--memory-budget"), std::string::npos) << quality.err;
  // Outputs are checked before meshing, as arguments (exit 1, after the meshing, before).
  const auto folder = test::run_cli("mesh " + s + " -o " + (dir / "no" / "m.ply").string() + " --precision 0.1");
  EXPECT_EQ(folder.code, 2);
  EXPECT_NE(folder.err.find("does not exist"), std::string::npos) << folder.err;
  // Precisions that are no number, or coarser than the whole scene.
  for (const char* p : {"nan", "inf", "-0.1"}) {
    const auto bad = test::run_cli("mesh " + s + " -o " + (dir / "m.ply").string() + " --precision " + p);
    EXPECT_EQ(bad.code, 2) << p;
    EXPECT_NE(bad.err.find("must be a finite number > 0, not " + std::string(p)), std::string::npos) << bad.err;
  }
  const auto coarse = test::run_cli("mesh " + s + " -o " + (dir / "m.ply").string() + " --precision 1e9");
  EXPECT_EQ(coarse.code, 2);
  EXPECT_NE(coarse.err.find("coarser than the whole scene"), std::string::npos) << coarse.err;
  // A solid whose box underflows to a point has no precision to offer ("use at most 0" before).
  const auto point = test::run_cli("mesh " + write_scene(dir, "p.json", R"({"hybridtree": 1, "root": {"type": "point",
      "center": [0,0,0], "radius": 1e-300}})") + " -o " + (dir / "p.ply").string());
  EXPECT_EQ(point.code, 2);
  EXPECT_NE(point.err.find("lies in a box of no size"), std::string::npos) << point.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "p.ply"));
  // An estimate no integer holds is said as such, not as an overflowed count.
  const auto huge = test::run_cli("mesh " + write_scene(dir, "h.json", R"({"hybridtree": 1, "root": {"type": "point",
      "center": [0,0,0], "radius": 1e18}})") + " -o " + (dir / "m.ply").string() + " --precision 1e9");
  EXPECT_EQ(huge.code, 2);
  EXPECT_NE(huge.err.find("more than 10^15 triangles"), std::string::npos) << huge.err;
  EXPECT_EQ(huge.err.find("-9223372036854775808"), std::string::npos) << huge.err;
  // A ball moved 1e17 away, where doubles step by 16: the grid's points could not be told apart
  // and the brick classification recursed until the stack overflowed (a segmentation fault).
  const auto far = test::run_cli("mesh " + write_scene(dir, "f.json", R"({"hybridtree": 1, "root": {"type": "affine",
      "translate": [1e17, 0, 0], "child": {"type": "point", "center": [0,0,0], "radius": 1}}})") + " -o " +
                                 (dir / "m.ply").string());
  EXPECT_EQ(far.code, 2);
  EXPECT_NE(far.err.find("the solid lies 1e+17 from the origin, where doubles step by 16: precision"), std::string::npos)
      << far.err;
  // The scene gave no precision: the one named is said to be the default.
  EXPECT_NE(far.err.find("is the default: neither --precision nor the scene's mesher.precision gave one)"), std::string::npos)
      << far.err;
  // Scenes of extreme numbers, from an extreme-value campaign, each refused with what is wrong
  // and nothing written: a result that is no closed manifold (a curve of radius 1e-200, every
  // vertex NaN; exit 0 before); a disc of radius 1e150 (its sweep left 462 boundary edges, refused
  // at the end; now at the start) and a tapered cylinder of that radius (minutes in the checks on
  // infinite products); numbers the float tape cannot hold (a twist rate of 4e38 meshed as
  // empty; one of 1.7e308 filled 4 GB refining its warped mesh); a bend of rate 1e9 (its bounds
  // listed every quarter turn: 2 GB, then std::bad_alloc) meshes.
  const std::pair<const char*, const char*> extreme[] = {
      {"nan_curve_radius_1e-200.json", "the mesh made is no closed manifold ("},
      {"open_disc_radius_1e150.json", "the solid reaches 1e+150 from the origin: HybridTree meshes solids within 1e+100"},
      {"hang_taper_cylinder_radius_1e150.json", "the solid reaches 1e+150 from the origin"},
      {"tape_tree_disagree_twist_rate_4e38.json", "node twist #1: its field needs the number 4e+38, beyond the float range"},
      {"hang_twist_rate_1.7e308.json", "node twist #1: its field needs the number 1.7e+308, beyond the float range"},
      // Beside an ffd the check was skipped (the compiler stops at an ffd not yet meshed): 25 s
      // and 1.4 GB before the same error.
      {"ffd_beside_float_range_twist.json", "node twist #3: its field needs the number 4e+38, beyond the float range"},
      {"badalloc_bend_rate_1e9.json", nullptr}};
  for (const auto& [scene, message] : extreme) {
    const auto run = test::run_cli("mesh " + (std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / "tests/data/stress" / scene).string() +
                                   " -o " + (dir / "m.ply").string());
    if (!message) {
      EXPECT_EQ(run.code, 0) << scene << ": " << run.err;
      std::filesystem::remove(dir / "m.ply");
      continue;
    }
    EXPECT_EQ(run.code, 2) << scene;
    EXPECT_NE(run.err.find(message), std::string::npos) << run.err;
  }
  // Nothing but the four scenes is left in the folder: no partial output.
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 4u);
  // More GiB than size_t holds in bytes is no limit (it was cast to a budget of 0 bytes).
  const auto endless = test::run_cli("mesh " + s + " -o " + (dir / "e.ply").string() + " --precision 0.1 --memory-budget 1e12");
  EXPECT_EQ(endless.code, 0) << endless.err;
  std::filesystem::remove(dir / "e.ply");
  std::filesystem::create_directory(dir / "d.ply");
  const auto onto = test::run_cli("mesh " + s + " -o " + (dir / "d.ply").string() + " --precision 0.1");
  EXPECT_EQ(onto.code, 2);
  EXPECT_NE(onto.err.find("d.ply: is a folder, not a file"), std::string::npos) << onto.err;
  // A stats file that cannot be written leaves no mesh behind; a device is not renamed over
  // (run as root, --stats-json /dev/full replaced the device with a file and exited 0).
  const auto stats = test::run_cli("mesh " + s + " -o " + (dir / "st.ply").string() + " --precision 0.1 --stats-json " +
                                   (dir / "no" / "s.json").string());
  EXPECT_EQ(stats.code, 2);
  EXPECT_FALSE(std::filesystem::exists(dir / "st.ply"));
  if (std::filesystem::is_character_file("/dev/full")) {
    const auto full = test::run_cli("mesh " + s + " -o " + (dir / "f.ply").string() + " --precision 0.1 --stats-json /dev/full");
    EXPECT_EQ(full.code, 2);
    EXPECT_NE(full.err.find("is not a regular file"), std::string::npos) << full.err;
    EXPECT_TRUE(std::filesystem::is_character_file("/dev/full"));
    EXPECT_FALSE(std::filesystem::exists(dir / "f.ply"));
  }
  // A pipe behind a link (as /dev/stdout is, through /proc/self/fd/1 -> "pipe:[N]").
  ASSERT_EQ(::mkfifo((dir / "fifo").c_str(), 0600), 0);
  std::filesystem::create_symlink(dir / "fifo", dir / "to_fifo.json");
  const auto piped = test::run_cli("mesh " + s + " -o " + (dir / "pp.ply").string() + " --precision 0.1 --stats-json " +
                                   (dir / "to_fifo.json").string());
  EXPECT_EQ(piped.code, 2) << piped.err;
  EXPECT_NE(piped.err.find("is not a regular file"), std::string::npos) << piped.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "pp.ply"));
  // A link is written through: the link stays, its target gets the mesh; the format is the
  // requested name's, whatever the target is called.
  std::filesystem::create_symlink(dir / "target.ply", dir / "link.ply");
  const auto link = test::run_cli("mesh " + s + " -o " + (dir / "link.ply").string() + " --precision 0.1");
  EXPECT_EQ(link.code, 0) << link.err;
  EXPECT_TRUE(std::filesystem::is_symlink(dir / "link.ply"));
  EXPECT_GT(std::filesystem::file_size(dir / "target.ply"), 0u);
  std::filesystem::create_symlink(dir / "blob", dir / "named.ply");
  const auto named = test::run_cli("mesh " + s + " -o " + (dir / "named.ply").string() + " --precision 0.1");
  EXPECT_EQ(named.code, 0) << named.err;
  EXPECT_GT(std::filesystem::file_size(dir / "blob"), 0u);
  const auto empty = test::run_cli("mesh " + write_scene(dir, "e.json", R"({"hybridtree": 1, "root": {"type": "point",
      "center": [0,0,0], "radius": 1, "strength": 0.3}})") + " -o " + (dir / "e.ply").string());
  EXPECT_EQ(empty.code, 0) << empty.err;
  EXPECT_NE(empty.err.find("empty"), std::string::npos) << empty.err;
  std::filesystem::remove_all(dir);
}

TEST(Cli, ScenesWithFfdEvaluateAndMesh) {
  const auto dir = test::temp_dir("cli-ffd");
  std::ostringstream lattice;  // the unit lattice over [-1, 1]^3, its (1,1,1) corner pulled outward
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) {
        const double pull = (i && j && k) ? 0.4 : 0.0;
        lattice << (i + j + k ? ", " : "") << '[' << (-1 + 2 * i + pull) << ", " << (-1 + 2 * j + pull) << ", "
                << (-1 + 2 * k + pull) << ']';
      }
  const std::string pts = lattice.str();
  const std::string s = write_scene(dir, "ffd.json", R"({"hybridtree": 1, "mesher": {"precision": 0.04}, "root":
      {"type": "ffd", "min": [-1,-1,-1], "max": [1,1,1], "dims": [1,1,1], "radius": 0.1, "points": [)" + pts + R"(],
       "child": {"type": "segment", "a": [-0.3,0,0], "b": [0.3,0.2,0.1], "radius": 0.6}}})");
  const auto e = test::run_cli("eval " + s, "0 0 0\n3 3 3\n");
  ASSERT_EQ(e.code, 0) << e.err;
  EXPECT_EQ(e.out.substr(0, 2), "1\n") << e.out;  // deep inside the deformed solid: F
  const auto m = test::run_cli("mesh " + s + " -o " + (dir / "ffd.off").string());
  ASSERT_EQ(m.code, 0) << m.err;
  EXPECT_NE(m.out.find("closed manifold"), std::string::npos) << m.out;
  std::filesystem::remove_all(dir);
}

TEST(Cli, MeshStrategiesAreLoggedPerNode) {
  const auto dir = test::temp_dir("cli-strategy");
  const std::string s = write_scene(dir, "s.json", R"({"hybridtree": 1, "mesher": {"precision": 0.05}, "root":
      {"type": "taper", "axis": "z", "range": [-0.5, 0.5], "scale": [1, 0.3],
       "child": {"type": "cylinder", "a": [0,0,-0.5], "b": [0,0,0.5], "cylinder_radius": 0.3, "radius": 0.4}}})");
  for (const char* strategy : {"auto", "global"}) {
    const auto r = test::run_cli("mesh " + s + " -o " + (dir / "m.ply").string() + " --strategy " + strategy +
                                 " --stats-json " + (dir / "st.json").string());
    ASSERT_EQ(r.code, 0) << r.err;
    std::ifstream in(dir / "st.json");
    const auto j = nlohmann::json::parse(in);
    EXPECT_EQ(j["checks"]["watertight"], true) << strategy;
    EXPECT_EQ(j["strategy"], strategy);
    if (std::string(strategy) == "auto") {
      ASSERT_EQ(j["nodes"].size(), 2u);
      EXPECT_EQ(j["nodes"][0]["strategy"], "sweep");
      EXPECT_NE(j["nodes"][1]["strategy"].get<std::string>().find("warped child"), std::string::npos);
    } else {
      EXPECT_EQ(j["nodes"][0]["strategy"], "global");
    }
  }
  std::filesystem::remove_all(dir);
}

TEST(Cli, LocalStrategiesReportWhatTheyDidPerNode) {
  const auto dir = test::temp_dir("cli-local");
  const std::string s = write_scene(dir, "s.json", R"({"hybridtree": 1, "mesher": {"precision": 0.03}, "root":
      {"type": "union", "name": "pair", "children": [
        {"type": "blend", "name": "close", "children": [{"type": "point", "center": [0,0,0], "radius": 1},
                                                         {"type": "point", "center": [0.1,0,0], "radius": 1}]},
        {"type": "segment", "name": "bar", "a": [0.3,0,0], "b": [1.2,0,0], "radius": 0.4}]}})");
  const auto r = test::run_cli("mesh " + s + " -o " + (dir / "m.ply").string() + " --stats-json " + (dir / "st.json").string());
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream in(dir / "st.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["checks"]["watertight"], true);
  EXPECT_EQ(j["checks"]["self_intersecting_pairs"], 0);
  std::map<std::string, nlohmann::json> by_name;
  for (const auto& n : j["nodes"]) by_name[n["node"].get<std::string>()] = n;
  EXPECT_EQ(by_name["\"pair\""]["strategy"], "trim boolean");
  EXPECT_EQ(by_name["\"close\""]["strategy"], "global");
  EXPECT_EQ(by_name["\"close\""]["reason"], "high overlap");
  EXPECT_GT(by_name["\"close\""]["rho"].get<double>(), 0.5);
  EXPECT_GT(by_name["\"close\""]["bricks"]["active"].get<int>(), 0);  // the polygonizer's statistics survive
  EXPECT_EQ(by_name["\"bar\""]["strategy"], "sweep");
  EXPECT_GT(j["bricks"]["active"].get<int>(), 0);
  std::filesystem::remove_all(dir);
}

TEST(Cli, SharpFeaturesCanBeTurnedOff) {
  const auto dir = test::temp_dir("cli-sharp");
  const std::string s = write_scene(dir, "s.json", R"({"hybridtree": 1, "mesher": {"precision": 0.04}, "root":
      {"type": "crop", "min": [-1, -1, -0.2], "max": [0.25, 1, 1], "child": {"type": "point", "center": [0, 0, 0], "radius": 1}}})");
  double face_error[2] = {0, 0};
  for (int on = 0; on < 2; ++on) {
    const auto r = test::run_cli("mesh " + s + " -o " + (dir / "m.ply").string() + " --strategy global --sharp-features " +
                                 (on ? "on" : "off") + " --stats-json " + (dir / "st.json").string());
    ASSERT_EQ(r.code, 0) << r.err;
    std::ifstream in(dir / "st.json");
    const auto j = nlohmann::json::parse(in);
    EXPECT_EQ(j["checks"]["watertight"], true);
    EXPECT_EQ(j["sharp_features"]["crease_edges_split"].get<int>() > 0, on == 1);
    face_error[on] = j["checks"]["surface_error_face_max"].get<double>();
  }
  EXPECT_LT(face_error[1], 0.5 * face_error[0]);
  const auto bad = test::run_cli("mesh " + s + " -o " + (dir / "m.ply").string() + " --sharp-features maybe");
  EXPECT_EQ(bad.code, 2);
  std::filesystem::remove_all(dir);
}

// --- eval with .npy points and output -------------------------------------------------------
// The files are built and read here byte by byte, apart from tools/npy.cpp, so that the tests
// check the format itself rather than the CLI against its own reader.
namespace {

std::string slurp(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// An .npy file: magic, version, header length (2 bytes for 1.x, 4 for 2.x), dict, payload.
std::string npy_bytes(const std::string& dict, const std::string& payload, int major = 1) {
  std::string header = dict;
  const std::size_t preamble = major == 1 ? 10 : 12;
  while ((preamble + header.size() + 1) % 64) header += ' ';
  header += '\n';
  std::string out = std::string("\x93NUMPY", 6) + char(major) + '\0';
  for (int i = 0; i < (major == 1 ? 2 : 4); ++i) out += char((header.size() >> (8 * i)) & 0xff);
  return out + header + payload;
}

std::string npy_dict(const std::string& descr, const std::string& shape, bool fortran = false) {
  return "{'descr': '" + descr + "', 'fortran_order': " + (fortran ? "True" : "False") + ", 'shape': " + shape + ", }";
}

template <class Float>
std::string raw(const std::vector<glm::dvec3>& points) {
  std::string out;
  for (const glm::dvec3& p : points)
    for (int j = 0; j < 3; ++j) {
      const Float v = static_cast<Float>(p[j]);
      out.append(reinterpret_cast<const char*>(&v), sizeof v);
    }
  return out;
}

// An output file: its header must be exactly what numpy.save writes; the data as doubles.
std::vector<double> read_npy_output(const std::filesystem::path& file, const std::string& descr, const std::string& shape) {
  const std::string bytes = slurp(file);
  const std::string expected = npy_bytes(npy_dict(descr, shape), "");
  EXPECT_EQ(bytes.substr(0, expected.size()), expected) << file;
  std::vector<double> out;
  const std::size_t item = descr == "<f4" ? 4 : 8;
  for (std::size_t at = expected.size(); at + item <= bytes.size(); at += item) {
    if (item == 4) {
      float f;
      std::memcpy(&f, bytes.data() + at, 4);
      out.push_back(f);
    } else {
      double d;
      std::memcpy(&d, bytes.data() + at, 8);
      out.push_back(d);
    }
  }
  EXPECT_EQ((bytes.size() - expected.size()) % item, 0u);
  return out;
}

std::vector<double> numbers(const std::string& text) {
  std::istringstream in(text);
  std::vector<double> out;
  for (double v; in >> v;) out.push_back(v);
  return out;
}

}  // namespace

TEST(Cli, EvalNpyMatchesTextForBothDtypesAndAnyThreadCount) {
  const auto dir = test::temp_dir("cli-npy");
  const std::string s = write_scene(dir, "snake.json", scenes::snake_json(30));
  auto rng = test::seeded();
  std::uniform_real_distribution<double> ux(-1, 13), uy(-2, 2), uz(-1.5, 2);
  std::vector<glm::dvec3> points(1500);  // 6 blocks of the tape: enough for two threads to share
  for (auto& p : points) p = {ux(rng), uy(rng), uz(rng)};
  const std::string n = std::to_string(points.size());
  for (const std::string descr : {"<f4", "<f8"}) {
    const bool f4 = descr == "<f4";
    test::write_file(dir / "p.npy", npy_bytes(npy_dict(descr, "(" + n + ", 3)"), f4 ? raw<float>(points) : raw<double>(points)));
    // The same coordinates as text: 17 digits give the double (or the float, as a double) back
    // exactly, so that the tree engine, in double, sees the very same points.
    std::string text;
    char buf[96];
    for (const glm::dvec3& p : points) {
      const glm::dvec3 q = f4 ? glm::dvec3(glm::vec3(p)) : p;
      std::snprintf(buf, sizeof buf, "%.17g %.17g %.17g\n", q.x, q.y, q.z);
      text += buf;
    }
    test::write_file(dir / "p.txt", text);
    for (const std::string engine : {"tape", "tree"})
      for (const bool gradient : {false, true}) {
        const std::string flags = " --engine " + engine + (gradient ? " --gradient" : "");
        const std::string what = descr + flags;
        const auto t = test::run_cli("eval " + s + " --points " + (dir / "p.txt").string() + flags);
        ASSERT_EQ(t.code, 0) << t.err;
        for (const char* threads : {"1", "2"}) {
          const auto r = test::run_cli("eval " + s + " --points " + (dir / "p.npy").string() + " -o " +
                                       (dir / (std::string("o") + threads + ".npy")).string() + " --threads " + threads + flags);
          ASSERT_EQ(r.code, 0) << r.err;
          EXPECT_EQ(r.out, "") << "an output file, nothing on stdout";
        }
        EXPECT_EQ(slurp(dir / "o1.npy"), slurp(dir / "o2.npy")) << what << ": the same bytes at 1 and 2 threads";
        const std::vector<double> expected = numbers(t.out);
        const std::vector<double> got = read_npy_output(dir / "o2.npy", descr, gradient ? "(" + n + ", 4)" : "(" + n + ",)");
        ASSERT_EQ(expected.size(), points.size() * (gradient ? 4 : 1)) << what;
        ASSERT_EQ(got.size(), expected.size()) << what;
        double nonzero = 0;
        for (std::size_t i = 0; i < got.size(); ++i) {
          nonzero += got[i] != 0;
          if (engine == "tape") {  // floats: 9 digits of text give each one back exactly
            ASSERT_EQ(float(got[i]), float(expected[i])) << what << " entry " << i;
            ASSERT_EQ(got[i], double(float(got[i]))) << what << " entry " << i;
          } else {  // doubles, rounded to 9 digits in the text and to float in '<f4'
            ASSERT_NEAR(got[i], expected[i], (f4 ? 1e-7 : 1e-8) * std::max(1.0, std::abs(expected[i])))
                << what << " entry " << i;
          }
        }
        EXPECT_GT(nonzero, 0.1 * double(got.size())) << what << ": the points must reach the snake";
      }
  }
  // Text points in, .npy out: float32, the tape's precision. Format 2.0 and empty arrays read.
  const auto t = test::run_cli("eval " + s + " -o " + (dir / "t.npy").string(), "1 0 0.5\n5 0.5 0\n");
  ASSERT_EQ(t.code, 0) << t.err;
  const auto from_text = read_npy_output(dir / "t.npy", "<f4", "(2,)");
  const auto printed = numbers(test::run_cli("eval " + s, "1 0 0.5\n5 0.5 0\n").out);
  auto floats = [](const std::vector<double>& v) { return std::vector<float>(v.begin(), v.end()); };
  ASSERT_EQ(printed.size(), 2u);
  EXPECT_GT(printed[0], 1.0);
  EXPECT_EQ(floats(from_text), floats(printed));
  test::write_file(dir / "v2.npy", npy_bytes(npy_dict("<f8", "(2, 3)"), raw<double>({{1, 0, 0.5}, {5, 0.5, 0}}), 2));
  const auto v2 = test::run_cli("eval " + s + " --points " + (dir / "v2.npy").string() + " -o " + (dir / "v2out.npy").string());
  ASSERT_EQ(v2.code, 0) << v2.err;
  EXPECT_EQ(floats(read_npy_output(dir / "v2out.npy", "<f8", "(2,)")), floats(printed));
  test::write_file(dir / "empty.npy", npy_bytes(npy_dict("<f4", "(0, 3)"), ""));
  const auto empty = test::run_cli("eval " + s + " --gradient --points " + (dir / "empty.npy").string() + " -o " +
                                   (dir / "eout.npy").string());
  ASSERT_EQ(empty.code, 0) << empty.err;
  EXPECT_TRUE(read_npy_output(dir / "eout.npy", "<f4", "(0, 4)").empty());
  std::filesystem::remove_all(dir);
}

TEST(Cli, EvalRefusesMalformedNpyNamingTheFileAndWritesNothing) {
  const auto dir = test::temp_dir("cli-npy-bad");
  const std::string s = write_scene(dir, "ball.json", kBall);
  const std::vector<glm::dvec3> four = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const std::string f8 = raw<double>(four);
  std::vector<glm::dvec3> nan = four, inf = four;
  nan[1].z = std::nan("");
  inf[3].x = -HUGE_VAL;
  const std::string good = npy_bytes(npy_dict("<f8", "(4, 3)"), f8);
  struct Case {
    std::string name, bytes, expected;
  };
  const std::vector<Case> cases = {
      {"empty", "", "not a .npy file"},
      {"magic", "\x93NUMPX" + good.substr(6), "not a .npy file"},
      {"version", good.substr(0, 6) + '\x03' + good.substr(7), ".npy format version 3.0 is not supported"},
      {"header_cut", good.substr(0, 40), "truncated .npy header"},
      {"header_syntax", npy_bytes("{'descr' '<f8'}", f8), "the .npy header does not parse"},
      {"no_shape", npy_bytes("{'descr': '<f8', 'fortran_order': False}", f8), "the .npy header has no valid 'shape' entry"},
      {"big_endian", npy_bytes(npy_dict(">f8", "(4, 3)"), f8), "unsupported dtype '>f8'"},
      {"int", npy_bytes(npy_dict("<i4", "(4, 3)"), f8), "unsupported dtype '<i4'"},
      {"fortran", npy_bytes(npy_dict("<f8", "(4, 3)", true), f8), "fortran_order is True"},
      {"columns", npy_bytes(npy_dict("<f8", "(6, 2)"), f8), "shape (6, 2) is not (N, 3)"},
      {"flat", npy_bytes(npy_dict("<f8", "(12,)"), f8), "shape (12,) is not (N, 3)"},
      {"truncated", npy_bytes(npy_dict("<f8", "(4, 3)"), f8.substr(0, 90)), "truncated: shape (4, 3) of <f8 needs 96 bytes"},
      {"trailing", npy_bytes(npy_dict("<f4", "(4, 3)"), f8), "48 bytes follow the (4, 3) array"},
      {"nan", npy_bytes(npy_dict("<f4", "(4, 3)"), raw<float>(nan)), "points[1, 2] is nan, not a finite number"},
      {"inf", npy_bytes(npy_dict("<f8", "(4, 3)"), raw<double>(inf)), "points[3, 0] is -inf, not a finite number"},
  };
  for (const Case& c : cases) {
    const std::string in = (dir / (c.name + ".npy")).string();
    test::write_file(in, c.bytes);
    const auto r = test::run_cli("eval " + s + " --points " + in + " -o " + (dir / "out.npy").string());
    EXPECT_EQ(r.code, 2) << c.name;
    EXPECT_NE(r.err.find("hybridtree: " + in + ": " + c.expected), std::string::npos) << c.name << ": " << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "out.npy")) << c.name;
  }
  test::write_file(dir / "good.npy", good);
  const auto ok = test::run_cli("eval " + s + " --points " + (dir / "good.npy").string() + " -o " + (dir / "out.npy").string());
  ASSERT_EQ(ok.code, 0) << ok.err;
  EXPECT_EQ(read_npy_output(dir / "out.npy", "<f8", "(4,)"), (std::vector<double>{1, 0.421875, 0.421875, 0.421875}));
  const std::string missing = (dir / "no" / "out.npy").string();
  const auto folder = test::run_cli("eval " + s + " --points " + (dir / "good.npy").string() + " -o " + missing);
  EXPECT_EQ(folder.code, 2);
  EXPECT_NE(folder.err.find(missing + ": cannot write the output file"), std::string::npos) << folder.err;
  // Only the inputs and the one good output are left: no temporary survives a refusal.
  std::size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    ++files;
    EXPECT_EQ(e.path().string().find(".partial"), std::string::npos) << e.path();
  }
  EXPECT_EQ(files, cases.size() + 3);  // the cases, ball.json, good.npy, out.npy
  std::filesystem::remove_all(dir);
}

namespace {
// Width and height from a PNG's IHDR chunk, or {0, 0} when the file is not a PNG.
std::pair<std::uint32_t, std::uint32_t> png_size(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::string head(24, '\0');
  in.read(head.data(), 24);
  if (!in || head.compare(0, 8, "\x89PNG\r\n\x1a\n") != 0 || head.compare(12, 4, "IHDR") != 0) return {0, 0};
  auto be32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    for (std::size_t i = 0; i < 4; ++i) v = v << 8 | static_cast<unsigned char>(head[at + i]);
    return v;
  };
  return {be32(16), be32(20)};
}
}  // namespace

TEST(Cli, RenderDrawsScenesAndMeshesIntoPngs) {
  const auto dir = test::temp_dir("cli-render");
  const std::string s = write_scene(dir, "s.json", kBall);
  const auto scene = test::run_cli("render " + s + " -o " + (dir / "s.png").string() + " --size 120 90 --view 10 40");
  ASSERT_EQ(scene.code, 0) << scene.err;
  EXPECT_EQ(png_size(dir / "s.png"), std::make_pair(120u, 90u));
  EXPECT_NE(scene.out.find("(0 on mesh leaves"), std::string::npos) << scene.out;
  const auto mesh = test::run_cli("render " + test::cgal_mesh("eight.off").string() + " -o " + (dir / "m.png").string() +
                                  " --size 64 48");
  ASSERT_EQ(mesh.code, 0) << mesh.err;
  EXPECT_EQ(png_size(dir / "m.png"), std::make_pair(64u, 48u));
  // Bad requests: exit 2 with the reason, and no picture.
  const auto ext = test::run_cli("render " + s + " -o " + (dir / "x.jpg").string());
  EXPECT_EQ(ext.code, 2);
  EXPECT_NE(ext.err.find("PNG"), std::string::npos) << ext.err;
  const auto size = test::run_cli("render " + s + " -o " + (dir / "y.png").string() + " --size 4 100000");
  EXPECT_EQ(size.code, 2);
  EXPECT_NE(size.err.find("16 to 8192"), std::string::npos) << size.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.jpg"));
  EXPECT_FALSE(std::filesystem::exists(dir / "y.png"));
  std::filesystem::create_directory(dir / "d.png");
  const auto onto = test::run_cli("render " + test::cgal_mesh("eight.off").string() + " -o " + (dir / "d.png").string() +
                                  " --size 32 32");
  EXPECT_NE(onto.code, 0);
  EXPECT_NE(onto.err.find("d.png: is a folder, not a file"), std::string::npos) << onto.err;
  std::filesystem::remove_all(dir);
}
