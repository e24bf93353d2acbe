#include "exabricks/core/error.h"
#include "exabricks/documents/mesh.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

using namespace exa;
namespace fs = std::filesystem;

namespace {

// The fixture: a tetrahedron and a square pyramid (quad base) side by side.
const std::vector<vec3f> kVertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0},    {0, 0, 1}, // tetrahedron
                                      {2, 0, 0}, {3, 0, 0}, {3, 1, 0.5f}, {2, 1, 0}, {2.5f, 0.5f, -1.25f}}; // pyramid
const std::vector<std::vector<int>> kFaces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}, {4, 7, 6, 5},
                                              {4, 5, 8}, {5, 6, 8}, {6, 7, 8}, {7, 4, 8}};
const std::vector<vec3i> kTriangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}, {4, 7, 6},
                                       {4, 6, 5}, {4, 5, 8}, {5, 6, 8}, {6, 7, 8}, {7, 4, 8}};

/// Little or big endian binary writer.
struct Bytes {
  std::string data;
  bool big = false;
  template <typename T> Bytes& put(T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if (big != (std::endian::native == std::endian::big)) std::reverse(b, b + sizeof(T));
    data.append(b, sizeof(T));
    return *this;
  }
  Bytes& text(const std::string& s) {
    data += s;
    return *this;
  }
};

class MeshTest : public ::testing::Test {
protected:
  void SetUp() override {
    dir = fs::path(EXABRICKS_TEST_TMP) / "mesh" / ::testing::UnitTest::GetInstance()->current_test_info()->name();
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  std::string path(const std::string& name) const { return (dir / name).string(); }
  std::string write(const std::string& name, const std::string& bytes) const {
    std::ofstream(path(name), std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    return path(name);
  }
  /// The message readMesh throws for `file`, or "no error".
  static std::string errorOf(const std::string& file) {
    try {
      readMesh(file);
    } catch (const Error& e) {
      return e.what();
    }
    return "no error";
  }
  static void expectFixture(const TriangleMesh& m) {
    EXPECT_EQ(m.vertices, kVertices);
    EXPECT_EQ(m.triangles, kTriangles);
  }

  static std::string obj() {
    // Tetrahedron with plain and v/t/n indices, pyramid with negative indices, //n and a quad.
    return "# exported\r\n"
           "mtllib scene.mtl\r\n"
           "o tetra\r\n"
           "v 0 0 0\r\n"
           "v 1.0 0 0 1.0\r\n"
           "v 0 1 0 0.5 0.5 0.5\r\n"
           "v +0 0 1e0\r\n"
           "vt 0 0\r\nvt 1 0\r\nvn 0 0 1\r\n"
           "g side\r\n"
           "usemtl red\r\n"
           "s off\r\n"
           "f 1 3 2\r\n"
           "f 1/1 2/2 4/1\r\n"
           "f 1/1/1 4/2/1 3/1/1\r\n"
           "f 2//1 3//1 4//1 # a comment\r\n"
           "\r\n"
           "o pyramid\n"
           "v 2 0 0\n"
           "v 3 0 0\n"
           "v 3 1 0.5\n"
           "v 2 1 0\n"
           "v 2.5 0.5 -1.25\n"
           "curv 0 1 1 2\n"
           "f -5 -2 -3 -4\n"
           "f -5/1 -4/2 -1/1\n"
           "f 6 7 9\n"
           "f\t7  8 9 \n"
           "f 8 5 9";
  }

  static std::string plyAscii() {
    std::string s = "ply\nformat ascii 1.0\ncomment made by hand\nobj_info none\n"
                    "element vertex 9\nproperty float x\nproperty float y\nproperty float z\n"
                    "property uchar red\n"
                    "element face 9\nproperty list uchar int vertex_indices\n"
                    "element edge 2\nproperty int vertex1\nproperty int vertex2\nend_header\n";
    for (const vec3f& v : kVertices)
      s += std::to_string(v.x) + " " + std::to_string(v.y) + " " + std::to_string(v.z) + " 255\n";
    for (const auto& f : kFaces) {
      s += std::to_string(f.size());
      for (int i : f) {
        s += ' ';
        s += std::to_string(i);
      }
      s += "\n";
    }
    return s + "0 1\n1 2\n";
  }

  /// Binary PLY: extra vertex properties of several types, x/y/z of different types, an extra
  /// face list and an extra element before the faces.
  static std::string plyBinary(bool big) {
    Bytes b;
    b.big = big;
    b.text(std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
           " 1.0\ncomment extra properties and elements\n"
           "element vertex 9\nproperty uint8 red\nproperty float x\nproperty double y\n"
           "property int16 label\nproperty float32 z\nproperty float64 confidence\n"
           "element edge 2\nproperty int vertex1\nproperty int vertex2\nproperty list uchar uint extra\n"
           "element face 9\nproperty uchar flags\nproperty list uchar int vertex_indices\n"
           "property list ushort float texcoord\nend_header\n");
    for (const vec3f& v : kVertices)
      b.put<uint8_t>(7).put<float>(v.x).put<double>(v.y).put<int16_t>(-3).put<float>(v.z).put<double>(0.5);
    b.put<int32_t>(0).put<int32_t>(1).put<uint8_t>(2).put<uint32_t>(5).put<uint32_t>(6);
    b.put<int32_t>(1).put<int32_t>(2).put<uint8_t>(0);
    for (const auto& f : kFaces) {
      b.put<uint8_t>(1).put<uint8_t>(uint8_t(f.size()));
      for (int i : f)
        b.put<int32_t>(i);
      b.put<uint16_t>(2).put<float>(0.25f).put<float>(0.75f);
    }
    return b.data;
  }

  /// .tris holding the tetrahedron and the pyramid as two meshes with their own indices.
  static std::string tris() {
    Bytes b;
    b.put<int32_t>(4);
    for (int i = 0; i < 4; ++i)
      b.put(kVertices[i].x).put(kVertices[i].y).put(kVertices[i].z);
    b.put<int32_t>(4);
    for (int i = 0; i < 4; ++i)
      b.put(kTriangles[i].x).put(kTriangles[i].y).put(kTriangles[i].z);
    b.put<int32_t>(5);
    for (int i = 4; i < 9; ++i)
      b.put(kVertices[i].x).put(kVertices[i].y).put(kVertices[i].z);
    b.put<int32_t>(6);
    for (int i = 4; i < 10; ++i)
      b.put(kTriangles[i].x - 4).put(kTriangles[i].y - 4).put(kTriangles[i].z - 4);
    return b.data;
  }

  fs::path dir;
};

#define EXPECT_MESSAGE(msg, ...)                                                                                       \
  do {                                                                                                                 \
    const std::string m_ = (msg);                                                                                      \
    for (const char* part : {__VA_ARGS__})                                                                             \
      EXPECT_NE(m_.find(part), std::string::npos) << m_;                                                               \
  } while (0)

} // namespace

TEST_F(MeshTest, ObjQuadsNegativeIndicesAndCornerForms) {
  const TriangleMesh m = readMesh(write("fixture.obj", obj()));
  expectFixture(m);
  EXPECT_EQ(m.bounds(), box3f(vec3f(0, 0, -1.25f), vec3f(3, 1, 1)));
  // Faces may reference vertices defined further down.
  const TriangleMesh late = readMesh(write("late.OBJ", "f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"));
  EXPECT_EQ(late.triangles, (std::vector<vec3i>{{0, 1, 2}}));
  EXPECT_EQ(late.vertices.size(), 3u);
}

TEST_F(MeshTest, PlyAsciiAndBinaryInBothByteOrders) {
  expectFixture(readMesh(write("ascii.ply", plyAscii())));
  expectFixture(readMesh(write("little.ply", plyBinary(false))));
  expectFixture(readMesh(write("big.ply", plyBinary(true))));
  std::string crlf;
  for (char c : plyAscii())
    crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  expectFixture(readMesh(write("crlf.ply", crlf)));
  // Known by its magic line, whatever the name.
  expectFixture(readMesh(write("mesh.data", plyBinary(false))));
}

TEST_F(MeshTest, TrisWithTwoMeshesIsMerged) {
  expectFixture(readMesh(write("two.tris", tris())));
  // Without the extension it is recognised by its structure.
  expectFixture(readMesh(write("two.bin", tris())));
  EXPECT_MESSAGE(errorOf(write("junk.bin", "this is no mesh")), "junk.bin", "unknown mesh format");
}

TEST_F(MeshTest, BadInputsNameFileRecordAndProblem) {
  const std::string little = plyBinary(false);
  EXPECT_MESSAGE(errorOf(write("trunc.ply", little.substr(0, little.size() - 7))), "trunc.ply", "element 'face' 8",
                 "byte", "truncated");
  EXPECT_MESSAGE(errorOf(write("trunc2.ply", little.substr(0, little.size() - 120))), "trunc2.ply", "truncated");

  std::string absurd = plyBinary(false);
  absurd.replace(absurd.find("vertex 9"), 8, "vertex 2000000000");
  EXPECT_MESSAGE(errorOf(write("absurd.ply", absurd)), "absurd.ply", "'vertex' count 2000000000",
                 "exceeds what the file size allows");
  std::string huge = plyBinary(false);
  huge.replace(huge.find("edge 2"), 6, "edge 18446744073709551615");
  EXPECT_MESSAGE(errorOf(write("huge.ply", huge)), "huge.ply", "'edge' count", "exceeds");
  std::string negative = plyAscii();
  negative.replace(negative.find("face 9"), 6, "face -9");
  EXPECT_MESSAGE(errorOf(write("negative.ply", negative)), "negative.ply", "line 10", "negative count");
  std::string absurdTris = tris();
  const int32_t big = std::numeric_limits<int32_t>::max();
  std::memcpy(absurdTris.data(), &big, 4);
  EXPECT_MESSAGE(errorOf(write("absurd.tris", absurdTris)), "absurd.tris", "mesh 0", "byte 0",
                 "vertex count 2147483647 exceeds what the file size allows");

  std::string range = plyAscii();
  range.replace(range.find("3 1 2 3\n"), 8, "3 1 2 9\n");
  EXPECT_MESSAGE(errorOf(write("range.ply", range)), "range.ply", "element 'face' 3", "line 28",
                 "vertex index 9 out of range [0, 9)");
  EXPECT_MESSAGE(errorOf(write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n")), "range.obj", "line 4",
                 "vertex index 4 out of range");
  EXPECT_MESSAGE(errorOf(write("neg.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n")), "neg.obj", "line 4",
                 "vertex index -4 out of range");
  EXPECT_MESSAGE(errorOf(write("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n")), "zero.obj", "line 4", "index 0");
  std::string rangeTris = tris();
  const int32_t five = 5; // the pyramid has vertices 0..4 of its own
  std::memcpy(rangeTris.data() + rangeTris.size() - 4, &five, 4);
  EXPECT_MESSAGE(errorOf(write("range.tris", rangeTris)), "range.tris", "mesh 1 triangle 5",
                 "vertex index 5 out of range [0, 5)");

  EXPECT_MESSAGE(errorOf(write("nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n")), "nan.obj", "line 2",
                 "NaN or infinite");
  EXPECT_MESSAGE(errorOf(write("inf.obj", "v 0 0 0\nv 1 1e300 0\nv 0 1 0\nf 1 2 3\n")), "inf.obj", "line 2",
                 "NaN or infinite");
  std::string nanTris = tris();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(nanTris.data() + 4 + 12 + 4, &nan, 4);
  EXPECT_MESSAGE(errorOf(write("nan.tris", nanTris)), "nan.tris", "mesh 0 vertex 1", "byte 16", "NaN or infinite");
  std::string nanPly = plyBinary(true);
  const size_t at = nanPly.find("end_header\n") + 11 + 1;
  std::memset(nanPly.data() + at, 0xff, 4); // x of vertex 0: all ones is a NaN in either order
  EXPECT_MESSAGE(errorOf(write("nan.ply", nanPly)), "nan.ply", "element 'vertex' 0", "NaN or infinite");

  EXPECT_MESSAGE(errorOf(write("face.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n")), "face.obj", "line 4",
                 "malformed 'f' line", "'x'");
  EXPECT_MESSAGE(errorOf(write("short.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n")), "short.obj", "line 3", "malformed 'f' line");
  EXPECT_MESSAGE(errorOf(write("slash.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/a 2 3\n")), "slash.obj", "line 4",
                 "malformed 'f' line");
  EXPECT_MESSAGE(errorOf(write("vert.obj", "v 0 0\nf 1 1 1\n")), "vert.obj", "line 1", "malformed 'v' line");

  EXPECT_MESSAGE(errorOf(write("empty.obj", "")), "empty.obj", "empty file");
  EXPECT_MESSAGE(errorOf(write("empty.tris", "")), "empty.tris", "empty file");
  EXPECT_MESSAGE(errorOf(write("points.obj", "v 0 0 0\nv 1 0 0\n")), "points.obj", "no triangles");
  EXPECT_MESSAGE(errorOf(write("none.tris", std::string(8, '\0'))), "none.tris", "no triangles");
  EXPECT_MESSAGE(errorOf(path("missing.ply")), "missing.ply", "cannot open");

  std::string format = plyAscii();
  format.replace(format.find("ascii"), 5, "binary_middle_endian");
  EXPECT_MESSAGE(errorOf(write("format.ply", format)), "format.ply", "line 2",
                 "unknown PLY format 'binary_middle_endian'");
  std::string noY = plyAscii();
  noY.replace(noY.find("property float y"), 16, "property float q");
  EXPECT_MESSAGE(errorOf(write("noy.ply", noY)), "noy.ply", "no scalar 'y' property");
  EXPECT_MESSAGE(errorOf(write("magic.ply", "solid cube\n")), "magic.ply", "missing 'ply' magic");
  std::string noEnd = plyAscii();
  noEnd.resize(noEnd.find("end_header"));
  EXPECT_MESSAGE(errorOf(write("noend.ply", noEnd)), "noend.ply", "no 'end_header'");
  std::string truncAscii = plyAscii();
  truncAscii.resize(truncAscii.find("0 1\n1 2\n") - 5);
  EXPECT_MESSAGE(errorOf(write("truncascii.ply", truncAscii)), "truncascii.ply", "element 'face' 8", "truncated");
}

TEST_F(MeshTest, CorruptedBinaryFilesOnlyEverThrowExaError) {
  std::mt19937 rng(12345);
  const std::vector<std::pair<std::string, std::string>> seeds = {{"seed.ply", plyBinary(false)},
                                                                  {"seed_be.ply", plyBinary(true)},
                                                                  {"seed.tris", tris()},
                                                                  {"seed.dat", tris()},
                                                                  {"seed.obj", obj()}};
  int succeeded = 0, failed = 0;
  for (const auto& [name, valid] : seeds) {
    for (int iteration = 0; iteration < 400; ++iteration) {
      std::string bytes = valid;
      const int mode = int(rng() % 3);
      if (mode == 0) {
        bytes.resize(rng() % bytes.size());
      } else {
        const int flips = 1 + int(rng() % 4);
        for (int k = 0; k < flips; ++k) {
          const size_t at = rng() % bytes.size();
          bytes[at] = mode == 1 ? char(bytes[at] ^ char(1u << (rng() % 8))) : char(rng());
        }
      }
      // A fresh name each time: rewriting one file in place can force a flush per write.
      const std::string file = write(std::to_string(iteration) + name, bytes);
      try {
        const TriangleMesh m = readMesh(file);
        ++succeeded;
        ASSERT_FALSE(m.triangles.empty());
        for (const vec3i& t : m.triangles)
          for (int a = 0; a < 3; ++a) {
            ASSERT_GE(t[a], 0);
            ASSERT_LT(size_t(t[a]), m.vertices.size());
          }
        for (const vec3f& v : m.vertices)
          ASSERT_TRUE(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z));
      } catch (const Error& e) {
        ++failed;
        EXPECT_NE(std::string(e.what()).find(file), std::string::npos) << e.what();
      }
      fs::remove(file);
    }
  }
  EXPECT_GT(succeeded, 0);
  EXPECT_GT(failed, 0);
}

TEST_F(MeshTest, LargeMeshReadsQuickly) {
  // A 400 x 400 grid of quads (320,000 triangles) in every format.
  const int n = 400;
  std::string o, ascii = "ply\nformat ascii 1.0\nelement vertex " + std::to_string((n + 1) * (n + 1)) +
                         "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
                         std::to_string(n * n) + "\nproperty list uchar int vertex_indices\nend_header\n";
  Bytes t;
  t.put<int32_t>((n + 1) * (n + 1));
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const std::string xyz = std::to_string(i) + " " + std::to_string(j) + " 0.5";
      o += "v " + xyz + "\n";
      ascii += xyz + "\n";
      t.put(float(i)).put(float(j)).put(0.5f);
    }
  t.put<int32_t>(2 * n * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = b + n + 1, d = a + n + 1;
      o += "f " + std::to_string(a + 1) + " " + std::to_string(b + 1) + " " + std::to_string(c + 1) + " " +
           std::to_string(d + 1) + "\n";
      ascii +=
          "4 " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(c) + " " + std::to_string(d) + "\n";
      t.put(a).put(b).put(c).put(a).put(c).put(d);
    }
  const TriangleMesh fromObj = readMesh(write("grid.obj", o));
  const TriangleMesh fromPly = readMesh(write("grid.ply", ascii));
  const TriangleMesh fromTris = readMesh(write("grid.tris", t.data));
  ASSERT_EQ(fromObj.triangles.size(), size_t(2 * n * n));
  EXPECT_EQ(fromObj.triangles, fromPly.triangles);
  EXPECT_EQ(fromObj.triangles, fromTris.triangles);
  EXPECT_EQ(fromObj.vertices, fromTris.vertices);
  EXPECT_EQ(fromPly.bounds(), box3f(vec3f(0, 0, 0.5f), vec3f(n, n, 0.5f)));
}
