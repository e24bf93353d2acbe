#include "errors.h"
#include "exabricks/core/error.h"
#include "exabricks/io/load.h"
#include "exabricks/io/vtk_amr.h"
#include "reader_checks.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <tuple>

using namespace exa;
using namespace exa::test;
namespace fs = std::filesystem;

namespace {

double truth(double x, double y, double z) { return x * y - 0.5 * z + std::cos(x); }

struct VBox {
  int level;
  int lo[3], hi[3];
};

std::string base64(const std::string& bytes) {
  static const char* a = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    uint32_t v = uint32_t((unsigned char)bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= uint32_t((unsigned char)bytes[i + 1]) << 8;
    if (i + 2 < bytes.size()) v |= uint32_t((unsigned char)bytes[i + 2]);
    out += a[(v >> 18) & 63];
    out += a[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? a[(v >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? a[v & 63] : '=';
  }
  return out;
}

/// Three levels (ratios 2 and 4) with origin (1, 2, 3); cell arrays rho = truth(centre),
/// T = 2 rho + level, a vtkGhostType array and a 3-component array that is not a field.
struct VtkFixture {
  fs::path dir;
  std::string format = "ascii"; ///< ascii, binary or appended
  bool bigEndian = false;
  bool header64 = false;
  bool zlib = false;
  size_t zlibBlock = 64; ///< nominal block size; VTK writes 32768, larger than small arrays
  bool lastZero = false; ///< a last block of whole size written as 0, as VTK does
  bool float32 = false;
  int ratio2 = 4;
  std::string gridDescription = "XYZ";
  bool truncate = false;    ///< cut the last piece's file inside its appended data
  bool wrongExtent = false; ///< level-1 piece one cell short in z
  std::vector<VBox> boxes{{0, {0, 0, 0}, {3, 3, 3}}, {1, {2, 2, 2}, {5, 5, 3}}, {2, {12, 12, 8}, {19, 19, 11}}};

  double spacing(int level) const { return level == 0 ? 0.25 : level == 1 ? 0.125 : 0.125 / ratio2; }
  fs::path file() const { return dir / "data.vthb"; }

  std::string number(uint64_t v, size_t bytes) const {
    std::string s(bytes, '\0');
    for (size_t i = 0; i < bytes; ++i)
      s[bigEndian ? bytes - 1 - i : i] = char((v >> (8 * i)) & 0xff);
    return s;
  }
  std::string encodeValues(const std::vector<double>& v, bool asFloat) const {
    std::string out;
    for (double d : v) {
      unsigned char b[8];
      const size_t n = asFloat ? 4 : 8;
      if (asFloat) {
        const float f = float(d);
        std::memcpy(b, &f, 4);
      } else {
        std::memcpy(b, &d, 8);
      }
      for (size_t i = 0; i < n; ++i)
        out += char(b[bigEndian ? n - 1 - i : i]);
    }
    return out;
  }
  /// Header and data of one array; for base64 the two are returned apart.
  std::pair<std::string, std::string> block(const std::string& data) const {
    const size_t hb = header64 ? 8 : 4;
    if (!zlib) return {number(data.size(), hb), data};
    const size_t bs = zlibBlock;
    const size_t nb = (data.size() + bs - 1) / bs;
    const size_t last = data.size() - (nb - 1) * bs;
    std::string header = number(nb, hb) + number(bs, hb) + number(lastZero && last == bs ? 0 : last, hb), packed;
    for (size_t b = 0; b < nb; ++b) {
      const std::string part = data.substr(b * bs, bs);
      uLongf size = compressBound(uLong(part.size()));
      std::string out(size, '\0');
      compress2(reinterpret_cast<Bytef*>(out.data()), &size, reinterpret_cast<const Bytef*>(part.data()),
                uLong(part.size()), 6);
      out.resize(size);
      header += number(out.size(), hb);
      packed += out;
    }
    return {header, packed};
  }

  void write() const {
    fs::remove_all(dir);
    fs::create_directories(dir / "data");
    std::ofstream h(file());
    h << "<?xml version=\"1.0\"?>\n<VTKFile type=\"vtkOverlappingAMR\" version=\"1.1\" byte_order=\"LittleEndian\" "
         "header_type=\"UInt32\">\n  <vtkOverlappingAMR origin=\"1 2 3\" grid_description=\""
      << gridDescription << "\">\n";
    for (int l = 0; l < 3; ++l) {
      h << "    <Block level=\"" << l << "\" spacing=\"" << spacing(l) << " " << spacing(l) << " " << spacing(l)
        << "\">\n";
      int index = 0;
      for (size_t bi = 0; bi < boxes.size(); ++bi) {
        const VBox& b = boxes[bi];
        if (b.level != l) continue;
        const std::string piece = "data/data_" + std::to_string(l) + "_" + std::to_string(index) + ".vti";
        h << "      <DataSet index=\"" << index++ << "\" amr_box=\"" << b.lo[0] << " " << b.hi[0] << " " << b.lo[1]
          << " " << b.hi[1] << " " << b.lo[2] << " " << b.hi[2] << "\" file=\"" << piece << "\"/>\n";
        writePiece(dir / piece, b, bi + 1 == boxes.size());
      }
      h << "    </Block>\n";
    }
    h << "  </vtkOverlappingAMR>\n</VTKFile>\n";
  }

  void writePiece(const fs::path& path, const VBox& b, bool last) const {
    int n[3];
    for (int a = 0; a < 3; ++a)
      n[a] = b.hi[a] - b.lo[a] + 1;
    if (wrongExtent && b.level == 1) n[2] -= 1;
    const double s = spacing(b.level);
    std::vector<double> rho, temp, ghost, vel;
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i) {
          const double t = truth(1 + (b.lo[0] + i + 0.5) * s, 2 + (b.lo[1] + j + 0.5) * s, 3 + (b.lo[2] + k + 0.5) * s);
          rho.push_back(t);
          temp.push_back(2 * t + b.level);
          ghost.push_back(0);
          vel.insert(vel.end(), {1, 2, 3});
        }
    std::ostringstream out, appended;
    out.precision(17);
    out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\""
        << (bigEndian ? "BigEndian" : "LittleEndian") << "\" header_type=\"" << (header64 ? "UInt64" : "UInt32") << "\""
        << (zlib ? " compressor=\"vtkZLibDataCompressor\"" : "") << ">\n<ImageData WholeExtent=\"" << b.lo[0] << " "
        << b.lo[0] + n[0] << " " << b.lo[1] << " " << b.lo[1] + n[1] << " " << b.lo[2] << " " << b.lo[2] + n[2]
        << "\" Origin=\"1 2 3\" Spacing=\"" << s << " " << s << " " << s << "\">\n<Piece Extent=\"" << b.lo[0] << " "
        << b.lo[0] + n[0] << " " << b.lo[1] << " " << b.lo[1] + n[1] << " " << b.lo[2] << " " << b.lo[2] + n[2]
        << "\">\n<PointData>\n</PointData>\n<CellData Scalars=\"rho\">\n";
    auto array = [&](const char* name, const std::vector<double>& v, const char* type, bool asFloat, int comps) {
      out << "<DataArray type=\"" << type << "\" Name=\"" << name << "\" NumberOfComponents=\"" << comps
          << "\" format=\"" << format << "\"";
      if (format == "ascii") {
        out << ">\n";
        for (double d : v)
          out << d << " ";
        out << "\n</DataArray>\n";
        return;
      }
      std::string bytes;
      if (std::string(type) == "UInt8") {
        for (double d : v)
          bytes += char(int(d));
      } else {
        bytes = encodeValues(v, asFloat);
      }
      const auto [head, data] = block(bytes);
      if (format == "binary") {
        out << ">\n" << (zlib ? base64(head) + base64(data) : base64(head + data)) << "\n</DataArray>\n";
      } else {
        out << " offset=\"" << appended.str().size() << "\"/>\n";
        appended << head << data;
      }
    };
    array("vtkGhostType", ghost, "UInt8", false, 1);
    array("rho", rho, float32 ? "Float32" : "Float64", float32, 1);
    array("vel", vel, "Float32", true, 3);
    array("T", temp, "Float64", false, 1);
    out << "</CellData>\n</Piece>\n</ImageData>\n";
    std::string tail;
    if (format == "appended") {
      tail = "<AppendedData encoding=\"raw\">\n_" + appended.str() + "\n</AppendedData>\n";
    }
    std::ofstream(path, std::ios::binary) << out.str() << tail << "</VTKFile>\n";
    if (truncate && last) fs::resize_file(path, fs::file_size(path) - 60); // ends inside the data
  }
};

/// Independent truth for the fixture's boxes `read`: the cells of each box not under a box of the
/// next level among them. (x, y, z, exabricks level) -> VTK level.
std::map<std::tuple<int, int, int, int>, int> expectedLeaves(const std::vector<VBox>& read) {
  const int widths[3] = {8, 4, 1};
  std::map<std::tuple<int, int, int, int>, int> expected;
  for (const VBox& b : read)
    for (int k = b.lo[2]; k <= b.hi[2]; ++k)
      for (int j = b.lo[1]; j <= b.hi[1]; ++j)
        for (int i = b.lo[0]; i <= b.hi[0]; ++i) {
          const int w = widths[b.level];
          bool covered = false;
          for (const VBox& c : read) {
            if (c.level != b.level + 1) continue;
            const int cw = widths[c.level];
            covered |= i * w >= c.lo[0] * cw && i * w < (c.hi[0] + 1) * cw && j * w >= c.lo[1] * cw &&
                       j * w < (c.hi[1] + 1) * cw && k * w >= c.lo[2] * cw && k * w < (c.hi[2] + 1) * cw;
          }
          if (!covered) expected[{i * w, j * w, k * w, b.level == 0 ? 3 : b.level == 1 ? 2 : 0}] = b.level;
        }
  return expected;
}

} // namespace

TEST(VtkAmr, LeafCellsInEveryEncoding) {
  struct Variant {
    const char* format;
    bool bigEndian, header64, zlib, float32;
    size_t zlibBlock = 64;
    bool lastZero = false;
  };
  const Variant variants[] = {{"ascii", false, false, false, false},
                              {"binary", false, false, false, true},
                              {"binary", true, true, false, false},
                              {"appended", false, true, false, false},
                              {"appended", true, false, false, true},
                              {"appended", false, false, true, true},
                              {"binary", true, true, true, false},
                              {"appended", true, true, true, false},
                              // As VTK writes small arrays: one block, smaller than the nominal 32768.
                              {"appended", false, false, true, true, 32768},
                              {"binary", false, true, true, false, 32768},
                              // Several blocks with a short last one, UInt32 and UInt64 headers.
                              {"appended", false, false, true, false, 100},
                              {"binary", true, true, true, true, 100},
                              // Whole blocks only: the last block's size written as 0.
                              {"appended", false, false, true, false, 64, true},
                              {"binary", false, true, true, true, 64, true}};
  int vi = 0;
  for (const Variant& v : variants) {
    SCOPED_TRACE(vi);
    VtkFixture f;
    f.dir = fs::path(EXABRICKS_TEST_TMP) / ("vtk" + std::to_string(vi++));
    f.format = v.format;
    f.bigEndian = v.bigEndian;
    f.header64 = v.header64;
    f.zlib = v.zlib;
    f.zlibBlock = v.zlibBlock;
    f.lastZero = v.lastZero;
    f.float32 = v.float32;
    f.write();
    const std::string path = f.file().string();
    ASSERT_TRUE(isVtkAmrFile(path));
    EXPECT_EQ(detectInput(path), InputKind::VtkAmr);
    EXPECT_EQ(listFields(path), (std::vector<std::string>{"rho", "T"}));
    const CellSet s = loadCells(path);
    EXPECT_EQ(s.world.origin, vec3d(1, 2, 3));
    EXPECT_EQ(s.world.scale, vec3d(0.125 / 4));
    const auto expected = expectedLeaves(f.boxes);
    ASSERT_EQ(s.size(), expected.size());
    ASSERT_EQ(s.fields.size(), 2u);
    for (size_t i = 0; i < s.size(); ++i) {
      const Cell& c = s.cells[i];
      const auto it = expected.find({c.lower.x, c.lower.y, c.lower.z, c.level});
      ASSERT_NE(it, expected.end()) << c.lower.x << " " << c.lower.y << " " << c.lower.z << " level " << c.level;
      const vec3d centre = s.world.toWorld(vec3d(c.lower) + vec3d(0.5 * c.width()));
      const double t = truth(centre.x, centre.y, centre.z);
      EXPECT_NEAR(s.fields[0].values[i], t, 1e-6 * (1 + std::abs(t)));
      EXPECT_NEAR(s.fields[1].values[i], 2 * t + it->second, 1e-5 * (1 + std::abs(t)));
    }
  }
}

TEST(VtkAmr, CoarseLevelsAloneFromTheBoxes) {
  // The .vthb file's boxes give each level's cells; a read of the coarse levels leaves out the
  // finer boxes' pieces, and the cells under them are leaves with their own stored values.
  VtkFixture f;
  f.dir = fs::path(EXABRICKS_TEST_TMP) / "vtk-coarse";
  f.write();
  const std::string path = f.file().string();
  std::vector<double> expectedCells(size_t(kMaxLevel) + 1, 0.0);
  expectedCells[0] = 8 * 8 * 4, expectedCells[2] = 4 * 4 * 2, expectedCells[3] = 4 * 4 * 4;
  EXPECT_EQ(vtkAmrLevelCells(path), expectedCells);
  ASSERT_EQ(coarseFirstChoices(path).size(), 3u);
  const int widths[3] = {8, 4, 1};
  for (int finest = 0; finest <= 3; ++finest) {
    SCOPED_TRACE(finest);
    LoadOptions o;
    o.finestLevel = finest;
    const CellSet s = loadCells(path, o);
    EXPECT_EQ(s.world.scale, vec3d(0.125 / 4)); // the finest level's lattice, whichever are read
    std::vector<VBox> read;
    for (const VBox& b : f.boxes)
      if (widths[b.level] >= (1 << finest)) read.push_back(b);
    expectCoarseLeaves(
        s, expectedLeaves(read), finest, 32.0,
        [](const vec3d& p, int level) { return 2 * truth(p.x, p.y, p.z) + level; }, 1e-5 * 20);
  }
}

TEST(VtkAmr, CensusFromTheBoxesAndABuildFromThemEqualTheCells) {
  VtkFixture f;
  f.dir = fs::path(EXABRICKS_TEST_TMP) / "vtk-parts";
  f.write();
  const std::string path = f.file().string();
  const size_t leaves = loadCells(path).size();
  const Census census = vtkAmrCensus(path);
  EXPECT_EQ(census.cells(), double(leaves));
  EXPECT_EQ(census.coarsestLevel, 3);
  expectBoxBuildEqualsCells(path, 2, leaves);
}

TEST(VtkAmr, BadFilesAreRejectedClearly) {
  const fs::path base = fs::path(EXABRICKS_TEST_TMP) / "vtk-bad";
  auto errorFor = [&](const std::string& name, auto change) {
    VtkFixture f;
    f.dir = base / name;
    f.format = "appended";
    change(f);
    f.write();
    return loadError(f.file().string());
  };
  expectIn(errorFor("flat", [](VtkFixture& f) { f.gridDescription = "XY"; }), {"data.vthb", "XY", "3-D"});
  expectIn(errorFor("ratio3", [](VtkFixture& f) { f.ratio2 = 3; }), {"data.vthb", "spacing", "not a power of two"});
  expectIn(errorFor("cut", [](VtkFixture& f) { f.truncate = true; }), {"data_2_0.vti", "truncated"});
  expectIn(errorFor("cutz",
                    [](VtkFixture& f) {
                      f.truncate = true;
                      f.zlib = true;
                    }),
           {"data_2_0.vti", "truncated"});
  expectIn(errorFor("extent", [](VtkFixture& f) { f.wrongExtent = true; }),
           {"data_1_0.vti", "level 1 DataSet 0", "amr_box"});
  {
    VtkFixture f;
    f.dir = base / "missing";
    f.write();
    fs::remove(f.dir / "data" / "data_1_0.vti");
    expectIn(loadError(f.file().string()), {"data_1_0.vti", "missing piece"});
  }
  {
    VtkFixture f;
    f.dir = base / "header";
    f.write();
    std::ofstream(f.file())
        << "<?xml version=\"1.0\"?>\n<VTKFile type=\"vtkOverlappingAMR\">\n<vtkOverlappingAMR origin=\"0 0\">";
    expectIn(loadError(f.file().string()), {"data.vthb", "origin"});
  }
}

TEST(VtkAmr, CorruptedPiecesGiveErrorsNotCrashes) {
  // Every truncation point and a byte flipped at every position of one compressed piece and
  // of the hierarchy: the reader either succeeds or throws exa::Error, nothing else.
  VtkFixture f;
  f.dir = fs::path(EXABRICKS_TEST_TMP) / "vtk-corrupt";
  f.format = "appended";
  f.zlib = true;
  f.write();
  for (const fs::path& target : {f.dir / "data" / "data_1_0.vti", f.file()}) {
    std::string original;
    {
      std::ifstream in(target, std::ios::binary);
      std::stringstream ss;
      ss << in.rdbuf();
      original = ss.str();
    }
    const size_t step = std::max<size_t>(1, original.size() / 120);
    for (size_t at = 0; at < original.size(); at += step) {
      for (int mode = 0; mode < 2; ++mode) {
        std::string bytes = original;
        if (mode == 0)
          bytes.resize(at);
        else
          bytes[at] = char(bytes[at] ^ 0x5a);
        std::ofstream(target, std::ios::binary) << bytes;
        try {
          readVtkAmr(f.file().string());
        } catch (const Error&) {
        } catch (const std::exception& e) {
          ADD_FAILURE() << target.filename() << " mode " << mode << " at " << at << ": " << e.what();
        }
      }
    }
    std::ofstream(target, std::ios::binary) << original;
  }
}

TEST(VtkAmr, CompressionHeadersAsVtkWritesThem) {
  // One piece of 3x2x2 = 12 Float64 cells (96 bytes), hand-made: "1 32768 96 N" (one block
  // shorter than the nominal size), then corrupt headers that must be refused by name.
  const fs::path dir = fs::path(EXABRICKS_TEST_TMP) / "vtk-zlib-header";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::string plain;
  for (int i = 0; i < 12; ++i) {
    const double d = i;
    plain.append(reinterpret_cast<const char*>(&d), 8);
  }
  uLongf size = compressBound(uLong(plain.size()));
  std::string packed(size, '\0');
  compress2(reinterpret_cast<Bytef*>(packed.data()), &size, reinterpret_cast<const Bytef*>(plain.data()),
            uLong(plain.size()), 6);
  packed.resize(size);
  auto u32 = [](uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
  auto write = [&](const std::string& header, const std::string& data) {
    std::ofstream(dir / "data.vthb") << "<VTKFile type=\"vtkOverlappingAMR\" version=\"1.1\">\n"
                                        "<vtkOverlappingAMR origin=\"0 0 0\" grid_description=\"XYZ\">\n"
                                        "<Block level=\"0\" spacing=\"1 1 1\">\n"
                                        "<DataSet index=\"0\" amr_box=\"0 2 0 1 0 1\" file=\"p.vti\"/>\n"
                                        "</Block>\n</vtkOverlappingAMR>\n</VTKFile>\n";
    std::ofstream(dir / "p.vti", std::ios::binary)
        << "<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt32\" "
           "compressor=\"vtkZLibDataCompressor\">\n<ImageData WholeExtent=\"0 3 0 2 0 2\">\n<Piece Extent=\"0 3 0 2 0 "
           "2\">\n"
           "<CellData>\n<DataArray type=\"Float64\" Name=\"rho\" format=\"appended\" offset=\"0\"/>\n</CellData>\n"
           "</Piece>\n</ImageData>\n<AppendedData encoding=\"raw\">\n_"
        << header << data << "\n</AppendedData>\n</VTKFile>\n";
    return (dir / "data.vthb").string();
  };
  const CellSet s = loadCells(write(u32(1) + u32(32768) + u32(96) + u32(uint32_t(packed.size())), packed));
  ASSERT_EQ(s.size(), 12u);
  for (size_t i = 0; i < 12; ++i)
    EXPECT_EQ(s.fields[0].values[i], float(i));
  expectIn(loadError(write(u32(1) + u32(32768) + u32(40000) + u32(uint32_t(packed.size())), packed)),
           {"p.vti", "array 'rho'", "corrupt compression header", "last block of 40000 bytes"});
  expectIn(loadError(write(u32(1) + u32(0) + u32(0) + u32(uint32_t(packed.size())), packed)),
           {"p.vti", "array 'rho'", "block size 0"});
  expectIn(loadError(write(u32(1) + u32(32768) + u32(96) + u32(1u << 30), packed)),
           {"p.vti", "array 'rho'", "compressed blocks", "bytes are present"});
  expectIn(loadError(write(u32(4000000) + u32(1) + u32(1), "")),
           {"p.vti", "array 'rho'", "corrupt compression header"});
  expectIn(loadError(write(u32(3) + u32(32) + u32(32) + u32(10) + u32(10) + u32(10), std::string(30, 'x'))),
           {"p.vti", "array 'rho'", "zlib block 0", "corrupt data"});
}
