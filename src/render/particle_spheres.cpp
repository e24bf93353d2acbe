#include "particle_spheres.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"

#include <algorithm>
#include <cmath>

namespace exa {
namespace {

std::vector<const ParticleSpecies*> drawnSpecies(const ParticleSet& set, const std::string& wanted) {
  std::vector<const ParticleSpecies*> out;
  std::string names;
  for (const ParticleSpecies& s : set.species) {
    names += (names.empty() ? "" : ", ") + s.name;
    if (wanted.empty() || s.name == wanted) out.push_back(&s);
  }
  if (!wanted.empty() && out.empty())
    fail("no particle species '", wanted, "' (",
         set.species.empty() ? std::string("the dataset holds no particles") : "the dataset holds: " + names, ")");
  return out;
}

/// The attribute `name` of every species that has it; fails when none has it.
std::vector<const ParticleAttribute*> attributeOf(const std::vector<const ParticleSpecies*>& species,
                                                  const std::string& name, const char* what) {
  std::vector<const ParticleAttribute*> out;
  std::string lacking;
  bool any = false;
  for (const ParticleSpecies* s : species) {
    out.push_back(s->attribute(name));
    any = any || out.back();
    if (!out.back()) lacking += (lacking.empty() ? "" : ", ") + s->name;
  }
  if (!any && !species.empty()) {
    std::string known;
    for (const ParticleAttribute& a : species[0]->attributes)
      known += (known.empty() ? "" : ", ") + a.name;
    fail("particles.", what, ": no particle attribute '", name, "' (", species[0]->name, " has: ", known, ")");
  }
  if (!lacking.empty())
    logWarning(strCat("particles.", what, ": species ", lacking, " have no attribute '", name,
                      "'; they are drawn without it"));
  return out;
}

} // namespace

ParticleSpheres particleSpheres(const ParticleSet& set, const ParticleStyle& style, float defaultRadius) {
  ParticleSpheres out;
  if (!style.show) return out;
  const std::vector<const ParticleSpecies*> species = drawnSpecies(set, style.species);
  const float radius = style.radius > 0.f ? style.radius : defaultRadius;
  std::vector<const ParticleAttribute*> sizes(species.size(), nullptr), colors(species.size(), nullptr);
  if (!style.radiusBy.empty()) sizes = attributeOf(species, style.radiusBy, "radius_by");
  if (!style.colorBy.empty()) colors = attributeOf(species, style.colorBy, "color_by");
  // The radius attribute's largest value and the colour attribute's range (positive values
  // only on a logarithmic map) over the species drawn.
  double largest = 0.0;
  range1f range;
  for (size_t k = 0; k < species.size(); ++k) {
    if (sizes[k])
      for (double v : sizes[k]->values)
        largest = std::max(largest, v);
    if (colors[k])
      for (double v : colors[k]->values)
        if (std::isfinite(v) && (!style.colorTf.logScale || v > 0.0)) range.extend(float(v));
  }
  TransferFunction tf = style.colorTf;
  if (tf.valueRange.empty()) tf.valueRange = range.empty() ? range1f{0.f, 1.f} : range;
  for (size_t k = 0; k < species.size(); ++k) {
    const ParticleSpecies& s = *species[k];
    for (size_t p = 0; p < s.count(); ++p) {
      float r = radius;
      if (sizes[k]) {
        const double v = sizes[k]->values[p];
        if (!(v > 0.0) || !(largest > 0.0)) continue;
        r = float(double(radius) * std::cbrt(v / largest));
      }
      if (!(r > 0.f)) continue;
      const double* x = &s.position[3 * p];
      if (!std::isfinite(x[0]) || !std::isfinite(x[1]) || !std::isfinite(x[2]) || !std::isfinite(r)) continue;
      out.spheres.push_back({vec3f(float(x[0]), float(x[1]), float(x[2])), r});
      out.colors.push_back(colors[k] ? tf.colorMap.at(tf.normalize(float(colors[k]->values[p]))) : style.color);
    }
  }
  return out;
}

} // namespace exa
