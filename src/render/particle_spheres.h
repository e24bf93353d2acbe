// The spheres a scene's particle style makes of a dataset's particles: which species, each
// sphere's radius and its colour (fixed, or an attribute through a colour map), for the one
// sphere hierarchy every back end intersects.
#pragma once

#include "exabricks/accel/sphere_bvh.h"
#include "exabricks/amr/particles.h"
#include "exabricks/render/scene.h"

#include <vector>

namespace exa {

struct ParticleSpheres {
  std::vector<BvhSphere> spheres;
  std::vector<vec3f> colors; ///< linear RGB, one per sphere
};

/// The spheres of the particles `style` draws (none unless style.show). `defaultRadius` is the
/// radius a style of radius 0 gets. Throws exa::Error naming a species or attribute the
/// particles lack (an attribute some species lack: those are drawn in the style's colour or
/// radius, said once).
ParticleSpheres particleSpheres(const ParticleSet& set, const ParticleStyle& style, float defaultRadius);

} // namespace exa
