// Particle readers: the species a simulation output holds beside its cells.
//   AMReX plotfiles: every folder of the plotfile whose Header begins with a particle version
//     string (Version_Two_Dot_Zero_double, ..._single, Version_Two_Dot_One_*: 64-bit ids), its
//     Level_L/DATA_nnnnn files as the Header's grid table places them: per grid, the integer
//     block (id, cpu and the integer components) and then the real block (x, y, z and the real
//     components), in the machine's byte order. Positions are physical, as the cells' world.
//   Enzo packed HDF5: the grids' particle_position_x/y/z and every other 1-D particle_* dataset,
//     split into species by particle_type where the output writes it (dark_matter, star, ...)
//     and one species "particles" otherwise. Positions are code units, as the cells' world.
//   NAME.particles beside a native NAME.cells (exabricks generate writes it): every species with
//     its attributes in double precision, positions in the cells' world (the lattice).
//   FLASH HDF5: the "tracer particles" table (particles x properties) with its "particle names"
//     (posx, posy, posz, tag, velx, ...): one species "particles", every property but the
//     positions an attribute. Positions are physical, as the cells' world.
// Other formats hold no particles here (an empty list).
//
// Treatment of odd data: a particle with a NaN or infinite coordinate is skipped and counted; a
// particle outside the domain is kept and counted (both said once per species as a warning); a
// species with zero particles is listed with count 0; an attribute that some grids lack is
// dropped with a warning naming the first such grid. Counts and offsets that disagree with the
// data files, declared counts larger than the files can hold, and unknown versions are errors
// naming the file and the record, checked before anything is allocated by the declared count.
#pragma once

#include "exabricks/amr/particles.h"
#include "exabricks/core/math.h"

#include <memory>
#include <string>
#include <vector>

namespace exa {

/// The species of an input, from its headers (AMReX) or its hierarchy and dataset shapes (Enzo).
std::vector<ParticleSpeciesInfo> listParticles(const std::string& path);

/// Bytes one particle of the species takes once read (positions and attributes in double).
size_t bytesPerParticle(const ParticleSpeciesInfo& s);
/// The species as `info --json` lists them: a JSON array of {species, count, attributes,
/// precision, bytes_per_particle}.
std::string particleSpeciesJson(const std::vector<ParticleSpeciesInfo>& species);

/// Reads every species, or the one named (an error naming the input's species when it has no
/// such species).
ParticleSet readParticles(const std::string& path, const std::string& species = "");

/// The species named ("" every one) of an input that holds particles; null for an empty path or
/// an input without particles (the front ends draw none then).
std::shared_ptr<const ParticleSet> readParticlesIfAny(const std::string& path, const std::string& species = "");

/// AMReX, Enzo and FLASH readers (listParticles and readParticles dispatch to them).
std::vector<ParticleSpeciesInfo> listAmrexParticles(const std::string& plotfile);
ParticleSet readAmrexParticles(const std::string& plotfile, const std::string& species = "");
std::vector<ParticleSpeciesInfo> listEnzoParticles(const std::string& path);
ParticleSet readEnzoParticles(const std::string& path, const std::string& species = "");
std::vector<ParticleSpeciesInfo> listFlashParticles(const std::string& path);
ParticleSet readFlashParticles(const std::string& path, const std::string& species = "");
std::vector<ParticleSpeciesInfo> listNativeParticles(const std::string& cellsPath);
ParticleSet readNativeParticles(const std::string& cellsPath, const std::string& species = "");

/// NAME.particles for NAME.cells (an error for a path that does not end in .cells).
std::string nativeParticlesPath(const std::string& cellsPath);
/// The bytes of NAME.particles for a set of particles in a domain [lower, upper] (world
/// coordinates); an error names a species or attribute the format cannot hold.
std::vector<char> nativeParticleBytes(const ParticleSet& set, const vec3d& lower, const vec3d& upper);
/// Writes NAME.particles beside NAME.cells, whole or not at all.
void writeNativeParticles(const ParticleSet& set, const std::string& cellsPath, const vec3d& lower, const vec3d& upper);

} // namespace exa
