// Scene format v1: every node type loads, and every malformed scene is rejected with the JSON
// path of the offending value and the rule it breaks (table-driven).
#include "nodes/mesh_leaf.hpp"
#include "runtime/scene.hpp"
#include "runtime/tape_eval.hpp"
#include "runtime/tree_eval.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>
#include <filesystem>
#include <fstream>

#include <string>

using namespace ht;

namespace {

std::string scene(const std::string& root, const std::string& top = "") {
  return "{\"hybridtree\": 1, " + top + "\"root\": " + root + "}";
}

const char* kPoint = R"({"type": "point", "center": [0,0,0], "radius": 1})";

struct BadCase {
  std::string text;
  std::string expected;  // a substring of the message: path and rule
};

std::vector<BadCase> bad_cases() {
  const std::string p = kPoint;
  return {
      {"{not json", "not valid JSON"},
      {"[]", ": must be an object"},
      {R"({"root": )" + p + "}", "hybridtree: is required"},
      {R"({"hybridtree": 2, "root": )" + p + "}", "hybridtree: must be 1"},
      {R"({"hybridtree": "1", "root": )" + p + "}", "hybridtree: must be 1"},
      {R"({"hybridtree": 1})", "root: is required"},
      {scene(p, R"("threshold": 0, )"), "threshold: must be > 0"},
      {scene(p, R"("threshold": "high", )"), "threshold: must be a number"},
      {scene(p, R"("colour": 1, )"), "colour: unknown key"},
      {scene(p, R"("mesher": {"precision": -1}, )"), "mesher.precision: must be > 0"},
      {scene(p, R"("mesher": {"strategy": "fast"}, )"), "mesher.strategy: must be \"auto\""},
      {scene(p, R"("mesher": {"blend_overlap": 2}, )"), "mesher.blend_overlap: must be in [0, 1]"},
      {scene(p, R"("mesher": {"speed": 2}, )"), "mesher.speed: unknown key"},
      {scene(R"({"type": "sphere", "radius": 1})"), "root.type: unknown type \"sphere\""},
      {scene(R"({"radius": 1})"), "root.type: is required"},
      {scene(R"({"type": "point", "center": [0,0,0], "radius": 1, "colour": 3})"), "root.colour: unknown key"},
      {scene(R"({"type": "point", "center": [0,0], "radius": 1})"), "root.center: must be a vector of 3 numbers"},
      {scene(R"({"type": "point", "center": [0,0,"x"], "radius": 1})"), "root.center[2]: must be a number"},
      {scene(R"({"type": "point", "center": 5, "radius": 1})"), "root.center: must be a vector"},
      {scene(R"({"type": "point", "center": [0,0,1e999], "radius": 1})"),
       "root.center[2]: the number 1e999 is past the range of doubles (every number must be finite)"},
      {scene(R"({"type": "blend", "children": [)" + p + R"(, {"type": "point", "center": [0,0,0], "radius": 1)" + std::string(400, '0') + "}]}"),
       "root.children[1].radius: the number 100000000000...000000 (401 characters) is past the range of doubles"},
      {scene(R"({"type": "point", "center": [0,0,0], "radius": 0})"), "root.radius: must be > 0"},
      {scene(R"({"type": "point", "center": [0,0,0], "radius": -2})"), "root.radius: must be > 0"},
      {scene(R"({"type": "point", "center": [0,0,0]})"), "root.radius: is required"},
      {scene(R"({"type": "point", "center": [0,0,0], "radius": 1, "strength": 0})"), "root.strength: must be non-zero"},
      {scene(R"({"type": "point", "center": [0,0,0], "radius": 1, "name": 7})"), "root.name: must be a string"},
      {scene(R"({"type": "point", "center": [0,0,0], "radius": 1, "mesher": "global"})"), "root.mesher: unknown key"},
      {scene(R"({"type": "circle", "center": [0,0,0], "normal": [0,0,0], "circle_radius": 1, "radius": 1})"),
       "root.normal: must be a non-zero vector"},
      {scene(R"({"type": "disc", "center": [0,0,0], "normal": [0,0,1], "disc_radius": 0, "radius": 1})"),
       "root.disc_radius: must be > 0"},
      {scene(R"({"type": "curve", "points": [[0,0,0]], "radius": 1})"), "root.points: must hold at least 2 points"},
      {scene(R"({"type": "curve", "points": [[0,0,0], [1,1]], "radius": 1})"), "root.points[1]: must be a vector of 3"},
      {scene(R"({"type": "box", "min": [0,0,0], "max": [1,0,1], "radius": 1})"), "root.max: must be greater than min"},
      {scene(R"({"type": "cylinder", "a": [0,0,0], "b": [0,0,0], "cylinder_radius": 1, "radius": 1})"), "root.b: must differ from a"},
      {scene(R"({"type": "cone_sphere", "a": [0,0,0], "b": [0,0,1], "radius_a": 1, "radius_b": -1, "radius": 1})"),
       "root.radius_b: must be > 0"},
      {scene(R"({"type": "blend", "children": []})"), "root.children: must hold at least 1 node"},
      {scene(R"({"type": "blend", "children": {}})"), "root.children: must be an array"},
      {scene(R"({"type": "blend", "children": [)" + p + R"(, {"type": "point", "center": [0,0,0], "radius": -1}]})"),
       "root.children[1].radius: must be > 0"},
      {scene(R"({"type": "union", "children": [)" + p + R"(], "boolean": "smooth"})"), "root.boolean: must be \"auto\""},
      {scene(R"({"type": "blend", "children": [)" + p + R"(], "boolean": "minmax"})"), "root.boolean: unknown key"},
      {scene(R"({"type": "union", "children": [)" + p + R"(], "mesher": "fastest"})"), "root.mesher: must be \"auto\""},
      {scene(R"({"type": "local_blend", "a": )" + p + R"(, "b": )" + p + "}"), "root.region: is required"},
      {scene(R"({"type": "crop", "child": )" + p + R"(, "min": [0,0,0], "max": [-1,1,1]})"), "root.max: must be greater than min"},
      {scene(R"({"type": "affine", "child": )" + p + "}"), "root: affine needs matrix"},
      {scene(R"({"type": "affine", "child": )" + p + R"(, "scale": 0})"), "root.scale: must be non-zero"},
      // Invertible on paper, not in doubles: named where the scene says it, not as a matrix.
      {scene(R"({"type": "affine", "child": )" + p + R"(, "scale": 1e200})"),
       "root.scale: makes the map singular in double precision: its determinant, the scales' product (1e+600), is past the range of doubles"},
      {scene(R"({"type": "affine", "child": )" + p + R"(, "scale": 1e-200, "translate": [1,0,0]})"),
       "root.scale: makes the map singular in double precision: its determinant, the scales' product (1e-600), rounds to 0"},
      {scene(R"({"type": "affine", "child": )" + p + R"(, "scale": 1e-103})"), "(1e-309), has an inverse past the range of doubles"},
      {scene(R"({"type": "affine", "child": )" + p + R"(, "scale": [1.5e12, 1, 1]})"),
       "root.scale: makes the map singular in double precision: its scales differ by a factor of 1.5e+12"},
      {scene(R"({"type": "affine", "child": )" + p + R"(, "scale": [1e308, 1e308, 1e-308]})"), "differ by a factor of 1e+616"},
      {R"({"hybridtree": 1, "x": )" + std::string(2000, '[') + "1e999" + std::string(2000, ']') + R"(, "root": )" + p + "}",
       "...(5881 characters)...[0][0][0][0]"},
      {scene(R"({"type": "affine", "child": )" + p + R"(, "matrix": [1,0,0,0, 0,1,0,0, 0,2,0,0, 0,0,0,1]})"),
       "root.matrix: is singular"},
      {scene(R"({"type": "affine", "child": )" + p + R"(, "matrix": [1e8,0,0,0, 0,1e-8,0,0, 0,0,1,0, 0,0,0,1]})"),
       "root.matrix: is singular, or too near it to invert in double precision (condition past 1e12)"},
      {scene(R"({"type": "affine", "child": )" + p + R"(, "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 1,0,0,1]})"),
       "root.matrix: last row must be [0, 0, 0, 1]"},
      {scene(R"({"type": "affine", "child": )" + p + R"(, "matrix": [1,0,0]})"), "root.matrix: must be 16 numbers"},
      {scene(R"({"type": "affine", "child": )" + p + R"(, "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1], "translate": [1,0,0]})"),
       "root.translate: cannot be combined with matrix"},
      {scene(R"({"type": "affine", "child": )" + p + R"(, "rotate": {"axis": "w", "degrees": 3}})"), "root.rotate.axis: must be"},
      {scene(R"({"type": "affine", "child": )" + p + R"(, "rotate": {"axis": "x"}})"), "root.rotate.degrees: is required"},
      {scene(R"({"type": "twist", "child": )" + p + R"(, "axis": "q", "rate": 1})"), "root.axis: must be \"x\", \"y\" or \"z\""},
      {scene(R"({"type": "twist", "child": )" + p + "}"), "root.rate: is required"},
      {scene(R"({"type": "taper", "child": )" + p + R"(, "range": [0,1], "scale": [1,0]})"), "root.scale: must be > 0"},
      {scene(R"({"type": "taper", "child": )" + p + R"(, "range": [1,0], "scale": [1,1]})"), "root.range: must be [h0, h1]"},
      {scene(R"({"type": "taper", "child": )" + p + R"(, "range": [0], "scale": [1,1]})"), "root.range: must be an array of 2"},
      {scene(R"({"type": "bend", "child": )" + p + R"(, "range": [0,1]})"), "root.rate: is required"},
      {scene(R"({"type": "ffd", "child": )" + p +
             R"(, "min": [0,0,0], "max": [1,1,1], "dims": [1,1,1], "points": [[0,0,0]], "radius": 0.1})"),
       "root.points: must hold (l+1)(m+1)(n+1) = 8 control points, not 1"},
      {scene(R"({"type": "ffd", "child": )" + p + R"(, "min": [0,0,0], "max": [1,1,1], "dims": [1,0,1], "points": [], "radius": 0.1})"),
       "root.dims[1]: must be a whole number from 1 to 64"},
      {scene(R"({"type": "mesh", "file": "missing.off", "radius": 0.1})"), "root.file: "},
      {scene(R"({"type": "mesh", "file": "missing.off", "radius": 0.1, "strength": 0.4})"),
       "root.strength: |strength| must be > threshold"},
      {scene(R"({"type": "mesh", "file": "missing.off", "radius": 0.1, "inside": "parity"})"),
       "root.inside: must be \"closed\" or \"winding\", not \"parity\""},
      {scene(R"({"type": "mesh", "file": "missing.off", "radius": 0.1, "inside": 3})"), "root.inside: must be a string"},
      {scene(R"({"type": "mesh", "file": "missing.off", "radius": 0.1, "inside": "winding", "repair": true})"),
       "root.repair: cannot be combined with \"inside\": \"winding\""},
  };
}

}  // namespace

TEST(Scene, EveryMalformedSceneNamesThePathAndTheRule) {
  for (const BadCase& c : bad_cases()) {
    try {
      load_scene_text(c.text, ".", "s.json");
      ADD_FAILURE() << "accepted: " << c.text;
    } catch (const SceneError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(c.expected), std::string::npos) << "message: " << msg << "\nexpected: " << c.expected;
      EXPECT_EQ(msg.rfind("s.json: ", 0), 0u) << msg;
    }
  }
}

// A stream that is no scene is told by its first bytes, before it fills memory: `hybridtree mesh
// /dev/zero` read for 32 s up to 4 GB and ended with std::bad_alloc (the second stress run).
TEST(Scene, AFileThatIsNoSceneIsToldByItsFirstBytes) {
  const auto message = [](const std::filesystem::path& file) -> std::string {
    try {
      load_scene(file);
    } catch (const SceneError& e) {
      return e.what();
    }
    return "loaded";
  };
  if (std::filesystem::is_character_file("/dev/zero")) {
    EXPECT_EQ(message("/dev/zero"),
              "/dev/zero: is not a scene: a scene is a JSON object, which starts with '{', and byte 0 is 0x00");
  }
  const std::filesystem::path dir = test::temp_dir("scene_bytes");
  const auto write = [&](const std::string& name, const std::string& bytes) {
    std::ofstream(dir / name, std::ios::binary) << bytes;
    return dir / name;
  };
  const std::string point = scene(kPoint);
  EXPECT_NE(message(write("off.json", "OFF\n3 1 0\n")).find("byte 0 is 0x4f"), std::string::npos);
  EXPECT_NE(message(write("spaced.json", "\n\n  [1]")).find("byte 4 is 0x5b"), std::string::npos);
  EXPECT_EQ(message(write("ok.json", "\n  " + point)), "loaded");
  EXPECT_EQ(message(write("bom.json", "\xEF\xBB\xBF" + point)), "loaded");
  // A byte order mark opens the file or is no scene's; what follows it is looked at too.
  EXPECT_NE(message(write("bom_off.json", "\xEF\xBB\xBFOFF\n")).find("byte 3 is 0x4f"), std::string::npos);
  EXPECT_NE(message(write("late_bom.json", " \xEF\xBB\xBF" + point)).find("byte 1 is 0xef"), std::string::npos);
}

// A stretch whose determinant is 1 is no singular map (the rule before held |det| to the largest
// entry cubed and refused it); its inverse round-trips points.
TEST(Scene, AStretchFarFromSingularLoads) {
  const Tree t = load_scene_text(
      scene(R"({"type": "affine", "child": )" + std::string(kPoint) + R"(, "matrix": [1e4,0,0,0, 0,1e-4,0,0, 0,0,1,0, 0,0,0,1]})"),
      ".");
  const std::vector<glm::dvec3> at = {{0, 0, 0}, {5e3, 0, 0}, {0, 5e-5, 0}, {0, 2e-4, 0}};
  std::vector<double> v(at.size());
  t.evaluator().field(at, v);
  EXPECT_GT(v[0], 0.5);
  EXPECT_GT(v[1], 0.0);
  EXPECT_GT(v[2], 0.0);
  EXPECT_EQ(v[3], 0.0);
}

// Normals and axes of extreme size are unit vectors all the same: a circle's normal of 1e155
// squared past doubles and made every vertex of its sweep NaN.
TEST(Scene, HugeAndTinyNormalsAreUnitVectors) {
  for (const char* n : {"1e155", "1e300", "1e-170", "5e-324"}) {
    const Tree t = load_scene_text(scene(R"({"type": "circle", "center": [0,0,0], "normal": [0, 0, )" + std::string(n) +
                                         R"(], "circle_radius": 1, "radius": 0.4})"),
                                   ".");
    const std::vector<glm::dvec3> at = {{1, 0, 0}, {0, 0, 1}};
    std::vector<double> v(at.size());
    t.evaluator().field(at, v);
    EXPECT_GT(v[0], 0.5) << n;  // on the circle
    EXPECT_EQ(v[1], 0.0) << n;  // on its axis, beyond the radius
  }
}

TEST(Scene, DeepNestingIsAnErrorNotACrash) {
  std::string text = kPoint;
  for (int i = 0; i < kMaxSceneDepth + 5; ++i) text = R"({"type": "blend", "children": [)" + text + "]}";
  const auto load = [&] {
    try {
      load_scene_text(scene(text), ".", "deep.json");
      FAIL() << "a scene nested deeper than the limit loaded";
    } catch (const SceneError& e) {
      // The path is shortened: its first and last steps and how many were left out, not the
      // thousands of characters of every step.
      const std::string msg = e.what();
      EXPECT_LT(msg.size(), 200u) << msg;
      EXPECT_EQ(msg.rfind("deep.json: root.children[0].children[0].children[0]...(", 0), 0u) << msg;
      EXPECT_NE(msg.find(" steps)...children[0].children[0].children[0]: "), std::string::npos) << msg;
      EXPECT_NE(msg.find("nests deeper than " + std::to_string(kMaxSceneDepth)), std::string::npos) << msg;
    }
  };
  // The loader's recursion takes about 1.6 KB of stack per level at -O3, 1.6 MB at the limit;
  // the sanitizers' redzones make it about 10 KB, more than the main thread's 8 MB at the limit.
  if constexpr (test::kSanitized)
    test::run_on_stack(std::size_t{64} << 20, load);
  else
    load();
}

TEST(Scene, EveryNodeTypeLoads) {
  const auto dir = test::temp_dir("scene-all");
  std::filesystem::copy_file(test::cgal_mesh("eight.off"), dir / "eight.off");
  const std::string text = R"({
    "hybridtree": 1, "threshold": 0.4, "mesher": {"precision": 0.05, "strategy": "global", "blend_overlap": 0.3},
    "root": {"type": "blend", "name": "all", "mesher": "global", "children": [
      {"type": "point", "center": [0,0,0], "radius": 1, "strength": 2},
      {"type": "segment", "a": [0,0,0], "b": [1,0,0], "radius": 0.5},
      {"type": "circle", "center": [0,0,0], "normal": [0,0,1], "circle_radius": 1, "radius": 0.5},
      {"type": "disc", "center": [0,0,0], "normal": [0,1,0], "disc_radius": 1, "radius": 0.5},
      {"type": "triangle", "a": [0,0,0], "b": [1,0,0], "c": [0,1,0], "radius": 0.5},
      {"type": "curve", "points": [[0,0,0],[1,1,0],[2,0,0]], "radius": 0.5},
      {"type": "box", "min": [0,0,0], "max": [1,1,1], "radius": 0.5},
      {"type": "cylinder", "a": [0,0,0], "b": [0,0,1], "cylinder_radius": 0.2, "radius": 0.5},
      {"type": "cone_sphere", "a": [0,0,0], "b": [0,0,1], "radius_a": 0.2, "radius_b": 0.1, "radius": 0.5},
      {"type": "mesh", "file": "eight.off", "radius": 0.1},
      {"type": "union", "boolean": "minmax", "children": [{"type": "point", "center": [0,0,0], "radius": 1}]},
      {"type": "intersection", "boolean": "rfunction", "children": [{"type": "point", "center": [0,0,0], "radius": 1}]},
      {"type": "difference", "boolean": "auto", "children": [{"type": "point", "center": [0,0,0], "radius": 1}]},
      {"type": "local_blend", "a": {"type": "point", "center": [0,0,0], "radius": 1},
       "b": {"type": "point", "center": [1,0,0], "radius": 1}, "region": {"type": "point", "center": [0.5,0,0], "radius": 1}},
      {"type": "crop", "child": {"type": "point", "center": [0,0,0], "radius": 1}, "min": [0,0,0], "max": [1,1,1]},
      {"type": "affine", "scale": [1,2,3], "rotate": {"axis": [0,0,1], "degrees": 30}, "translate": [1,0,0],
       "child": {"type": "point", "center": [0,0,0], "radius": 1}},
      {"type": "affine", "matrix": [[1,0,0,1],[0,1,0,0],[0,0,1,0],[0,0,0,1]], "child": {"type": "point", "center": [0,0,0], "radius": 1}},
      {"type": "twist", "axis": "x", "rate": 1, "child": {"type": "point", "center": [0,0,0], "radius": 1}},
      {"type": "taper", "axis": "y", "center": [0,1,0], "range": [0,1], "scale": [1,0.5], "child": {"type": "point", "center": [0,0,0], "radius": 1}},
      {"type": "bend", "range": [0,1], "rate": 0.5, "child": {"type": "point", "center": [0,0,0], "radius": 1}}
    ]}})";
  test::write_file(dir / "all.json", text);
  const Tree t = load_scene(dir / "all.json");
  EXPECT_EQ(t.threshold(), 0.4);
  EXPECT_EQ(t.mesher_settings().precision, 0.05);
  EXPECT_EQ(t.graph().kind[t.root()], NodeKind::Blend);
  EXPECT_EQ(t.graph().children_of(t.root()).size(), 20u);
  EXPECT_GT(t.reference({0.1, 0.1, 0.1}), 0.0);
  std::filesystem::remove_all(dir);
}

TEST(Scene, AffineComposesScaleThenRotateThenTranslate) {
  const std::string text = scene(R"({"type": "affine", "scale": 2, "rotate": {"axis": "z", "degrees": 90},
      "translate": [10, 0, 0], "child": {"type": "point", "center": [1, 0, 0], "radius": 1}})");
  const Tree t = load_scene_text(text, ".");
  // The skeleton point (1,0,0) goes to (2,0,0), then (0,2,0), then (10,2,0).
  EXPECT_NEAR(t.reference({10, 2, 0}), 1.0, 1e-12);
}

TEST(Scene, SameMeshNamedTwiceIsLoadedOnce) {
  const auto dir = test::temp_dir("scene-shared");
  std::filesystem::copy_file(test::cgal_mesh("sphere.off"), dir / "sphere.off");
  std::filesystem::create_directories(dir / "sub");
  const std::string text = scene(R"({"type": "blend", "children": [
      {"type": "mesh", "file": "sphere.off", "radius": 0.1},
      {"type": "affine", "translate": [3,0,0], "child": {"type": "mesh", "file": "sub/../sphere.off", "radius": 0.2}}]})");
  test::write_file(dir / "s.json", text);
  const Tree t = load_scene(dir / "s.json");
  EXPECT_EQ(t.graph().meshes.size(), 1u);
  std::filesystem::remove_all(dir);
}

// A scene's mesh files are loaded together before its tree is built; one that fails is still
// reported where the scene names it, and the good ones are the same leaves as loaded alone.
TEST(Scene, MeshesLoadTogetherAndAFailingOneIsNamedWhereItStands) {
  const auto dir = test::temp_dir("scene-prefetch");
  std::filesystem::copy_file(test::cgal_mesh("sphere.off"), dir / "sphere.off");
  std::filesystem::copy_file(test::cgal_mesh("eight.off"), dir / "eight.off");
  test::write_file(dir / "bad.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 nan 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  const std::string good = R"({"type": "blend", "children": [
      {"type": "mesh", "file": "sphere.off", "radius": 0.1},
      {"type": "affine", "translate": [3,0,0], "child": {"type": "mesh", "file": "eight.off", "radius": 0.2}}]})";
  test::write_file(dir / "good.json", scene(good));
  const Tree t = load_scene(dir / "good.json");
  ASSERT_EQ(t.graph().meshes.size(), 2u);
  const auto alone = MeshLeaf::load(dir / "eight.off");
  const auto& leaf = *t.graph().meshes[1];
  EXPECT_EQ(leaf.positions(), alone->positions());
  EXPECT_EQ(leaf.triangles(), alone->triangles());
  test::write_file(dir / "bad.json", scene(R"({"type": "blend", "children": [
      {"type": "mesh", "file": "sphere.off", "radius": 0.1},
      {"type": "mesh", "file": "eight.off", "radius": 0.1},
      {"type": "mesh", "file": "bad.off", "radius": 0.1}]})"));
  try {
    load_scene(dir / "bad.json");
    ADD_FAILURE() << "a mesh with a non-finite coordinate loaded";
  } catch (const SceneError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("children[2].file: "), std::string::npos) << what;
    EXPECT_NE(what.find("non-finite"), std::string::npos) << what;
  }
  std::filesystem::remove_all(dir);
}

TEST(Scene, FfdIsParsedButItsFieldWaitsForMeshing) {
  // The unit cube's corners, x fastest: the identity lattice.
  const std::string pts = "[0,0,0],[1,0,0],[0,1,0],[1,1,0],[0,0,1],[1,0,1],[0,1,1],[1,1,1]";
  const std::string text = scene(R"({"type": "ffd", "min": [0,0,0], "max": [1,1,1], "dims": [1,1,1], "radius": 0.1,
      "points": [)" + pts + R"(], "child": {"type": "point", "center": [0,0,0], "radius": 1}})");
  const Tree t = load_scene_text(text, ".");
  EXPECT_THROW(t.reference({0, 0, 0}), EvalError);
}
