// Mesh files as the fuzzers feed them (fuzz/fuzz_mesh_*.cpp): each real bug they found, as a
// focused test of MeshLeaf::load. The inputs themselves are kept in fuzz/corpus/ and replayed by
// the fuzz_replay.* tests; these say what the behaviour must be.
#include "nodes/mesh_leaf.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <future>
#include <string>
#include <utility>
#include <vector>

namespace ht {
namespace {

const std::string kTetraObj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

// An OBJ's "mtllib" was opened by OpenMesh's reader wherever it pointed: "../../dev/zero" read
// forever, a FIFO blocked forever. Only geometry is read, so the library is never opened; here
// it is a FIFO, which a reader opening it would wait on until the test writes to it.
TEST(MeshReading, ObjMaterialLibraryIsNeverOpened) {
  const auto dir = test::temp_dir("mesh-mtllib");
  const auto fifo = dir / "blocks.mtl";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  test::write_file(dir / "tet.obj", "mtllib blocks.mtl\nusemtl stone\n" + kTetraObj);
  auto load = std::async(std::launch::async, [&] { return MeshLeaf::load(dir / "tet.obj"); });
  const bool finished = load.wait_for(std::chrono::seconds(20)) == std::future_status::ready;
  if (!finished) {  // let the blocked reader go: it sees an empty material file
    const int fd = ::open(fifo.c_str(), O_WRONLY);
    if (fd >= 0) ::close(fd);
  }
  EXPECT_TRUE(finished) << "the OBJ reader opened the material library";
  EXPECT_EQ(load.get()->report().triangles, 4u);

  // The same with a path out of the folder, to a file that never ends.
  test::write_file(dir / "zero.obj", "  mtllib ../../../../../../../../dev/zero\n" + kTetraObj);
  EXPECT_EQ(MeshLeaf::load(dir / "zero.obj")->report().triangles, 4u);
  std::filesystem::remove_all(dir);
}

std::string message_of(const std::filesystem::path& file) {
  try {
    MeshLeaf::load(file);
  } catch (const MeshError& e) {
    return e.what();
  }
  return "loaded";
}

const std::string kPlyHeader = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                               "property float z\nelement face FACES\nproperty list uchar int vertex_indices\nend_header\n";
const std::string kTetraBody = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";

std::string ply_stating(const std::string& faces, const std::string& body) {
  std::string header = kPlyHeader;
  header.replace(header.find("FACES"), 5, faces);
  return header + body;
}

// OpenMesh trusted the counts a header states (or fails to state): an empty OFF file or one starting
// "4OFF2" reserved 3 to 14 GB, one starting "BINARYF" read faces for seconds; OFF stating 30 million faces
// in 50 bytes took 46 s and 9 GB to end in a wrong message; ASCII PLY stating more faces than it
// holds was read to its end and accepted (two triangles on one face, a solid of no volume); a
// PLY count that is not a number took 65 s to end in bad_alloc.
TEST(MeshReading, CountsBeyondTheFileAreRefusedAtOnce) {
  const auto dir = test::temp_dir("mesh-counts");
  test::write_file(dir / "faces.off", "OFF\n4 30000000 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n");
  test::write_file(dir / "vertices.off", "OFF 1000000000 4 0\n0 0 0\n");
  test::write_file(dir / "negative.off", "OFF\n-1 4 0\n0 0 0\n");
  test::write_file(dir / "empty.off", "");
  test::write_file(dir / "keyword.off", "OFF\n");
  test::write_file(dir / "4OFF2.off", "4OFF2\n");
  test::write_file(dir / "BINARYF.off", "BINARYF");
  test::write_file(dir / "4OFF.off", "4OFF\n1 0 0\n0 0 0 1\n");
  test::write_file(dir / "huge_face.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4000000000 0 1 2\n");
  test::write_file(dir / "word.off", "OFF\n3 1 0\n0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n");
  // A number past the float range coordinates are read in: told as such, not as a typo.
  test::write_file(dir / "huge.off", "OFF\n3 1 0\n0 0 0\n1 1.7e308 0\n0 1 0\n3 0 1 2\n");
  test::write_file(dir / "huge.obj", "v 0 0 0\nv 1 4e38 0\nv 0 1 0\nf 1 2 3\n");
  test::write_file(dir / "binary.off", std::string("OFF BINARY\n\0\0\0\4\0\0\1\0\0\0\0\0", 23) + std::string(48, '\0'));
  test::write_file(dir / "faces.ply", ply_stating("30000000", "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n"));
  test::write_file(dir / "binary.ply",
                   "ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\nproperty double x\n"
                   "property double y\nproperty double z\nend_header\n\1\2\3");
  const std::string tet_ply = ply_stating("4", kTetraBody);
  test::write_file(dir / "nothing.ply", "ply\nformat ascii 1.0\nelement junk 2000000000\n" +
                                            tet_ply.substr(tet_ply.find("element vertex")));
  test::write_file(dir / "word.ply", kPlyHeader + kTetraBody);
  // A list size past its items made OpenMesh's reader push indices until memory ran out.
  test::write_file(dir / "list.ply", ply_stating("4", "0 0 0\n1 0 0\n0 1 0\n0 0 1\n88888888888888888888 0 2 1\n"));
  // OpenMesh's header parser crashed (SIGSEGV) on a property before any element.
  test::write_file(dir / "property.ply", "ply\nformat binary_little_endian 1.0\nproperty float y\nend_header\n");
  test::write_file(dir / "type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty real x\nend_header\n0\n");
  test::write_file(dir / "open.ply", "ply\nformat ascii 1.0\nelement vertex 1\n");
  // ... and looped forever on a version it could not read.
  test::write_file(dir / "version.ply", "ply\nformat binary_big_endian @0.\nelement vertex 0\nend_header\n");
  test::write_file(dir / "unknown.ply", "ply\nformat ascii 1.0\nelementloat x\nend_header\n");
  const auto start = std::chrono::steady_clock::now();
  for (const auto& [name, expected] : std::vector<std::pair<std::string, std::string>>{
           {"faces.off", "faces.off: the header states 4 vertices and 30000000 faces, more than the file holds "
                         "(16 numbers after the counts; a truncated file?)"},
           {"vertices.off", "vertices.off: the header states 1000000000 vertices and 4 faces"},
           {"negative.off", "negative.off: the header states a negative count (-1)"},
           {"empty.off", "empty.off: the first line must be an OFF keyword ([ST][C][N]OFF), not \"\""},
           {"BINARYF.off", "BINARYF.off: the first line must be an OFF keyword ([ST][C][N]OFF), not \"BINARYF\""},
           {"binary.off", "binary.off: binary OFF is not read (ASCII OFF, PLY and STL are)"},
           {"4OFF2.off", "4OFF2.off: the first line must be an OFF keyword ([ST][C][N]OFF), not \"4OFF2\""},
           {"4OFF.off", "4OFF.off: vertex dimensions other than 3 (4OFF, nOFF) are not read"},
           {"huge_face.off", "huge_face.off: the file ends in face 0 (it states 4000000000 vertices)"},
           {"word.off", "word.off: vertex 1: \"x\" is not a finite number (line 4)"},
           {"huge.off", "huge.off: vertex 1: \"1.7e308\" is past the float range coordinates are read in (magnitudes up to 3.4e38) (line 4)"},
           {"huge.obj", "huge.obj: vertex 1: \"4e38\" is past the float range coordinates are read in (magnitudes up to 3.4e38) (line 2)"},
           {"keyword.off", "keyword.off: no vertex and face counts after the OFF keyword"},
           {"faces.ply", "faces.ply: the file ends in element \"face\" record 1 (the header states 30000000)"},
           {"binary.ply", "binary.ply: the file ends in element \"vertex\" record 0 (the header states 2000000000)"},
           {"list.ply", "list.ply: element \"face\" record 0: a list of 88888888888888888888 items, more than the file holds"},
           {"nothing.ply", "nothing.ply: element \"junk\" states 2000000000 records but no properties"},
           {"word.ply", "word.ply: the header's count of element \"face\" is not a whole number (FACES)"},
           {"property.ply", "property.ply: a property before any element (header line 3)"},
           {"type.ply", "type.ply: a property without a valid type or name (header line 4)"},
           {"open.ply", "open.ply: the header does not end (no end_header line)"},
           {"version.ply", "version.ply: unknown PLY version \"@0.\" (1.0 is the only one) (header line 2)"},
           {"unknown.ply", "unknown.ply: unknown header line \"elementloat\" (header line 3)"}}) {
    const std::string m = message_of(dir / name);
    EXPECT_NE(m.find(expected), std::string::npos) << m;
  }
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));

  // Counts that fit still load, whatever the layout of the numbers.
  test::write_file(dir / "tet.ply", tet_ply);
  EXPECT_EQ(message_of(dir / "tet.ply"), "loaded");
  test::write_file(dir / "tet.off", "OFF\n4 4 6\n" + kTetraBody);
  EXPECT_EQ(message_of(dir / "tet.off"), "loaded");
  // Coordinates below the float range (noise an exporter left) read as the float they round to,
  // 0 here; they were refused as "not a finite number".
  test::write_file(dir / "noise.off", "OFF\n4 4 6\n0 0 0\n1 1e-50 0\n0 1 -4e-400\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  EXPECT_EQ(message_of(dir / "noise.off"), "loaded");
  test::write_file(dir / "noise.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 3e-45 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  EXPECT_EQ(message_of(dir / "noise.obj"), "loaded");
  std::filesystem::remove_all(dir);
}

// OpenMesh's OFF reader, given a stream, never read the keyword: COFF's colours and NOFF's
// normals were taken for faces (faces of 0 vertices). OFF is now read by HybridTree itself.
TEST(MeshReading, OffVariantsLoad) {
  const auto dir = test::temp_dir("mesh-off-variants");
  test::write_file(dir / "c.off", "COFF\n4 4 6\n0 0 0 255 0 0\n1 0 0 255 0 0 255\n0 1 0 1.0 0.5 0.5\n0 0 1\n"
                                   "3 0 2 1 0 255 0\n3 0 1 3\n3 0 3 2 0.5 0.5 0.5 1.0\n3 1 2 3\n");
  test::write_file(dir / "n.off", "NOFF\n4 4 6\n0 0 0 0 0 -1\n1 0 0 1 0 0\n0 1 0 0 1 0\n0 0 1 0 0 1\n"
                                   "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  test::write_file(dir / "st.off", "STOFF\n4 4 6\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n0 0 1 1 1\n" +
                                       kTetraBody.substr(kTetraBody.find("3 0")));
  for (const char* name : {"c.off", "n.off", "st.off"}) {
    SCOPED_TRACE(name);
    EXPECT_EQ(message_of(dir / name), "loaded");
    const auto leaf = MeshLeaf::load(dir / name);
    EXPECT_EQ(leaf->report().triangles, 4u);
    EXPECT_EQ(leaf->positions()[3], glm::dvec3(0, 0, 1));
  }
  std::filesystem::remove_all(dir);
}

// OpenMesh's OBJ reader asserted, aborting the process, on a corner with no vertex index, and
// dropped faces of fewer than three corners without a word. OBJ is now read by HybridTree.
TEST(MeshReading, ObjFacesAreReadOrRefusedByName) {
  const auto dir = test::temp_dir("mesh-obj");
  const std::string v = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n";
  test::write_file(dir / "corner.obj", v + "f /1/8 2 3\n");
  test::write_file(dir / "short.obj", v + "f 1 3 2\nf 1 2\n");
  test::write_file(dir / "word.obj", v + "f 1 3 x\n");
  test::write_file(dir / "vertex.obj", "v 0 0\n");
  test::write_file(dir / "range.obj", v + "f 1 3 9\n");
  for (const auto& [name, expected] : std::vector<std::pair<std::string, std::string>>{
           {"corner.obj", "corner.obj: face 0: \"/1/8\" is not a vertex index (line 5)"},
           {"short.obj", "short.obj: face 1 has only 2 vertices"},
           {"word.obj", "word.obj: face 0: \"x\" is not a vertex index (line 5)"},
           {"vertex.obj", "vertex.obj: vertex 0: needs three coordinates (line 1)"},
           {"range.obj", "range.obj: face 0 has an out-of-range vertex index"}}) {
    const std::string m = message_of(dir / name);
    EXPECT_NE(m.find(expected), std::string::npos) << m;
  }
  // Corners with texture and normal indices, negative (relative) indices, a face naming vertices
  // listed after it, and statements that are not geometry.
  test::write_file(dir / "tet.obj", "o t\nf 1/1/1 3//1 2/2\n" + v +
                                        "vt 0 0\nvn 0 0 1\ng side\nusemtl x\ns 1\nl 1 2\n"
                                        "f -4 -3 -1\nf 1 4 3 # comment\nf 2 3 4\n");
  const auto tet = MeshLeaf::load(dir / "tet.obj");
  EXPECT_EQ(tet->report().triangles, 4u);
  EXPECT_EQ(tet->positions()[3], glm::dvec3(0, 0, 1));
  std::filesystem::remove_all(dir);
}

// Embree asserts, aborting the process, on a ray from past about 1.8e18: a vertex at 5.5e24 put
// the orientation probe there. Such meshes are refused; points that far are answered without
// Embree.
TEST(MeshReading, CoordinatesEmbreeCannotReachAreRefused) {
  const auto dir = test::temp_dir("mesh-far");
  test::write_file(dir / "far.off", "OFF\n4 4 0\n0 0 0\n5.5e24 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  EXPECT_EQ(message_of(dir / "far.off"), (dir / "far.off").string() +
                                             ": vertex 1 lies beyond 1e18 on an axis, farther than the ray queries reach");
  test::write_file(dir / "tet.off", "OFF\n4 4 0\n" + kTetraBody);
  const auto tet = MeshLeaf::load(dir / "tet.off");
  for (const double x : {2e18, 1e30, -1e100}) {
    const glm::dvec3 p(x, 0.25, 0.25);
    EXPECT_FALSE(tet->inside(p));
    EXPECT_FALSE(std::isfinite(tet->query(p, 1.0).distance));
    const MeshLeaf::Closest all = tet->query(p, 1e308);  // the walk over triangles
    EXPECT_NEAR(all.distance, std::abs(x) - (x > 0 ? 1.0 : 0.0), 1e-12 * std::abs(x));
    EXPECT_FALSE(all.inside);
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace ht
