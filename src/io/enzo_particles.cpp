#include "exabricks/io/particles.h"

#include "enzo_output.h"
#include "particle_checks.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"

#include <algorithm>
#include <map>

namespace exa {

namespace {

using io::enzo::DataFiles;
using io::enzo::Grid;
using io::enzo::Output;

const char* const kPosition[3] = {"particle_position_x", "particle_position_y", "particle_position_z"};

/// Enzo's particle types (its PARTICLE_TYPE_* numbers) as species names.
std::string typeName(int64_t type) {
  static const char* const kNames[] = {"gas",         "dark_matter", "star",       "tracer",
                                       "must_refine", "single_star", "black_hole", "cluster"};
  if (type >= 0 && type < int64_t(std::size(kNames))) return kNames[type];
  return "type_" + std::to_string(type);
}

/// An attribute's name: the dataset's, without Enzo's "particle_" prefix.
std::string attributeName(const std::string& dataset) {
  return dataset.rfind("particle_", 0) == 0 ? dataset.substr(9) : dataset;
}

/// A grid with particles: its file, group and 1-D datasets of NumberOfParticles values each.
struct GridParticles {
  const Grid* grid = nullptr;
  const h5::File* file = nullptr;
  std::string group;
  std::vector<std::string> datasets;
};

/// Every grid with particles, its datasets checked against NumberOfParticles; the positions must
/// be there. A particle_* dataset of another length is an error; other 1-D datasets of another
/// length are not particle data.
std::vector<GridParticles> particleGrids(const Output& o, DataFiles& files) {
  std::vector<GridParticles> out;
  for (const Grid& g : o.grids) {
    if (g.particles == 0) continue;
    GridParticles gp;
    gp.grid = &g;
    gp.file = &files.get(g.particleFile.empty() ? g.file : g.particleFile);
    gp.group = io::enzo::gridGroup(*gp.file, g, o.hierarchyPath);
    for (const std::string& m : gp.file->members(gp.group)) {
      const std::string path = gp.group + "/" + m;
      if (!gp.file->isDataset(path)) continue;
      const std::vector<uint64_t> d = gp.file->dims(path);
      if (d.size() != 1) continue;
      if (d[0] != uint64_t(g.particles)) {
        if (m.rfind("particle_", 0) != 0) continue;
        gp.file->bad(path, strCat("grid ", g.id, ": ", d[0],
                                  " values, but the hierarchy gives NumberOfParticles = ", g.particles));
      }
      gp.file->requireStorage(path);
      gp.datasets.push_back(m);
    }
    for (const char* p : kPosition)
      if (std::find(gp.datasets.begin(), gp.datasets.end(), p) == gp.datasets.end())
        gp.file->bad(gp.group, strCat("grid ", g.id, " has ", g.particles, " particles but no ", p));
    out.push_back(std::move(gp));
  }
  return out;
}

/// The attribute datasets every grid with particles holds, in name order; those some grids lack
/// are dropped with one warning naming the first such grid.
std::vector<std::string> commonAttributes(const std::vector<GridParticles>& grids, const std::string& where) {
  if (grids.empty()) return {};
  std::vector<std::string> common;
  for (const std::string& d : grids[0].datasets)
    if (std::find(std::begin(kPosition), std::end(kPosition), d) == std::end(kPosition)) common.push_back(d);
  for (const GridParticles& g : grids) {
    std::vector<std::string> kept;
    for (const std::string& d : common) {
      if (std::find(g.datasets.begin(), g.datasets.end(), d) != g.datasets.end())
        kept.push_back(d);
      else
        logWarning(strCat(where, ": grid ", g.grid->id, " has no ", d, ": the attribute ", attributeName(d),
                          " is left out of every particle"));
    }
    common = std::move(kept);
  }
  return common;
}

bool typed(const std::vector<std::string>& attributes) {
  return std::find(attributes.begin(), attributes.end(), "particle_type") != attributes.end();
}

/// Per species name, the particle count (species split by particle_type where there is one).
std::map<int64_t, uint64_t> typeCounts(const std::vector<GridParticles>& grids, bool byType) {
  std::map<int64_t, uint64_t> counts;
  for (const GridParticles& g : grids) {
    if (!byType) {
      counts[-1] += uint64_t(g.grid->particles);
      continue;
    }
    for (int64_t t : g.file->readInts(g.group + "/particle_type"))
      ++counts[t];
  }
  return counts;
}

std::string speciesName(int64_t type) { return type == -1 ? "particles" : typeName(type); }

} // namespace

std::vector<ParticleSpeciesInfo> listEnzoParticles(const std::string& path) {
  const Output o = io::enzo::readOutput(path);
  DataFiles files;
  const std::vector<GridParticles> grids = particleGrids(o, files);
  const std::vector<std::string> attributes = commonAttributes(grids, o.hierarchyPath);
  std::vector<ParticleSpeciesInfo> out;
  for (const auto& [type, count] : typeCounts(grids, typed(attributes))) {
    ParticleSpeciesInfo info{speciesName(type), count, {}, "double"};
    for (const std::string& a : attributes)
      info.attributes.push_back(attributeName(a));
    if (!grids.empty() && !grids[0].file->isDouble(grids[0].group + "/" + kPosition[0])) info.precision = "single";
    out.push_back(std::move(info));
  }
  return out;
}

ParticleSet readEnzoParticles(const std::string& path, const std::string& species) {
  const Output o = io::enzo::readOutput(path);
  DataFiles files;
  const std::vector<GridParticles> grids = particleGrids(o, files);
  const std::vector<std::string> attributes = commonAttributes(grids, o.hierarchyPath);
  const bool byType = typed(attributes);
  const std::map<int64_t, uint64_t> counts = typeCounts(grids, byType);
  std::vector<std::string> names;
  std::vector<int64_t> types;
  for (const auto& [type, count] : counts) {
    names.push_back(speciesName(type));
    types.push_back(type);
  }
  std::map<int64_t, ParticleSpecies> picked;
  for (size_t i : io::pickSpecies(path, names, species)) {
    ParticleSpecies& s = picked[types[i]];
    s.name = names[i];
    s.position.reserve(3 * counts.at(types[i]));
    for (const std::string& a : attributes)
      s.attributes.push_back({attributeName(a), {}, false});
  }
  // Precision and integer attributes as the first grid with particles stores them.
  for (auto& [t, s] : picked) {
    s.precision = "double";
    if (grids.empty()) continue;
    const GridParticles& g = grids[0];
    if (!g.file->isDouble(g.group + "/" + kPosition[0])) s.precision = "single";
    for (size_t k = 0; k < attributes.size(); ++k)
      s.attributes[k].integer = g.file->isInteger(g.group + "/" + attributes[k]);
  }
  for (const GridParticles& g : grids) {
    std::vector<std::vector<double>> position, values;
    for (const char* p : kPosition)
      position.push_back(g.file->readDoubles(g.group + "/" + p));
    for (const std::string& a : attributes)
      values.push_back(g.file->readDoubles(g.group + "/" + a));
    const std::vector<int64_t> type =
        byType ? g.file->readInts(g.group + "/particle_type") : std::vector<int64_t>(size_t(g.grid->particles), -1);
    for (size_t p = 0; p < size_t(g.grid->particles); ++p) {
      auto it = picked.find(type[p]);
      if (it == picked.end()) continue;
      ParticleSpecies& s = it->second;
      for (int a = 0; a < 3; ++a)
        s.position.push_back(position[size_t(a)][p]);
      for (size_t k = 0; k < attributes.size(); ++k)
        s.attributes[k].values.push_back(values[k][p]);
    }
  }
  ParticleSet set;
  for (auto& [t, s] : picked) {
    io::finishSpecies(s, o.params.left, o.params.right, path, set);
  }
  return set;
}

} // namespace exa
