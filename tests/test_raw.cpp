#include "errors.h"
#include "exabricks/core/error.h"
#include "exabricks/io/load.h"
#include "exabricks/io/raw.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

using namespace exa;
using namespace exa::test;
namespace fs = std::filesystem;

namespace {

/// A volume with a constant slab (merges to the top level), a gentle ramp (merges partly) and
/// a rough region (stays at voxel level).
double voxel(int x, int y, int z) {
  if (z < 16) return 5.0;
  if (x < 20) return 0.001 * (x + y + z);
  return std::sin(0.9 * x) * std::cos(1.3 * y) + 0.1 * z;
}

const vec3l kDims(40, 36, 32);

std::vector<float> denseVolume() {
  std::vector<float> v;
  for (int z = 0; z < kDims.z; ++z)
    for (int y = 0; y < kDims.y; ++y)
      for (int x = 0; x < kDims.x; ++x)
        v.push_back(float(voxel(x, y, z)));
  return v;
}

/// Every voxel must lie in exactly one cell, within the threshold of the cell's value.
void checkAgainstVolume(const CellSet& s, const std::vector<float>& dense, double threshold) {
  std::vector<int> hits(dense.size(), 0);
  for (size_t i = 0; i < s.size(); ++i) {
    const Cell& c = s.cells[i];
    const int w = c.width();
    ASSERT_EQ(c.lower.x % w, 0);
    for (int z = c.lower.z; z < c.lower.z + w; ++z)
      for (int y = c.lower.y; y < c.lower.y + w; ++y)
        for (int x = c.lower.x; x < c.lower.x + w; ++x) {
          ASSERT_TRUE(x < kDims.x && y < kDims.y && z < kDims.z) << "cell reaches outside the volume";
          const size_t v = size_t((z * kDims.y + y) * kDims.x + x);
          ++hits[v];
          ASSERT_LE(std::abs(double(dense[v]) - double(s.fields[0].values[i])), threshold + 1e-6)
              << "voxel " << x << " " << y << " " << z << " in a level-" << c.level << " cell";
        }
  }
  for (size_t v = 0; v < hits.size(); ++v)
    ASSERT_EQ(hits[v], 1) << "voxel " << v;
}

void writeRaw(const fs::path& path, const std::string& type, const std::vector<float>& dense) {
  fs::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  for (float f : dense) {
    if (type == "uint8") {
      const uint8_t b = uint8_t(std::lround(std::clamp(f * 10.0f + 20.0f, 0.0f, 255.0f)));
      out.put(char(b));
    } else if (type == "uint16") {
      const uint16_t u = uint16_t(std::lround(std::clamp(f * 1000.0f + 3000.0f, 0.0f, 65535.0f)));
      out.put(char(u & 0xff)).put(char(u >> 8));
    } else if (type == "float32") {
      out.write(reinterpret_cast<const char*>(&f), 4);
    } else {
      const double d = f;
      out.write(reinterpret_cast<const char*>(&d), 8);
    }
  }
}

} // namespace

TEST(Raw, MergedCellsAgreeWithTheVolumeWithinTheThreshold) {
  const std::vector<float> dense = denseVolume();
  for (double threshold : {0.0, 0.01, 0.5}) {
    SCOPED_TRACE(threshold);
    const CellSet s = mergeDenseVolume(dense, kDims, threshold, 4);
    checkAgainstVolume(s, dense, threshold);
    validateCells(s, "merged");
    int top = 0;
    for (const Cell& c : s.cells)
      top = std::max(top, c.level);
    EXPECT_EQ(top, 4);                         // the constant slab merges to 16^3 cells
    EXPECT_LT(s.size(), dense.size() * 3 / 5); // the slab alone is half the volume
  }
  // A larger threshold never gives more cells; a lower maximum level caps the cell size.
  EXPECT_LE(mergeDenseVolume(dense, kDims, 0.5, 4).size(), mergeDenseVolume(dense, kDims, 0.01, 4).size());
  for (const Cell& c : mergeDenseVolume(dense, kDims, 0.5, 2).cells)
    EXPECT_LE(c.level, 2);
  EXPECT_EQ(mergeDenseVolume(dense, kDims, 1e9, 0).size(), dense.size());
}

TEST(Raw, FilesOfEveryTypeByNameAndByOptions) {
  const std::vector<float> dense = denseVolume();
  const fs::path dir = fs::path(EXABRICKS_TEST_TMP) / "raw";
  for (const std::string type : {"uint8", "uint16", "float32", "float64"}) {
    SCOPED_TRACE(type);
    const fs::path named = dir / ("vol_40x36x32_" + type + ".raw");
    writeRaw(named, type, dense);
    ASSERT_EQ(detectInput(named.string()), InputKind::Raw);
    // The values as stored, for the comparison.
    std::vector<float> stored;
    for (float f : dense)
      stored.push_back(type == "uint8"    ? float(std::lround(std::clamp(f * 10.0f + 20.0f, 0.0f, 255.0f)))
                       : type == "uint16" ? float(std::lround(std::clamp(f * 1000.0f + 3000.0f, 0.0f, 65535.0f)))
                                          : f);
    LoadOptions o;
    o.raw.threshold = type == "uint8" ? 1.0 : type == "uint16" ? 10.0 : 0.01;
    const CellSet s = loadCells(named.string(), o);
    checkAgainstVolume(s, stored, o.raw.threshold);
    EXPECT_EQ(s.fields.at(0).name, "scalar");
    // The same bytes under a plain name with explicit dimensions and type.
    const fs::path plain = dir / ("plain_" + type + ".raw");
    fs::copy_file(named, plain, fs::copy_options::overwrite_existing);
    o.raw.dims = kDims;
    o.raw.type = type;
    EXPECT_EQ(loadCells(plain.string(), o).cells, s.cells);
  }
}

TEST(Raw, BadVolumesAreRejectedClearly) {
  const fs::path dir = fs::path(EXABRICKS_TEST_TMP) / "raw-bad";
  const std::vector<float> dense = denseVolume();
  writeRaw(dir / "short_40x36x33_float32.raw", "float32", dense);
  std::string m = loadError((dir / "short_40x36x33_float32.raw").string());
  EXPECT_NE(m.find("short_40x36x33_float32.raw"), std::string::npos) << m;
  EXPECT_NE(m.find("wrong dimensions"), std::string::npos) << m;
  writeRaw(dir / "anon.raw", "uint8", dense);
  m = loadError((dir / "anon.raw").string());
  EXPECT_NE(m.find("--raw-dims"), std::string::npos) << m;
  LoadOptions o;
  o.raw.dims = kDims;
  o.raw.type = "int7";
  m = loadError((dir / "anon.raw").string(), o);
  EXPECT_NE(m.find("unknown raw type 'int7'"), std::string::npos) << m;
  std::vector<float> bad = dense;
  bad[1234] = std::nanf("");
  writeRaw(dir / "nan_40x36x32_float32.raw", "float32", bad);
  m = loadError((dir / "nan_40x36x32_float32.raw").string());
  EXPECT_NE(m.find("voxel (34,30,0)"), std::string::npos) << m;
  EXPECT_NE(m.find("NaN"), std::string::npos) << m;
  std::vector<float> huge(size_t(kDims.x * kDims.y * kDims.z), 1.0f);
  {
    fs::create_directories(dir);
    std::ofstream out(dir / "huge_40x36x32_float64.raw", std::ios::binary);
    for (size_t i = 0; i < huge.size(); ++i) {
      const double d = i == 7 ? 1e300 : 1.0;
      out.write(reinterpret_cast<const char*>(&d), 8);
    }
  }
  m = loadError((dir / "huge_40x36x32_float64.raw").string());
  EXPECT_NE(m.find("outside the float32 range"), std::string::npos) << m;
}
