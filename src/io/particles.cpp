#include "exabricks/io/particles.h"

#include "particle_checks.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"
#include "exabricks/io/load.h"

#include <nlohmann/json.hpp>

#include <cmath>

namespace exa {

namespace io {

void finishSpecies(ParticleSpecies& s, const vec3d& lower, const vec3d& upper, const std::string& where,
                   ParticleSet& set) {
  ParticleReport report;
  report.species = s.name;
  size_t kept = 0;
  const size_t n = s.count();
  for (size_t p = 0; p < n; ++p) {
    const double* x = &s.position[3 * p];
    if (!(std::isfinite(x[0]) && std::isfinite(x[1]) && std::isfinite(x[2]))) {
      ++report.nonFinite;
      continue;
    }
    for (int a = 0; a < 3; ++a)
      if (x[a] < lower[a] || x[a] > upper[a]) {
        ++report.outside;
        break;
      }
    if (kept != p) {
      for (int a = 0; a < 3; ++a)
        s.position[3 * kept + size_t(a)] = x[a];
      for (ParticleAttribute& attr : s.attributes)
        attr.values[kept] = attr.values[p];
    }
    ++kept;
  }
  s.position.resize(3 * kept);
  for (ParticleAttribute& attr : s.attributes)
    attr.values.resize(kept);
  if (report.nonFinite)
    logWarning(strCat(where, ": species ", s.name, ": skipped ", report.nonFinite,
                      " particles with a NaN or infinite coordinate"));
  if (report.outside)
    logWarning(strCat(where, ": species ", s.name, ": ", report.outside,
                      " particles lie outside the domain (kept, drawn where they are)"));
  set.reports.push_back(report);
  set.species.push_back(std::move(s));
}

std::vector<size_t> pickSpecies(const std::string& where, const std::vector<std::string>& available,
                                const std::string& wanted) {
  std::vector<size_t> out;
  for (size_t i = 0; i < available.size(); ++i)
    if (wanted.empty() || available[i] == wanted) out.push_back(i);
  if (!wanted.empty() && out.empty()) {
    std::string names;
    for (const std::string& a : available)
      names += (names.empty() ? "" : ", ") + a;
    fail(where, ": no particle species '", wanted, "' (",
         available.empty() ? "it holds no particles" : "it holds: " + names, ")");
  }
  return out;
}

} // namespace io

size_t bytesPerParticle(const ParticleSpeciesInfo& s) { return sizeof(double) * (3 + s.attributes.size()); }

std::string particleSpeciesJson(const std::vector<ParticleSpeciesInfo>& species) {
  nlohmann::json out = nlohmann::json::array();
  for (const ParticleSpeciesInfo& s : species)
    out.push_back({{"species", s.name},
                   {"count", s.count},
                   {"attributes", s.attributes},
                   {"precision", s.precision},
                   {"bytes_per_particle", bytesPerParticle(s)}});
  return out.dump();
}

std::vector<ParticleSpeciesInfo> listParticles(const std::string& path) {
  switch (detectInput(path)) {
  case InputKind::Amrex:
    return listAmrexParticles(path);
  case InputKind::Enzo:
    return listEnzoParticles(path);
  case InputKind::Flash:
    return listFlashParticles(path);
  case InputKind::Native:
    return listNativeParticles(path);
  default:
    return {};
  }
}

std::shared_ptr<const ParticleSet> readParticlesIfAny(const std::string& path, const std::string& species) {
  if (path.empty() || listParticles(path).empty()) return nullptr;
  return std::make_shared<const ParticleSet>(readParticles(path, species));
}

ParticleSet readParticles(const std::string& path, const std::string& species) {
  switch (detectInput(path)) {
  case InputKind::Amrex:
    return readAmrexParticles(path, species);
  case InputKind::Enzo:
    return readEnzoParticles(path, species);
  case InputKind::Flash:
    return readFlashParticles(path, species);
  case InputKind::Native:
    return readNativeParticles(path, species);
  default:
    if (!species.empty()) fail(path, ": no particle species '", species, "' (it holds no particles)");
    return {};
  }
}

} // namespace exa
