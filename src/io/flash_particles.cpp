#include "exabricks/io/particles.h"

#include "hdf5_file.h"
#include "particle_checks.h"

#include "exabricks/core/error.h"

#include <algorithm>

namespace exa {
namespace {

const char* const kData = "tracer particles";
const char* const kNames = "particle names";
const char* const kPosition[3] = {"posx", "posy", "posz"};

/// The particle table of a FLASH file: its property names and the columns of the positions.
struct Table {
  std::vector<std::string> names;
  uint64_t count = 0;
  int position[3] = {-1, -1, -1};
  bool present = false;
};

Table describe(const h5::File& f) {
  Table t;
  if (!f.isDataset(kData)) return t;
  t.present = true;
  const std::vector<uint64_t> d = f.dims(kData);
  if (d.size() != 2) f.bad(kData, "expected dimensions [particles, properties]");
  if (!f.isDataset(kNames)) f.bad(kNames, strCat("missing: it names the ", d[1], " properties of \"", kData, "\""));
  for (std::string n : f.readStrings(kNames)) {
    n.erase(std::find_if(n.rbegin(), n.rend(), [](char c) { return c != ' ' && c != '\0'; }).base(), n.end());
    t.names.push_back(n);
  }
  if (t.names.size() != d[1])
    f.bad(kNames, strCat("names ", t.names.size(), " properties, but \"", kData, "\" holds ", d[1]));
  for (int a = 0; a < 3; ++a) {
    const auto it = std::find(t.names.begin(), t.names.end(), kPosition[a]);
    if (it == t.names.end()) f.bad(kNames, strCat("no ", kPosition[a], " among the particle properties"));
    t.position[a] = int(it - t.names.begin());
  }
  t.count = d[0];
  return t;
}

std::vector<std::string> attributesOf(const Table& t) {
  std::vector<std::string> out;
  for (const std::string& n : t.names)
    if (std::find(std::begin(kPosition), std::end(kPosition), n) == std::end(kPosition)) out.push_back(n);
  return out;
}

} // namespace

std::vector<ParticleSpeciesInfo> listFlashParticles(const std::string& path) {
  const h5::File f(path);
  const Table t = describe(f);
  if (!t.present) return {};
  return {{"particles", t.count, attributesOf(t), f.isDouble(kData) ? "double" : "single"}};
}

ParticleSet readFlashParticles(const std::string& path, const std::string& species) {
  const h5::File f(path);
  const Table t = describe(f);
  ParticleSet set;
  if (io::pickSpecies(path, t.present ? std::vector<std::string>{"particles"} : std::vector<std::string>{}, species)
          .empty())
    return set;
  f.requireStorage(kData);
  const std::vector<double> values = f.readDoubles(kData);
  const size_t props = t.names.size();
  ParticleSpecies s;
  s.name = "particles";
  s.precision = f.isDouble(kData) ? "double" : "single";
  std::vector<size_t> columns;
  for (size_t c = 0; c < props; ++c)
    if (int(c) != t.position[0] && int(c) != t.position[1] && int(c) != t.position[2]) {
      s.attributes.push_back({t.names[c], {}, false});
      s.attributes.back().values.reserve(size_t(t.count));
      columns.push_back(c);
    }
  s.position.reserve(3 * size_t(t.count));
  for (size_t p = 0; p < size_t(t.count); ++p) {
    for (int a = 0; a < 3; ++a)
      s.position.push_back(values[p * props + size_t(t.position[a])]);
    for (size_t k = 0; k < columns.size(); ++k)
      s.attributes[k].values.push_back(values[p * props + columns[k]]);
  }
  // The domain: the blocks' bounding boxes together.
  vec3d lower(INFINITY), upper(-INFINITY);
  if (f.isDataset("bounding box")) {
    const std::vector<double> box = f.readDoubles("bounding box");
    for (size_t i = 0; i + 5 < box.size(); i += 6)
      for (int a = 0; a < 3; ++a) {
        lower[a] = std::min(lower[a], box[i + 2 * size_t(a)]);
        upper[a] = std::max(upper[a], box[i + 2 * size_t(a) + 1]);
      }
  }
  io::finishSpecies(s, lower, upper, path, set);
  return set;
}

} // namespace exa
