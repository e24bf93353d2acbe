// The command line's sampling: a noise target's checks, and the passes path tracing takes by
// default.
#include "common.h"
#include "scene_options.h"

#include "exabricks/core/log.h"
#include "exabricks/core/text.h"
#include "exabricks/render/defaults.h"

namespace exa::cli {

/// A noise target is above 0 and for the path tracer, and so is the denoiser; path tracing
/// without a scene file is denoised unless --denoise off, and given neither --spp nor
/// --noise-target passes to kDefaultNoiseTarget.
void applySampling(const CLI::App& cmd, bool fromFile, SceneDocument& doc) {
  Frame& f = doc.frame;
  const bool pathTraced = doc.scene.integration.integrator == Integrator::PathTrace,
             given = cmd.count("--noise-target");
  if (given && !(f.noiseTarget > 0.f))
    failUsage("--noise-target: ", f.noiseTarget, " is not above 0 (the noise in 1/255 steps at which a tile stops)");
  if (given && !pathTraced)
    failUsage("--noise-target: the ray marcher takes --spp passes everywhere; the noise target is for "
              "--integrator pathtrace");
  if (cmd.count("--denoise") && f.denoise && !pathTraced)
    failUsage("--denoise: the ray marcher's pictures have no noise to remove; the denoiser is for "
              "--integrator pathtrace");
  if (!pathTraced || doc.scene.debug != DebugView::None || fromFile) return;
  if (!cmd.count("--denoise")) f.denoise = true;
  if (given || cmd.count("--spp")) return;
  f.noiseTarget = kDefaultNoiseTarget;
  f.samplesPerPixel = kDefaultPathTracedPasses;
  logNote(strCat("path tracing each tile until its ", f.denoise ? "denoised picture's " : "", "noise is at most ",
                 kDefaultNoiseTarget, "/255 (at most ", kDefaultPathTracedPasses,
                 " samples per pixel; --noise-target or --spp to choose)"));
}

} // namespace exa::cli
