// The command line's particle options: which species to draw as spheres, their radius and
// colour, and reading them from the input.
#include "common.h"
#include "scene_options.h"

#include "exabricks/core/log.h"
#include "exabricks/io/particles.h"

#include <filesystem>

namespace exa::cli {

void addParticleOptions(RenderOptions& o, CLI::App& cmd) {
  cmd.add_option("--particles", o.particles,
                 "Draw the input's particles as spheres: every species, or the one named (scene key particles.show, "
                 "particles.species)")
      ->expected(0, 1)
      ->type_name("[SPECIES]");
  cmd.add_option("--particle-radius-by", o.particleRadiusBy,
                 "Scale each sphere's radius by the cube root of this attribute (particles.radius_by)");
  cmd.add_option("--particle-color", o.particleColor, "The spheres' colour r,g,b (sRGB; particles.color)")
      ->delimiter(',')
      ->check(singleNumber());
  cmd.add_option("--particle-color-by", o.particleColorBy, "Colour the spheres by this attribute (particles.color_by)");
  cmd.add_option("--particle-colormap", o.particleColormap, "Colour map for --particle-color-by")
      ->capture_default_str()
      ->check(colormapName());
  cmd.add_option("--particle-range", o.particleColorRange, "Value range LOW,HIGH for --particle-color-by")
      ->delimiter(',')
      ->check(singleNumber());
  cmd.add_flag("--particle-log", o.particleColorLog, "Map --particle-color-by logarithmically");
}

void applyParticleOptions(const RenderOptions& o, const CLI::App& cmd, bool fromFile, Scene& s) {
  auto apply = [&](const char* name) { return !fromFile || cmd.count(name) > 0; };
  ParticleStyle& p = s.particles;
  if (cmd.count("--particles")) {
    std::error_code ec;
    if (!o.particles.empty() && o.in.input.empty() && std::filesystem::exists(o.particles, ec))
      failUsage("--particles took '", o.particles,
                "' for a species name: name the input first (exabricks render INPUT --particles [SPECIES])");
    p.show = true;
    p.species = o.particles;
  }
  const bool shown = p.show;
  for (const char* flag : {"--particle-radius-by", "--particle-color", "--particle-color-by", "--particle-range",
                           "--particle-log", "--particle-radius", "--particle-radius-pixels"})
    if (cmd.count(flag) && !shown) logWarning(strCat(flag, " does nothing without --particles"));
  if (!o.particleColorRange.empty() &&
      (o.particleColorRange.size() != 2 || !(o.particleColorRange[0] < o.particleColorRange[1])))
    failUsage("--particle-range expects LOW,HIGH with LOW < HIGH");
  if (!o.particleColor.empty()) {
    if (o.particleColor.size() != 3) failUsage("--particle-color expects r,g,b (sRGB, each in [0, 1])");
    for (float c : o.particleColor)
      if (!(c >= 0.f && c <= 1.f)) failUsage("--particle-color components must lie in [0, 1] (sRGB)");
    p.color = srgbToLinear(vec3f(o.particleColor[0], o.particleColor[1], o.particleColor[2]));
  }
  if (apply("--particle-radius-by")) p.radiusBy = o.particleRadiusBy;
  if (apply("--particle-color-by")) p.colorBy = o.particleColorBy;
  if (apply("--particle-colormap")) p.colorTf.colorMap = builtinColorMap(o.particleColormap);
  if (apply("--particle-log")) p.colorTf.logScale = o.particleColorLog;
  if (apply("--particle-range"))
    p.colorTf.valueRange =
        o.particleColorRange.empty() ? range1f() : range1f{o.particleColorRange[0], o.particleColorRange[1]};
}

std::shared_ptr<const ParticleSet> particlesFor(const Scene& scene, const std::string& input) {
  if (!scene.particles.show) return nullptr;
  if (input.empty()) {
    logWarning("particles: the embedded dataset holds none; nothing is drawn for them");
    return nullptr;
  }
  std::shared_ptr<const ParticleSet> set = readParticlesIfAny(input, scene.particles.species);
  if (!set) {
    logWarning(strCat("particles: ", input, " holds none; nothing is drawn for them"));
    return nullptr;
  }
  uint64_t count = 0;
  for (const ParticleSpecies& s : set->species)
    count += s.count();
  logInfo(strCat("read ", count, " particles of ", set->species.size(), " species from ", input));
  return set;
}

} // namespace exa::cli
