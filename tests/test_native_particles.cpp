// NAME.particles beside a native dataset: written and read back exactly, bad files refused
// naming the file and the record, and the generated cosmic scene's particles (dark matter where
// the gas's mass is, stars in its haloes).
#include "errors.h"

#include "exabricks/amr/scenes.h"
#include "exabricks/io/native.h"
#include "exabricks/io/particles.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <unordered_map>

using namespace exa;
using namespace exa::test;
namespace fs = std::filesystem;

namespace {

ParticleSet twoSpecies() {
  ParticleSet set;
  ParticleSpecies a;
  a.name = "dark_matter";
  a.precision = "double";
  for (int p = 0; p < 5; ++p)
    for (int k = 0; k < 3; ++k)
      a.position.push_back(0.1 + p + 0.25 * k);
  a.attributes.push_back({"mass", {1.5, 2.5, 3.5, 4.5, 5.5}, false});
  a.attributes.push_back({"index", {10, 11, 12, 13, 9007199254740992.0}, true});
  ParticleSpecies b;
  b.name = "stars";
  b.precision = "double";
  set.species = {a, b};
  return set;
}

fs::path fresh(const std::string& name) {
  const fs::path dir = fs::path(EXABRICKS_TEST_TMP) / "native-particles" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  writeNative(generateScene(SceneOptions{"ramp", 200}), (dir / "d.cells").string());
  return dir / "d.cells";
}

void writeBytes(const fs::path& path, const std::vector<char>& bytes) {
  std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
}

} // namespace

TEST(NativeParticles, WrittenAndReadBackExactly) {
  const fs::path cells = fresh("round");
  const ParticleSet set = twoSpecies();
  writeNativeParticles(set, cells.string(), vec3d(0.0), vec3d(8.0));
  EXPECT_TRUE(fs::exists(cells.parent_path() / "d.particles"));
  const std::vector<ParticleSpeciesInfo> listed = listParticles(cells.string());
  ASSERT_EQ(listed.size(), 2u);
  EXPECT_EQ(listed[0].name, "dark_matter");
  EXPECT_EQ(listed[0].count, 5u);
  EXPECT_EQ(listed[0].attributes, (std::vector<std::string>{"mass", "index"}));
  EXPECT_EQ(listed[1].count, 0u);
  const ParticleSet back = readParticles(cells.string());
  ASSERT_EQ(back.species.size(), 2u);
  EXPECT_EQ(back.species[0].position, set.species[0].position);
  EXPECT_EQ(back.species[0].attributes[0].values, set.species[0].attributes[0].values);
  EXPECT_EQ(back.species[0].attributes[1].values, set.species[0].attributes[1].values);
  EXPECT_TRUE(back.species[0].attributes[1].integer);
  EXPECT_FALSE(back.species[0].attributes[0].integer);
  EXPECT_EQ(back.species[1].count(), 0u);
  // Particle 4 lies at x = 4.1 .. 4.6, inside [0, 8]; none outside.
  EXPECT_EQ(back.reports[0].outside, 0u);
  const ParticleSet stars = readParticles(cells.string(), "stars");
  ASSERT_EQ(stars.species.size(), 1u);
  EXPECT_EQ(stars.species[0].name, "stars");
  expectIn(errorOf([&] { readParticles(cells.string(), "gas"); }),
           {"d.particles", "no particle species 'gas'", "dark_matter, stars"});
}

TEST(NativeParticles, NonFiniteSkippedOutsideKept) {
  const fs::path cells = fresh("odd");
  ParticleSet set = twoSpecies();
  set.species[0].position[4] = std::nan("");
  writeNativeParticles(set, cells.string(), vec3d(0.0), vec3d(3.0));
  const ParticleSet back = readParticles(cells.string(), "dark_matter");
  EXPECT_EQ(back.reports[0].nonFinite, 1u);
  EXPECT_EQ(back.reports[0].outside, 2u); // particles 3 and 4 start beyond x = 3
  ASSERT_EQ(back.species[0].count(), 4u);
  EXPECT_EQ(back.species[0].attribute("mass")->values[1], 3.5);
}

TEST(NativeParticles, BadFilesAreRefusedNamingTheRecord) {
  const std::vector<char> good = nativeParticleBytes(twoSpecies(), vec3d(0.0), vec3d(8.0));
  auto refused = [&](const std::string& name, const std::vector<char>& bytes,
                     std::initializer_list<const char*> parts) {
    const fs::path cells = fresh(name);
    writeBytes(cells.parent_path() / "d.particles", bytes);
    const std::string message = errorOf([&] { readParticles(cells.string()); });
    expectIn(message, {"d.particles"});
    expectIn(message, parts);
  };
  std::vector<char> b = good;
  b[0] = 'X';
  refused("magic", b, {"not an exabricks particle file"});
  refused("short", std::vector<char>(good.begin(), good.begin() + 30), {"the file ends"});
  refused("trailing",
          [&] {
            auto t = good;
            t.push_back(0);
            return t;
          }(),
          {"declares", "bytes of particle data"});
  // The first species' count (after magic, species count, domain and the name) made huge.
  const size_t countAt = 8 + 4 + 48 + 1 + std::strlen("dark_matter");
  b = good;
  const uint64_t huge = uint64_t(1) << 60;
  std::memcpy(&b[countAt], &huge, 8);
  refused("huge", b, {"species 0", "'dark_matter'", "1152921504606846976 particles", "do not fit"});
  b = good;
  b[8] = 100; // species count
  refused("species", b, {"100 species declared"});
  b = good;
  std::memcpy(&b[countAt - std::strlen("dark_matter")], "st\x01rs", 5);
  refused("name", b, {"species 0's name", "not printable"});
  // An integer attribute holding 1.5.
  b = good;
  const double half = 1.5;
  std::memcpy(&b[good.size() - 8], &half, 8);
  refused("integer", b, {"species 'dark_matter'", "'index'", "particle 4", "not a whole number"});
  ParticleSet twice = twoSpecies();
  twice.species[1].name = "dark_matter";
  expectIn(errorOf([&] { nativeParticleBytes(twice, vec3d(0.0), vec3d(1.0)); }), {"'dark_matter' repeats"});
}

TEST(NativeParticles, WritingADatasetWithoutParticlesRemovesAnOldParticleFile) {
  const fs::path cells = fresh("stale");
  writeNativeParticles(twoSpecies(), cells.string(), vec3d(0.0), vec3d(8.0));
  ASSERT_EQ(listParticles(cells.string()).size(), 2u);
  writeNative(generateScene(SceneOptions{"ramp", 200}), cells.string());
  EXPECT_FALSE(fs::exists(cells.parent_path() / "d.particles"));
  EXPECT_TRUE(listParticles(cells.string()).empty());
}

TEST(NativeParticles, CosmicDarkMatterFollowsTheGasMassAndStarsSitInItsDensestKnots) {
  SceneOptions o{"cosmic", 100000};
  o = resolveSceneSize(o);
  const CellSet cells = generateScene(o);
  const ParticleSet set = generateSceneParticles(o, 20000);
  EXPECT_EQ(generateSceneParticles(o, 20000).species[0].position, set.species[0].position); // deterministic
  ASSERT_EQ(set.species.size(), 2u);
  ASSERT_EQ(set.species[0].count(), 20000u);
  ASSERT_EQ(set.species[1].count(), 800u);
  // The density of the cell holding each particle (cells by corner and level).
  std::unordered_map<uint64_t, float> density;
  auto key = [](const vec3i& c, int level) {
    return (uint64_t(c.x) << 44) ^ (uint64_t(c.y) << 24) ^ (uint64_t(c.z) << 4) ^ uint64_t(level);
  };
  const double volumeTotal = std::pow(double(o.base) * double(1 << (o.levels - 1)), 3);
  double massTotal = 0;
  std::vector<double> volumePerDecade(12, 0.0);
  std::vector<double> massPerDecade(12, 0.0);
  auto decade = [](double rho) { return std::clamp(int(std::floor(std::log10(rho))) + 4, 0, 11); };
  for (size_t i = 0; i < cells.cells.size(); ++i) {
    const Cell& c = cells.cells[i];
    const float rho = cells.fields[0].values[i];
    density[key(c.lower, c.level)] = rho;
    const double mass = double(rho) * std::pow(8.0, c.level);
    massTotal += mass;
    massPerDecade[size_t(decade(rho))] += mass;
    volumePerDecade[size_t(decade(rho))] += std::pow(8.0, c.level) / volumeTotal;
  }
  const double width = double(o.base) * double(1 << (o.levels - 1));
  auto densityAt = [&](const double* p) {
    for (int a = 0; a < 3; ++a)
      EXPECT_TRUE(p[a] >= 0 && p[a] <= width);
    for (int level = 0; level < o.levels; ++level) {
      const int w = 1 << level;
      const vec3i corner(int(std::floor(p[0] / w)) * w, int(std::floor(p[1] / w)) * w, int(std::floor(p[2] / w)) * w);
      const auto it = density.find(key(corner, level));
      if (it != density.end()) return double(it->second);
    }
    ADD_FAILURE() << "no cell holds the particle at " << p[0] << " " << p[1] << " " << p[2];
    return 0.0;
  };
  std::vector<double> particlesPerDecade(12, 0.0);
  for (size_t p = 0; p < set.species[0].count(); ++p)
    particlesPerDecade[size_t(decade(densityAt(&set.species[0].position[3 * p])))] += 1.0 / 20000;
  double unlikeVolume = 0; // particles placed by volume would miss by this much
  for (size_t d = 0; d < 12; ++d) {
    SCOPED_TRACE(d);
    EXPECT_NEAR(particlesPerDecade[d], massPerDecade[d] / massTotal, 0.05);
    unlikeVolume = std::max(unlikeVolume, std::abs(volumePerDecade[d] - massPerDecade[d] / massTotal));
  }
  EXPECT_GT(unlikeVolume, 0.2);
  // Stars: in the densest knots (every one above a hundred times the mean).
  size_t dense = 0;
  for (size_t p = 0; p < set.species[1].count(); ++p)
    dense += densityAt(&set.species[1].position[3 * p]) > 100;
  EXPECT_GT(double(dense) / 800, 0.9);
  EXPECT_THROW(generateSceneParticles(SceneOptions{"blobs", 1000}, 10), Error);
}
