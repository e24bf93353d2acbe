// Particle readers against hand-written AMReX plotfiles and Enzo outputs (both precisions,
// several levels and grids, empty grids, packed ids), a real Enzo output, and bad input.
#include "errors.h"
#include "flash_fixture.h"
#include "h5_writer.h"

#include "exabricks/io/particles.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <set>

using namespace exa;
using namespace exa::test;
namespace fs = std::filesystem;

namespace {

fs::path sharedData() {
  if (const char* env = std::getenv("EXABRICKS_DATA")) return env;
  return fs::path(EXABRICKS_SOURCE_DIR).parent_path() / "shared" / "data";
}

/// The plotfile Header of a 4^3 domain from prob_lo (-1, 0, 2) to prob_hi (3, 4, 6), one level.
void writePlotfileHeader(const fs::path& dir) {
  fs::create_directories(dir / "Level_0");
  std::ofstream(dir / "Header") << "HyperCLaw-V1.1\n1\nrho\n3\n0.5\n0\n-1 0 2\n3 4 6\n\n((0,0,0) (3,3,3) (0,0,0))\n0\n"
                                   "1 1 1\n0\n0\n0 1 0.5\n0\n-1 3\n0 4\n2 6\nLevel_0/Cell\n";
}

/// One AMReX species: grids per level, each with its particle count; particle p (counted over
/// the species) has id 1000 + p, cpu 7, integer component k = 10 p + k, position
/// (-1 + 0.03125 (p + 1), 0.0625 (p + 1), 2 + 0.125 (p + 1)) and real component k = p + 0.25 k.
struct AmrexSpecies {
  std::string name;
  bool single = false, packed = false;
  std::vector<std::string> reals{"mass", "vx"}, ints{"kind"};
  std::vector<std::vector<int>> grids; ///< per level, per grid: particle count
  std::string version() const {
    return std::string(packed ? "Version_Two_Dot_One_" : "Version_Two_Dot_Zero_") + (single ? "single" : "double");
  }
  static double position(int p, int a) {
    return a == 0 ? -1 + 0.03125 * (p + 1) : a == 1 ? 0.0625 * (p + 1) : 2 + 0.125 * (p + 1);
  }
  static double real(int p, size_t k) { return p + 0.25 * double(k); }

  /// Writes the species folder; every grid's data goes to DATA_00000 of its level except the
  /// second grid of a level, which goes to DATA_00001 (several files, offsets within them).
  void write(const fs::path& plotfile) const {
    const fs::path dir = plotfile / name;
    int total = 0;
    for (const auto& level : grids)
      total += std::accumulate(level.begin(), level.end(), 0);
    std::ostringstream table;
    int p = 0;
    for (size_t l = 0; l < grids.size(); ++l) {
      fs::create_directories(dir / ("Level_" + std::to_string(l)));
      std::vector<std::ofstream> files;
      files.emplace_back(dir / ("Level_" + std::to_string(l)) / "DATA_00000", std::ios::binary);
      files.emplace_back(dir / ("Level_" + std::to_string(l)) / "DATA_00001", std::ios::binary);
      for (size_t g = 0; g < grids[l].size(); ++g) {
        const int which = g == 1 ? 1 : 0;
        std::ofstream& out = files[size_t(which)];
        if (grids[l][g] == 0) {
          table << "-1 0 0\n";
          continue;
        }
        table << which << " " << grids[l][g] << " " << out.tellp() << "\n";
        for (int q = 0; q < grids[l][g]; ++q) {
          int32_t words[2] = {1000 + p + q, 7};
          if (packed) {
            const uint64_t idcpu = (uint64_t(1) << 63) | (uint64_t(1000 + p + q) << 24) | 7u;
            std::memcpy(words, &idcpu, 8);
          }
          out.write(reinterpret_cast<const char*>(words), 8);
          for (size_t k = 0; k < ints.size(); ++k) {
            const int32_t v = int32_t(10 * (p + q) + int(k));
            out.write(reinterpret_cast<const char*>(&v), 4);
          }
        }
        for (int q = 0; q < grids[l][g]; ++q) {
          std::vector<double> r;
          for (int a = 0; a < 3; ++a)
            r.push_back(position(p + q, a));
          for (size_t k = 0; k < reals.size(); ++k)
            r.push_back(real(p + q, k));
          for (double v : r) {
            if (single) {
              const float f = float(v);
              out.write(reinterpret_cast<const char*>(&f), 4);
            } else {
              out.write(reinterpret_cast<const char*>(&v), 8);
            }
          }
        }
        p += grids[l][g];
      }
    }
    std::ofstream h(dir / "Header");
    h << version() << "\n3\n" << reals.size() << "\n";
    for (const std::string& r : reals)
      h << r << "\n";
    h << ints.size() << "\n";
    for (const std::string& i : ints)
      h << i << "\n";
    h << "0\n" << total << "\n" << 1000 + total << "\n" << grids.size() - 1 << "\n";
    for (const auto& level : grids)
      h << level.size() << "\n";
    h << table.str();
  }
};

void expectSpecies(const ParticleSpecies& s, const AmrexSpecies& w, int count) {
  ASSERT_EQ(s.count(), size_t(count));
  EXPECT_EQ(s.precision, w.single ? "single" : "double");
  std::vector<std::string> names;
  for (const ParticleAttribute& a : s.attributes)
    names.push_back(a.name);
  EXPECT_EQ(names, (std::vector<std::string>{"id", "cpu", "kind", "mass", "vx"}));
  for (int p = 0; p < count; ++p) {
    for (int a = 0; a < 3; ++a) {
      const double x = AmrexSpecies::position(p, a);
      EXPECT_EQ(s.position[size_t(3 * p + a)], w.single ? double(float(x)) : x);
    }
    EXPECT_EQ(s.attribute("id")->values[size_t(p)], 1000 + p);
    EXPECT_EQ(s.attribute("cpu")->values[size_t(p)], 7);
    EXPECT_EQ(s.attribute("kind")->values[size_t(p)], 10 * p);
    EXPECT_EQ(s.attribute("vx")->values[size_t(p)], AmrexSpecies::real(p, 1));
  }
  EXPECT_TRUE(s.attribute("id")->integer);
  EXPECT_FALSE(s.attribute("mass")->integer);
}

} // namespace

TEST(Particles, AmrexSpeciesBothPrecisionsLevelsGridsAndPackedIds) {
  const fs::path dir = fs::path(EXABRICKS_TEST_TMP) / "amrex-particles" / "plt00010";
  fs::remove_all(dir.parent_path());
  writePlotfileHeader(dir);
  AmrexSpecies dm{"DM", false, false, {"mass", "vx"}, {"kind"}, {{5, 3, 0, 2}, {4}}};
  AmrexSpecies stars{"stars", true, true, {"mass", "vx"}, {"kind"}, {{0, 6}}};
  AmrexSpecies none{"tracers", false, false, {"mass", "vx"}, {"kind"}, {{0}}};
  for (const AmrexSpecies* s : {&dm, &stars, &none})
    s->write(dir);
  const std::vector<ParticleSpeciesInfo> info = listParticles(dir.string());
  ASSERT_EQ(info.size(), 3u);
  EXPECT_EQ(info[0].name, "DM");
  EXPECT_EQ(info[0].count, 14u);
  EXPECT_EQ(info[1].name, "stars");
  EXPECT_EQ(info[1].precision, "single");
  EXPECT_EQ(info[2].count, 0u);
  EXPECT_EQ(info[0].attributes, (std::vector<std::string>{"id", "cpu", "kind", "mass", "vx"}));

  const ParticleSet all = readParticles(dir.string());
  ASSERT_EQ(all.species.size(), 3u);
  expectSpecies(all.species[0], dm, 14);
  expectSpecies(all.species[1], stars, 6);
  EXPECT_EQ(all.species[2].count(), 0u);
  for (const ParticleReport& r : all.reports)
    EXPECT_EQ(r.nonFinite + r.outside, 0u) << r.species;

  const ParticleSet one = readParticles(dir.string(), "stars");
  ASSERT_EQ(one.species.size(), 1u);
  expectSpecies(one.species[0], stars, 6);
  expectIn(errorOf([&] { readParticles(dir.string(), "gas"); }),
           {"plt00010", "no particle species 'gas'", "DM, stars"});
}

TEST(Particles, AmrexNonFiniteSkippedOutsideKept) {
  const fs::path dir = fs::path(EXABRICKS_TEST_TMP) / "amrex-particles-odd" / "plt";
  fs::remove_all(dir.parent_path());
  writePlotfileHeader(dir);
  AmrexSpecies dm{"DM", false, false, {"mass"}, {}, {{40}}};
  dm.write(dir);
  // Particle 3's y becomes NaN; particles 32..39 have x = -1 + 0.03125 (p + 1) > 0.03125 ... and
  // z = 2 + 0.125 (p + 1) > 6 from p = 32 on: outside the domain.
  {
    std::fstream f(dir / "DM" / "Level_0" / "DATA_00000", std::ios::binary | std::ios::in | std::ios::out);
    const double nan = std::nan("");
    f.seekp(std::streamoff(40 * 8 + (3 * 4 + 1) * 8));
    f.write(reinterpret_cast<const char*>(&nan), 8);
  }
  const ParticleSet s = readParticles(dir.string());
  ASSERT_EQ(s.species.size(), 1u);
  EXPECT_EQ(s.reports[0].nonFinite, 1u);
  EXPECT_EQ(s.reports[0].outside, 8u);
  ASSERT_EQ(s.species[0].count(), 39u);
  EXPECT_EQ(s.species[0].attribute("id")->values[3], 1004); // particle 3 skipped
  EXPECT_EQ(s.species[0].attribute("mass")->values[3], 4);
}

TEST(Particles, BadAmrexParticleFilesAreRefusedClearly) {
  const fs::path root = fs::path(EXABRICKS_TEST_TMP) / "amrex-particles-bad";
  auto fresh = [&](const std::string& name) {
    const fs::path dir = root / name;
    fs::remove_all(dir);
    writePlotfileHeader(dir);
    AmrexSpecies{"DM", false, false, {"mass"}, {}, {{5, 3}}}.write(dir);
    return dir;
  };
  auto edit = [](const fs::path& header, const std::string& from, const std::string& to) {
    std::ifstream in(header);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    text.replace(text.find(from), from.size(), to);
    std::ofstream(header) << text;
  };
  {
    const fs::path d = fresh("total");
    edit(d / "DM" / "Header", "\n8\n", "\n9\n");
    expectIn(errorOf([&] { readParticles(d.string()); }), {"DM/Header", "declares 9 particles", "lists 8"});
  }
  {
    const fs::path d = fresh("huge");
    edit(d / "DM" / "Header", "\n8\n", "\n1000000000008\n");
    edit(d / "DM" / "Header", "0 5 0", "0 1000000000005 0");
    expectIn(errorOf([&] { readParticles(d.string()); }), {"DM/Header", "level 0 grid 0", "DATA_00000", "only"});
  }
  {
    // Both grids of level 0 claim the first grid's bytes (a file of 8 particles' bytes, 5 + 5 claimed).
    const fs::path d = fresh("overlap");
    edit(d / "DM" / "Header", "1 3 0", "0 5 0");
    edit(d / "DM" / "Header", "\n8\n", "\n10\n");
    expectIn(errorOf([&] { readParticles(d.string()); }), {"level 0 grid 1", "claim", "overlap"});
  }
  {
    const fs::path d = fresh("offset");
    edit(d / "DM" / "Header", "1 3 0", "1 3 999999");
    expectIn(errorOf([&] { readParticles(d.string()); }), {"level 0 grid 1", "offset 999999", "beyond"});
  }
  {
    const fs::path d = fresh("version");
    edit(d / "DM" / "Header", "Version_Two_Dot_Zero_double", "Version_Nine_double");
    // Not a known particle version: the folder is listed (its Header begins "Version_") and refused.
    expectIn(errorOf([&] { listParticles(d.string()); }), {"DM/Header", "line 1", "unknown particle version"});
  }
  {
    const fs::path d = fresh("dim");
    edit(d / "DM" / "Header", "_double\n3\n", "_double\n2\n");
    expectIn(errorOf([&] { readParticles(d.string()); }), {"DM/Header", "line 2", "2-D particles"});
  }
  {
    const fs::path d = fresh("cut");
    edit(d / "DM" / "Header", "1 3 0", "");
    expectIn(errorOf([&] { readParticles(d.string()); }), {"DM/Header", "ends before"});
  }
  {
    const fs::path d = fresh("missing");
    fs::remove(d / "DM" / "Level_0" / "DATA_00001");
    expectIn(errorOf([&] { readParticles(d.string()); }), {"level 0 grid 1", "DATA_00001", "cannot read"});
  }
}

namespace {

/// An Enzo output: a root grid 8^3 over [0,1]^3 and a level-1 grid over [0.25,0.75]^3, each
/// with particles; grid 1 holds types 1, 1, 2, 1 and a velocity, grid 2 types 2, 1, 1 and none.
struct EnzoParticles {
  fs::path dir;
  bool float32 = false;
  int grid2Count = 3; ///< NumberOfParticles the hierarchy gives grid 2
  fs::path parameterFile() const { return dir / "DD0003"; }
  static double x(int p, int a) { return 0.3 + 0.0625 * p + 0.125 * a; }
  void write() const {
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::ofstream(parameterFile()) << "TopGridRank = 3\nTopGridDimensions = 8 8 8\nRefineBy = 2\n"
                                      "DomainLeftEdge = 0 0 0\nDomainRightEdge = 1 1 1\n";
    std::ofstream h(dir / "DD0003.hierarchy");
    const char* const edges[2][2] = {{"0 0 0", "1 1 1"}, {"0.25 0.25 0.25", "0.75 0.75 0.75"}};
    for (int g = 0; g < 2; ++g)
      h << "\nGrid = " << g + 1 << "\nGridRank = 3\nGridDimension = 8 8 8\nGridStartIndex = 0 0 0\n"
        << "GridEndIndex = 7 7 7\nGridLeftEdge = " << edges[g][0] << "\nGridRightEdge = " << edges[g][1]
        << "\nNumberOfBaryonFields = 1\nBaryonFileName = /elsewhere/DD0003.cpu0000\nNumberOfParticles = "
        << (g == 0 ? 4 : grid2Count) << "\nParticleFileName = /elsewhere/DD0003.cpu0000\n";
    h5w::Writer w((dir / "DD0003.cpu0000").string());
    const std::vector<std::vector<int>> types{{1, 1, 2, 1}, {2, 1, 1}};
    int p = 0;
    for (int g = 0; g < 2; ++g) {
      const std::string group = "/Grid0000000" + std::to_string(g + 1);
      w.group(group);
      w.doubles(group + "/Density", {8, 8, 8}, std::vector<double>(512, 1.0), true);
      const hsize_t n = types[size_t(g)].size();
      for (int a = 0; a < 3; ++a) {
        std::vector<double> v;
        for (hsize_t q = 0; q < n; ++q)
          v.push_back(x(p + int(q), a));
        w.doubles(
            group + "/particle_position_" + "xyz" [a], { n }, v, float32);
      }
      std::vector<double> mass;
      std::vector<int> index;
      for (hsize_t q = 0; q < n; ++q) {
        mass.push_back(0.5 * (p + int(q)));
        index.push_back(100 + p + int(q));
      }
      w.doubles(group + "/particle_mass", {n}, mass, true);
      w.ints(group + "/particle_index", {n}, index);
      w.ints(group + "/particle_type", {n}, types[size_t(g)]);
      if (g == 0) w.doubles(group + "/particle_velocity_x", {n}, {1, 2, 3, 4}, true);
      p += int(n);
    }
  }
};

} // namespace

TEST(Particles, EnzoSpeciesByTypeBothPrecisionsAndMissingAttributes) {
  for (bool float32 : {false, true}) {
    SCOPED_TRACE(float32);
    EnzoParticles e;
    e.dir = fs::path(EXABRICKS_TEST_TMP) / (float32 ? "enzo-particles32" : "enzo-particles");
    e.float32 = float32;
    e.write();
    const std::string path = e.parameterFile().string();
    const std::vector<ParticleSpeciesInfo> info = listParticles(path);
    ASSERT_EQ(info.size(), 2u);
    EXPECT_EQ(info[0].name, "dark_matter");
    EXPECT_EQ(info[0].count, 5u);
    EXPECT_EQ(info[1].name, "star");
    EXPECT_EQ(info[1].count, 2u);
    EXPECT_EQ(info[0].precision, float32 ? "single" : "double");
    // velocity_x is in grid 1 only: left out.
    EXPECT_EQ(info[0].attributes, (std::vector<std::string>{"index", "mass", "type"}));

    const ParticleSet s = readParticles(path);
    ASSERT_EQ(s.species.size(), 2u);
    const ParticleSpecies& dm = s.species[0];
    const ParticleSpecies& star = s.species[1];
    ASSERT_EQ(dm.count(), 5u);
    ASSERT_EQ(star.count(), 2u);
    const std::vector<int> dmIndex{0, 1, 3, 5, 6}, starIndex{2, 4}; // file order over the grids
    for (size_t k = 0; k < dmIndex.size(); ++k) {
      const int p = dmIndex[k];
      for (int a = 0; a < 3; ++a)
        EXPECT_EQ(dm.position[3 * k + size_t(a)],
                  float32 ? double(float(EnzoParticles::x(p, a))) : EnzoParticles::x(p, a));
      EXPECT_EQ(dm.attribute("index")->values[k], 100 + p);
      EXPECT_EQ(dm.attribute("mass")->values[k], 0.5 * p);
      EXPECT_EQ(dm.attribute("type")->values[k], 1);
    }
    EXPECT_EQ(star.attribute("index")->values[0], 102);
    EXPECT_EQ(star.attribute("index")->values[1], 104);
    EXPECT_TRUE(dm.attribute("index")->integer);
    EXPECT_FALSE(dm.attribute("mass")->integer);
    const ParticleSet only = readParticles(path, "star");
    ASSERT_EQ(only.species.size(), 1u);
    EXPECT_EQ(only.species[0].count(), 2u);
  }
}

TEST(Particles, EnzoCountsThatDisagreeWithTheDataAreRefused) {
  EnzoParticles e;
  e.dir = fs::path(EXABRICKS_TEST_TMP) / "enzo-particles-bad";
  e.grid2Count = 5;
  e.write();
  expectIn(errorOf([&] { readParticles(e.parameterFile().string()); }),
           {"DD0003.cpu0000", "Grid00000002/particle_", "grid 2", "3 values", "NumberOfParticles = 5"});
}

TEST(Particles, FlashTracerParticlesBothPrecisions) {
  for (bool float32 : {false, true}) {
    SCOPED_TRACE(float32);
    flash_fixture::FlashFixture f;
    f.file = fs::path(EXABRICKS_TEST_TMP) / (float32 ? "flash-particles32.hdf5" : "flash-particles.hdf5");
    f.float32 = float32;
    f.particles = 30;
    f.write();
    const std::vector<ParticleSpeciesInfo> info = listParticles(f.file.string());
    ASSERT_EQ(info.size(), 1u);
    EXPECT_EQ(info[0].name, "particles");
    EXPECT_EQ(info[0].count, 30u);
    EXPECT_EQ(info[0].attributes, (std::vector<std::string>{"blk", "tag"}));
    EXPECT_EQ(info[0].precision, float32 ? "single" : "double");
    const ParticleSet set = readParticles(f.file.string());
    ASSERT_EQ(set.species.size(), 1u);
    const ParticleSpecies& s = set.species[0];
    ASSERT_EQ(s.count(), 30u);
    auto stored = [&](double v) { return float32 ? double(float(v)) : v; };
    for (int p = 0; p < 30; ++p) {
      EXPECT_EQ(s.position[size_t(3 * p)], stored(0.1 + 0.01 * p));
      EXPECT_EQ(s.position[size_t(3 * p + 1)], stored(0.2 + 0.02 * p));
      EXPECT_EQ(s.position[size_t(3 * p + 2)], stored(0.3 + 0.005 * p));
      EXPECT_EQ(s.attribute("tag")->values[size_t(p)], 100 + p);
    }
  }
  flash_fixture::FlashFixture none;
  none.file = fs::path(EXABRICKS_TEST_TMP) / "flash-no-particles.hdf5";
  none.write();
  EXPECT_TRUE(listParticles(none.file.string()).empty());
  expectIn(errorOf([&] { readParticles(none.file.string(), "particles"); }), {"no particle species 'particles'"});
}

TEST(Particles, FormatsWithoutParticlesListNone) {
  const fs::path dir = fs::path(EXABRICKS_TEST_TMP) / "amrex-no-particles" / "plt";
  fs::remove_all(dir.parent_path());
  writePlotfileHeader(dir);
  EXPECT_TRUE(listParticles(dir.string()).empty());
  EXPECT_TRUE(readParticles(dir.string()).species.empty());
}

TEST(Particles, SharedEnzoOutputWithDarkMatterOnEightLevels) {
  const fs::path path = sharedData() / "particles" / "enzo_moving7_3d" / "DD0010" / "moving7_0010";
  if (!fs::exists(path))
    GTEST_SKIP() << "sample data not found at " << path.string() << " (set EXABRICKS_DATA to the shared data folder)";
  const std::vector<ParticleSpeciesInfo> info = listParticles(path.string());
  ASSERT_EQ(info.size(), 1u);
  EXPECT_EQ(info[0].name, "dark_matter");
  EXPECT_EQ(info[0].count, 9233u);
  EXPECT_EQ(info[0].precision, "double");
  const ParticleSet s = readParticles(path.string());
  ASSERT_EQ(s.species.size(), 1u);
  const ParticleSpecies& dm = s.species[0];
  ASSERT_EQ(dm.count(), 9233u);
  EXPECT_EQ(s.reports[0].nonFinite + s.reports[0].outside, 0u);
  // Independent figures of the file (read with h5py): the indices are distinct, 0..19306, and
  // the masses (float32) sum to 113840480.384 in double.
  const std::vector<double>& index = dm.attribute("index")->values;
  EXPECT_EQ(std::set<double>(index.begin(), index.end()).size(), 9233u);
  EXPECT_EQ(*std::min_element(index.begin(), index.end()), 0);
  EXPECT_EQ(*std::max_element(index.begin(), index.end()), 19306);
  const std::vector<double>& mass = dm.attribute("mass")->values;
  EXPECT_NEAR(std::accumulate(mass.begin(), mass.end(), 0.0), 113840480.38425708, 1e-3);
  for (double x : dm.position) {
    EXPECT_GE(x, 0.0);
    EXPECT_LE(x, 1.0);
  }
}
