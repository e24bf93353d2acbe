// NaN and infinite values: refused by default with the record named; with NonFinite::Holes their
// cells become holes in every field, and the reconstruction equals a brute-force sum over the
// remaining cells.
#include "reference.h"

#include "exabricks/amr/model.h"
#include "exabricks/amr/scenes.h"
#include "exabricks/core/error.h"
#include "exabricks/io/load.h"
#include "exabricks/io/native.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

using namespace exa;
namespace fs = std::filesystem;

namespace {

/// Overwrites value `record` of a .scalars file.
void poke(const fs::path& scalars, size_t record, float value) {
  std::fstream f(scalars, std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(std::streamoff(record * sizeof(float)));
  f.write(reinterpret_cast<const char*>(&value), sizeof value);
}

struct HolesTest : ::testing::Test {
  void SetUp() override {
    // A folder per test: ctest runs the tests of this fixture at the same time.
    dir = fs::path(EXABRICKS_TEST_TMP) / "holes" / ::testing::UnitTest::GetInstance()->current_test_info()->name();
    fs::remove_all(dir);
    fs::create_directories(dir);
    cells = generateScene({"blobs", 3000, 1, 3}); // fields scalar and radius
    writeNative(cells, (dir / "n.cells").string());
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    const int scalar = cells.fieldIndex("scalar"), radius = cells.fieldIndex("radius");
    for (size_t r : {5, 100, 777}) {
      poke(dir / "n.scalars", r, nan);
      cells.fields[size_t(scalar)].values[r] = nan;
    }
    for (size_t r : {100, 1500}) {
      poke(dir / "n.radius.scalars", r, -inf);
      cells.fields[size_t(radius)].values[r] = -inf;
    }
  }
  fs::path dir;
  CellSet cells;
};

} // namespace

TEST_F(HolesTest, NonFiniteValuesAreRefusedByDefaultNamingTheRecord) {
  try {
    loadModel((dir / "n.cells").string());
    FAIL() << "no error";
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("record 100"), std::string::npos) << m; // radius is read first (sorted)
    EXPECT_NE(m.find("not finite"), std::string::npos) << m;
  }
  LoadOptions only;
  only.fields = {"scalar"};
  try {
    loadModel((dir / "n.cells").string(), only);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("record 5:"), std::string::npos) << e.what();
  }
}

TEST_F(HolesTest, HolesEqualABruteForceSumOverTheRemainingCells) {
  LoadOptions o;
  o.nonFinite = NonFinite::Holes;
  o.report = std::make_shared<LoadReport>();
  const Model m = loadModel((dir / "n.cells").string(), o);
  // A cell bad in any field is dropped from all: 3 + 2 bad values in 4 cells.
  EXPECT_EQ(o.report->holes, 4u);
  ASSERT_EQ(o.report->nonFinite.size(), 2u);
  for (const auto& [field, count] : o.report->nonFinite)
    EXPECT_EQ(count, field == "scalar" ? 3u : 2u) << field;
  EXPECT_EQ(m.cellCount(), cells.size() - 4);

  // The cells left: every value finite.
  std::vector<uint8_t> bad(cells.size(), 0);
  for (const Field& f : cells.fields)
    for (size_t i = 0; i < f.values.size(); ++i)
      if (!std::isfinite(f.values[i])) bad[i] = 1;
  size_t at = 0;
  CellSet kept = cells;
  keepCells(kept, [&](const Cell&) { return bad[at++] == 0; });
  ASSERT_EQ(kept.size(), cells.size() - 4);

  std::mt19937 rng(7);
  const box3l b = kept.bounds();
  std::uniform_real_distribution<double> u(0, 1);
  int compared = 0;
  for (const char* name : {"scalar", "radius"}) {
    const int mf = m.fieldIndex(name), kf = kept.fieldIndex(name);
    ASSERT_GE(mf, 0);
    for (int k = 0; k < 400; ++k) {
      vec3d p;
      for (int a = 0; a < 3; ++a)
        p[a] = double(b.lower[a]) + u(rng) * double(b.upper[a] - b.lower[a]);
      const test::Reference ref = test::bruteForce(kept, kf, p);
      double value = 0;
      const bool ok = sampleField(m.view(mf), p, value);
      EXPECT_EQ(ok, ref.valid) << name << " at " << p.x << " " << p.y << " " << p.z;
      if (ok && ref.valid) {
        EXPECT_NEAR(value, ref.value, 1e-6 * std::max(1.0, std::abs(ref.value))) << name;
        ++compared;
      }
    }
  }
  EXPECT_GT(compared, 100);
  // The holes' neighbourhoods: at the centre of each dropped cell, the sum leaves it out.
  for (size_t i = 0; i < cells.size(); ++i) {
    if (!bad[i]) continue;
    const Cell& c = cells.cells[i];
    const double w = double(int64_t(1) << c.level);
    const vec3d p = vec3d(c.lower) + vec3d(w * 0.5);
    const test::Reference ref = test::bruteForce(kept, kept.fieldIndex("scalar"), p);
    double value = 0;
    const bool ok = sampleField(m.view(m.fieldIndex("scalar")), p, value);
    EXPECT_EQ(ok, ref.valid) << "hole " << i;
    if (ok && ref.valid) {
      EXPECT_NEAR(value, ref.value, 1e-6 * std::max(1.0, std::abs(ref.value))) << "hole " << i;
    }
  }
}
