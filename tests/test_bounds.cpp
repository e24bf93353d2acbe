// Files that declare huge sizes but hold almost nothing must be refused quickly and without
// reserving memory for what they declare. Each case loads its fixture in a forked child under
// an address-space limit (RLIMIT_AS, 100 MB above what the child already maps), so that a
// regression fails here instead of swapping; the parent checks the message, the time and the
// child's peak memory. This binary starts no threads of its own before forking.
#include "exabricks/amr/model.h"
#include "exabricks/amr/scenes.h"
#include "exabricks/core/error.h"
#include "exabricks/io/load.h"
#include "exabricks/io/model_file.h"

#include "child_run.h"
#include "h5_writer.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

using namespace exa;
namespace fs = std::filesystem;

namespace {

constexpr long kLimitBytes = 100L << 20;

using test::ChildOutcome;
using test::mappedBytes;
using Outcome = ChildOutcome;

/// Loads `path` (its cells, or with `model` a model) in a child process under the memory limit;
/// the child reports the exa::Error message through a pipe and exits 0, or exits 2 when the
/// load succeeded, 3 on any other exception.
Outcome refuseInChild(const std::string& path, bool model = false) {
  return test::runInChild(kLimitBytes, 0, [&](std::string& message) {
    try {
      if (model)
        loadModel(path);
      else
        loadCells(path);
    } catch (const Error& e) {
      message = e.what();
      return 0;
    } catch (const std::exception& e) {
      message = std::string("not an exa::Error: ") + e.what();
      return 3;
    }
    message = "loaded without error";
    return 2;
  });
}

/// The fixture is refused in under a second, within the memory limit, with every part named.
void expectRefused(const fs::path& path, std::initializer_list<const char*> parts) {
  const long before = mappedBytes();
  const Outcome o = refuseInChild(path.string());
  EXPECT_EQ(o.status, 0) << o.message;
  for (const char* p : parts)
    EXPECT_NE(o.message.find(p), std::string::npos) << "'" << p << "' not in: " << o.message;
  EXPECT_LT(o.seconds, 1.0) << o.message;
  EXPECT_LT(o.peakKiB * 1024L, before + kLimitBytes) << o.message;
  std::printf("%s: refused in %.3f s, peak %ld KiB: %s\n", path.filename().c_str(), o.seconds, o.peakKiB,
              o.message.c_str());
}

fs::path fresh(const std::string& name) {
  const fs::path dir = fs::path(EXABRICKS_TEST_TMP) / "bounds" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

/// An AMReX plotfile with one level-0 box (`box`, e.g. "((0,0,0) (1023,1023,1023) (0,0,0))")
/// and `dataBytes` bytes of FAB data after the FAB header.
fs::path amrexPlotfile(const std::string& name, const std::string& box, const std::string& nvars = "1",
                       size_t dataBytes = 80) {
  const fs::path dir = fresh(name) / "plt";
  fs::create_directories(dir / "Level_0");
  std::ofstream(dir / "Header") << "HyperCLaw-V1.1\n"
                                << nvars << "\nrho\n3\n0\n0\n0 0 0\n1 1 1\n\n"
                                << box << "\n0\n1 1 1\n0\n0\n0 1 0\n0\n0 1\n0 1\n0 1\nLevel_0/Cell\n";
  std::ofstream(dir / "Level_0" / "Cell_H") << "1\n0\n1\n0\n(1 0\n" << box << "\n)\n1\nFabOnDisk: Cell_D_00000 0\n";
  std::ofstream d(dir / "Level_0" / "Cell_D_00000", std::ios::binary);
  d << "FAB ((8, (64 11 52 0 1 12 0 1023)),(8, (8 7 6 5 4 3 2 1)))" << box << " 1\n" << std::string(dataBytes, '\0');
  return dir;
}

/// A vtkOverlappingAMR file with one level-0 DataSet of cells 0..n-1 per axis and a tiny piece.
fs::path vtkHierarchy(const std::string& name, long n) {
  const fs::path dir = fresh(name);
  std::ofstream(dir / "data.vthb") << "<VTKFile type=\"vtkOverlappingAMR\" version=\"1.1\">\n"
                                   << "<vtkOverlappingAMR origin=\"0 0 0\" grid_description=\"XYZ\">\n"
                                   << "<Block level=\"0\" spacing=\"1 1 1\">\n<DataSet index=\"0\" amr_box=\"0 "
                                   << n - 1 << " 0 " << n - 1 << " 0 " << n - 1 << "\" file=\"p.vti\"/>\n"
                                   << "</Block>\n</vtkOverlappingAMR>\n</VTKFile>\n";
  std::ofstream(dir / "p.vti") << "<VTKFile type=\"ImageData\" version=\"1.0\" header_type=\"UInt32\">\n"
                               << "<ImageData WholeExtent=\"0 " << n << " 0 " << n << " 0 " << n << "\">\n"
                               << "<Piece Extent=\"0 " << n << " 0 " << n << " 0 " << n << "\">\n<CellData>\n"
                               << "<DataArray type=\"Float32\" Name=\"rho\" format=\"binary\">AAAAAA==</DataArray>\n"
                               << "</CellData>\n</Piece>\n</ImageData>\n</VTKFile>\n";
  return dir / "data.vthb";
}

/// An Enzo output whose one grid holds `n`^3 active cells; its Density dataset is `stored`^3
/// and written only when `write` (otherwise it is declared without storage).
fs::path enzoOutput(const std::string& name, int n, hsize_t stored, bool write) {
  const fs::path dir = fresh(name);
  std::ofstream(dir / "DD0001") << "TopGridRank = 3\nDomainLeftEdge = 0 0 0\nDomainRightEdge = 1 1 1\n";
  std::ofstream(dir / "DD0001.hierarchy") << "Grid = 1\nGridRank = 3\nGridDimension = " << n << " " << n << " " << n
                                          << "\nGridStartIndex = 0 0 0\nGridEndIndex = " << n - 1 << " " << n - 1 << " "
                                          << n - 1 << "\nGridLeftEdge = 0 0 0\nGridRightEdge = 1 1 1\n"
                                          << "NumberOfBaryonFields = 1\nBaryonFileName = DD0001.cpu0000\n";
  const std::string data = (dir / "DD0001.cpu0000").string();
  const std::vector<hsize_t> dims{stored, stored, stored};
  {
    h5w::Writer w(data);
    w.group("/Grid00000001");
    if (write) w.doubles("/Grid00000001/Density", dims, std::vector<double>(size_t(stored * stored * stored), 1.0));
  }
  if (!write) {
    // Declared, chunked, never written: libhdf5 would return fill values for all of it.
    const hid_t file = H5Fopen(data.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    const hid_t space = H5Screate_simple(3, dims.data(), nullptr);
    const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    const hsize_t chunk[3] = {64, 64, 64};
    H5Pset_chunk(dcpl, 3, chunk);
    H5Dclose(H5Dcreate2(file, "/Grid00000001/Density", H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT));
    H5Pclose(dcpl);
    H5Sclose(space);
    H5Fclose(file);
  }
  return dir / "DD0001";
}

/// Declares a chunked dataset of `dims` float64 values that is never written: libhdf5 would
/// return fill values for all of it.
void unwrittenDataset(const std::string& file, const std::string& name, const std::vector<hsize_t>& dims) {
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  const hid_t space = H5Screate_simple(int(dims.size()), dims.data(), nullptr);
  const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
  std::vector<hsize_t> chunk(dims.size(), 1);
  for (size_t a = 0; a < dims.size(); ++a)
    chunk[a] = std::min<hsize_t>(dims[a], 64);
  H5Pset_chunk(dcpl, int(chunk.size()), chunk.data());
  H5Dclose(H5Dcreate2(f, name.c_str(), H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT));
  H5Pclose(dcpl);
  H5Sclose(space);
  H5Fclose(f);
}

/// A one-level Chombo file whose one box holds `n`^3 cells, its data declared and never written.
fs::path chomboFile(const std::string& name, int n) {
  const fs::path path = fresh(name) / "c.hdf5";
  {
    h5w::Writer w(path.string());
    w.attrInts("/", "num_levels", {1});
    w.attrInts("/", "num_components", {1});
    w.attrString("/", "component_0", "density");
    w.group("/level_0");
    w.attrDoubles("/level_0", "dx", {1.0});
    w.intCompound("/level_0/boxes", {"lo_i", "lo_j", "lo_k", "hi_i", "hi_j", "hi_k"}, {0, 0, 0, n - 1, n - 1, n - 1});
    w.int64s("/level_0/data:offsets=0", {2}, {0, (long long)n * n * n});
  }
  unwrittenDataset(path.string(), "/level_0/data:datatype=0", {hsize_t(n) * hsize_t(n) * hsize_t(n)});
  return path;
}

/// A FLASH file of one leaf block of `n`^3 cells, its variable declared and never written.
fs::path flashFile(const std::string& name, int n) {
  const fs::path path = fresh(name) / "f.hdf5";
  {
    h5w::Writer w(path.string());
    w.ints("node type", {1}, {1});
    w.doubles("bounding box", {1, 3, 2}, {0, 1, 0, 1, 0, 1});
    w.strings("unknown names", {1, 1}, {"dens"}, 4);
    w.nameValueTable("integer scalars", {"nxb", "nyb", "nzb", "dimensionality"}, {double(n), double(n), double(n), 3.0},
                     true);
  }
  unwrittenDataset(path.string(), "dens", {1, hsize_t(n), hsize_t(n), hsize_t(n)});
  return path;
}

/// A model file whose brick array claims `count` bricks.
fs::path modelFile(const std::string& name, uint64_t count) {
  const fs::path path = fresh(name) / "m.exa";
  writeModel(buildModel(generateScene({"blobs", 200, 1, 2})), path.string());
  std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(std::streamoff(48 + sizeof(WorldTransform)));
  f.write(reinterpret_cast<const char*>(&count), sizeof count);
  return path;
}

/// Runs `exabricks info PATH` under an address-space limit of 256 MB (ulimit -v 262144): it must
/// fail in under two seconds with every part in its message and without "out of memory".
void expectCliRefuses(const fs::path& path, const std::vector<const char*>& parts) {
#ifdef EXABRICKS_ASAN
  const std::string limit = ""; // AddressSanitizer maps terabytes of shadow: no ulimit -v
#else
  const std::string limit = "ulimit -v 262144; ";
#endif
  const std::string command =
      "bash -c '" + limit + "exec \"$0\" info \"$1\"' '" + EXABRICKS_CLI + "' '" + path.string() + "' 2>&1";
  const auto start = std::chrono::steady_clock::now();
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string out;
  char buf[4096];
  for (size_t n; (n = std::fread(buf, 1, sizeof buf, pipe)) > 0;)
    out.append(buf, n);
  const int status = pclose(pipe);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 1) << "status " << status << ": " << out;
  for (const char* p : parts)
    EXPECT_NE(out.find(p), std::string::npos) << "'" << p << "' not in: " << out;
  EXPECT_EQ(out.find("out of memory"), std::string::npos) << out;
  EXPECT_LT(seconds, 2.0) << out;
  std::printf("exabricks info %s under 256 MB: refused in %.3f s: %s", path.filename().c_str(), seconds, out.c_str());
}

} // namespace

TEST(Bounds, AmrexBoxOfTwoToThe30CellsWithoutData) {
  expectRefused(amrexPlotfile("amrex-huge", "((0,0,0) (1023,1023,1023) (0,0,0))"),
                {"Cell_D_00000", "level 0 box 0", "1024x1024x1024 cells", "bytes follow the offset"});
}

TEST(Bounds, AmrexNumbersOutOfRangeBeforeConversion) {
  expectRefused(amrexPlotfile("amrex-corner", "((0,0,0) (3e102,3,3) (0,0,0))"),
                {"Header", "line 10", "box corner is 3e+102", "not an integer"});
  expectRefused(amrexPlotfile("amrex-nvars", "((0,0,0) (3,3,3) (0,0,0))", "1.3e15"),
                {"Header", "line 2", "variable count is 1.3e+15"});
}

TEST(Bounds, VtkExtentsOf1600And100000CubedWithoutData) {
  expectRefused(vtkHierarchy("vtk-1600", 1600), {"p.vti", "1600x1600x1600 cells", "too few"});
  expectRefused(vtkHierarchy("vtk-100000", 100000), {"data.vthb", "level 0 DataSet 0", "too large"});
}

TEST(Bounds, EnzoGridOf2048CubedWithoutData) {
  expectRefused(enzoOutput("enzo-shape", 2048, 4, true), {"DD0001.cpu0000", "Grid00000001/Density", "shape 4x4x4"});
  expectRefused(enzoOutput("enzo-unwritten", 2048, 2048, false),
                {"DD0001.cpu0000", "Grid00000001/Density", "declares 8589934592 values", "bytes are present"});
}

TEST(Bounds, GridsLineOf1000CubedCells) {
  const fs::path path = fresh("grids") / "big.grids";
  std::ofstream(path) << "0 0 0 1000 1000 1000 0 1.0\n";
  expectRefused(path, {"big.grids", "line 1", "1000x1000x1000", "at most"});
}

// Boxes of up to 2^33 cells in every reader whose header declares a count that drives memory:
// each is refused from the bytes present, in the library (under the limit above) and by
// `exabricks info` under an address-space limit of 256 MB.
TEST(Bounds, TwoToThe33CellsInEveryReaderUnder256MB) {
  struct Case {
    fs::path path;
    std::vector<const char*> parts;
  };
  std::vector<Case> cases;
  for (const char* box : {"((0,0,0) (1023,1023,1023) (0,0,0))", "((0,0,0) (2047,2047,2047) (0,0,0))",
                          "((0,0,0) (536870911,3,3) (0,0,0))"})
    cases.push_back({amrexPlotfile(strCat("amrex-", cases.size()), box),
                     {"Cell_D_00000", "level 0 box 0", "bytes follow the offset"}});
  {
    // Three boxes of 64^3 cells whose FABs would each fit alone, all at offset 0 of one file of
    // 1.5 MB that holds only one of them.
    const fs::path dir = fresh("amrex-shared") / "plt";
    fs::create_directories(dir / "Level_0");
    const std::string b[3] = {"((0,0,0) (63,63,63) (0,0,0))", "((64,0,0) (127,63,63) (0,0,0))",
                              "((128,0,0) (191,63,63) (0,0,0))"};
    std::ofstream(dir / "Header")
        << "HyperCLaw-V1.1\n1\nrho\n3\n0\n0\n0 0 0\n1 1 1\n\n((0,0,0) (191,63,63) (0,0,0))"
        << "\n0\n1 1 1\n0\n0\n0 3 0\n0\n0 1\n0 1\n0 1\n0 1\n0 1\n0 1\n0 1\n0 1\n0 1\nLevel_0/Cell\n";
    std::ofstream(dir / "Level_0" / "Cell_H")
        << "1\n0\n1\n0\n(3 0\n"
        << b[0] << "\n"
        << b[1] << "\n"
        << b[2] << "\n)\n3\nFabOnDisk: Cell_D_00000 0\nFabOnDisk: Cell_D_00000 0\n"
        << "FabOnDisk: Cell_D_00000 0\n";
    std::ofstream(dir / "Level_0" / "Cell_D_00000", std::ios::binary) << std::string(64 * 64 * 64 * 6, '\0');
    cases.push_back({dir, {"Cell_D_00000", "level 0 box 1", "the boxes stored in this file need"}});
  }
  cases.push_back({chomboFile("chombo", 2048), {"c.hdf5", "/level_0/data:datatype=0", "declares 8589934592 values"}});
  cases.push_back({flashFile("flash", 2048), {"f.hdf5", "dens", "declares 8589934592 values"}});
  cases.push_back({enzoOutput("enzo", 2048, 2048, false),
                   {"DD0001.cpu0000", "Grid00000001/Density", "declares 8589934592 values"}});
  cases.push_back({vtkHierarchy("vtk", 2048), {"p.vti", "2048x2048x2048 cells", "too few"}});
  {
    const fs::path raw = fresh("raw") / "v_2048x2048x2048_float32.raw";
    std::ofstream(raw, std::ios::binary) << std::string(100, '\0');
    cases.push_back({raw, {"v_2048x2048x2048_float32.raw", "holds 100 bytes", "2048x2048x2048 float32 voxels"}});
  }
  {
    const fs::path grids = fresh("grids-2048") / "big.grids";
    std::ofstream(grids) << "0 0 0 2048 2048 2048 0 1.0\n";
    cases.push_back({grids, {"big.grids", "line 1", "2048x2048x2048", "at most"}});
  }
  cases.push_back({modelFile("model", uint64_t(1) << 33), {"m.exa", "bricks", "claims 8589934592 entries"}});
  for (const Case& c : cases) {
    SCOPED_TRACE(c.path.string());
    const Outcome o = refuseInChild(c.path.string(), c.path.extension() == ".exa");
    EXPECT_EQ(o.status, 0) << o.message;
    EXPECT_LT(o.seconds, 1.0) << o.message;
    for (const char* p : c.parts)
      EXPECT_NE(o.message.find(p), std::string::npos) << "'" << p << "' not in: " << o.message;
    std::printf("%s: refused in %.3f s, peak %ld KiB\n", c.path.filename().c_str(), o.seconds, o.peakKiB);
    expectCliRefuses(c.path, c.parts);
  }
}
