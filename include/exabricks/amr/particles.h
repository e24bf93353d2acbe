// Particles beside the cells: species of point particles (dark matter, stars, tracers, sprays)
// with their positions in the cells' world coordinates and named per-particle attributes.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace exa {

/// One named value per particle, in particle order. Integer attributes (ids, types) are held
/// exactly (every integer up to 2^53).
struct ParticleAttribute {
  std::string name;
  std::vector<double> values;
  bool integer = false;
};

/// One species: N particles, positions x, y, z per particle in world coordinates.
struct ParticleSpecies {
  std::string name;
  std::vector<double> position; ///< 3 N values
  std::vector<ParticleAttribute> attributes;
  std::string precision; ///< "single" or "double": how the file stores the positions

  size_t count() const { return position.size() / 3; }
  /// The attribute of that name; null when the species has none.
  const ParticleAttribute* attribute(const std::string& wanted) const {
    for (const ParticleAttribute& a : attributes)
      if (a.name == wanted) return &a;
    return nullptr;
  }
};

/// What a file holds of one species, from its headers alone.
struct ParticleSpeciesInfo {
  std::string name;
  uint64_t count = 0;
  std::vector<std::string> attributes;
  std::string precision;
};

/// What reading particles skipped or found outside the cells' domain, per species.
struct ParticleReport {
  std::string species;
  uint64_t nonFinite = 0; ///< particles with a NaN or infinite coordinate: skipped
  uint64_t outside = 0;   ///< particles outside the domain's box: kept
};

struct ParticleSet {
  std::vector<ParticleSpecies> species;
  std::vector<ParticleReport> reports;
  const ParticleSpecies* find(const std::string& wanted) const {
    for (const ParticleSpecies& s : species)
      if (s.name == wanted) return &s;
    return nullptr;
  }
};

} // namespace exa
