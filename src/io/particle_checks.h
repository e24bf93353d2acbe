// What every particle reader does after reading a species: skips particles with a NaN or
// infinite coordinate and counts those outside the domain, each said once per species.
#pragma once

#include "exabricks/amr/particles.h"
#include "exabricks/core/math.h"

#include <string>

namespace exa::io {

/// Drops the non-finite particles of `s` (from its positions and every attribute), counts the
/// particles outside [lower, upper] and appends the report to `set`; warns once per species
/// when either count is not zero. `where` names the input.
void finishSpecies(ParticleSpecies& s, const vec3d& lower, const vec3d& upper, const std::string& where,
                   ParticleSet& set);

/// The one species `wanted` names out of `available` (all when empty), or an error naming the
/// input and the species it holds.
std::vector<size_t> pickSpecies(const std::string& where, const std::vector<std::string>& available,
                                const std::string& wanted);

} // namespace exa::io
