// The scene options of the rendering commands (render, view): what is drawn and how, the
// camera, and the defaults that adapt to the data. Options given override a --scene file.
#pragma once

#include "common.h"

#include "exabricks/core/image.h"
#include "exabricks/render/defaults.h"
#include "exabricks/render/legends.h"
#include "exabricks/render/renderer.h"
#include "exabricks/render/scene.h"

#include <map>
#include <string>
#include <vector>

namespace exa {
struct Model;
}

namespace exa::cli {

struct RenderOptions {
  InputOptions in;
  std::string size = "800x800";
  std::string colormap = "viridis";
  std::string tfFile;
  std::vector<float> opacity;     ///< x0 a0 x1 a1 ... in normalised value
  float opacityScale = 0.f;       ///< 0: chosen from the dataset's size
  std::vector<std::string> range; ///< LOW,HIGH (movies also: global or per-step)
  bool logScale = false;
  bool linear = false;
  bool frameAll = false;
  std::vector<double> position, lookAt, up;
  double fov = 40.0;
  bool ortho = false;
  double azimuth = 30.0, elevation = 25.0;
  std::vector<float> background{0.f, 0.f, 0.f};
  std::string light = "headlight";
  // Surfaces and effects.
  std::vector<std::string> layers; ///< FIELD=COLORMAP or FIELD=TF_FILE
  std::vector<float> iso;
  std::string isoField;
  std::vector<float> isoColor; ///< sRGB triples, one per iso-value (cycled)
  std::string isoColorField;
  std::string isoColormap = "cool-to-warm";
  std::vector<float> isoColorRange;
  bool isoColorLog = false;
  std::vector<std::string> meshes;
  std::vector<float> meshColor; ///< sRGB triples, one per mesh (cycled)
  std::string particles;        ///< --particles [SPECIES]
  std::string particleRadiusBy, particleColorBy, particleColormap = "plasma";
  std::vector<float> particleColor; ///< sRGB
  std::vector<float> particleColorRange;
  bool particleColorLog = false;
  std::vector<std::string> clipPlanes; ///< px,py,pz,nx,ny,nz each
  std::vector<double> clipBox;
  std::vector<float> environment; ///< r,g,b linear radiance
  std::vector<float> sky, ground; ///< r,g,b linear radiance at the zenith and the nadir
  std::vector<float> sun;         ///< dx,dy,dz,intensity[,angle]
  std::string sceneFile;
  /// The flags that set one described scene setting each, by flag: their text as given.
  std::map<std::string, std::string> settings;

  /// Registers every option above on a command.
  void add(CLI::App& cmd);
};

/// The renderer options (how the march computes, for measurements) of render and movie.
struct MarchFlags {
  std::string device = "auto"; ///< cpu, cuda, auto or portable
  bool scalar = false;
  bool noLazyGradients = false;
  bool noJoinSegments = false;
  bool noMajorantGrid = false;

  void add(CLI::App& cmd);
  RendererOptions options() const;
};

/// Registers --device (where passes run) on a command.
void addDeviceOption(CLI::App& cmd, std::string& device);

/// The scene and frame the options describe, over the scene file when one is given: without a
/// file every option applies (defaults included); with one, only the options given.
SceneDocument sceneFromOptions(const RenderOptions& o, const CLI::App& cmd);
/// --particles [SPECIES] and the --particle-* options (particle_options.cpp).
void addParticleOptions(RenderOptions& o, CLI::App& cmd);
/// Applies them to the scene: all of them without a scene file, the ones given over one.
void applyParticleOptions(const RenderOptions& o, const CLI::App& cmd, bool fromFile, Scene& s);
/// A noise target's checks (--noise-target above 0, with the path tracer), and path tracing given
/// neither --spp nor --noise-target passing to the default target (sampling_options.cpp).
void applySampling(const CLI::App& cmd, bool fromFile, SceneDocument& doc);
/// The particles a scene shows, read from the input (only the species it names); null where it
/// shows none, or the input holds none (said once).
std::shared_ptr<const ParticleSet> particlesFor(const Scene& scene, const std::string& input);
/// Fields the scene needs; empty means all (a layer names the default field).
std::vector<std::string> neededFields(const Scene& s);
/// What a process that holds one part of the data (data-parallel rendering) knows of the whole,
/// agreed by every process: the first picture, the camera and the overlays are the whole data's.
struct WholeData {
  box3i cellBounds;        ///< lattice bounds of all cells
  std::vector<int> levels; ///< levels that hold cells
  PartialData histogram;   ///< the part's cells and the sum over the parts
};

/// Whether the first layer's transfer function is chosen from the data (no scene or
/// transfer-function file gives it): applyDataDefaults then reads the data's values.
inline bool choosesTransferFunction(const RenderOptions& o) { return o.sceneFile.empty() && o.tfFile.empty(); }
/// The first layer's transfer function as the first picture adapts it to the data (`field`: the
/// layer's field index), without a word on stderr.
inline DefaultChoices firstTransferFunction(const CLI::App& cmd, const Scene& scene, int field, const Model& model,
                                            const DatasetInfo& dataset, const WholeData* whole = nullptr) {
  auto given = [&](const char* name) { return cmd.count(name) > 0; };
  return adaptTransferFunction(model, dataset, field, scene.layers.at(0).tf, !given("--log") && !given("--linear"),
                               !given("--opacity"), whole ? &whole->histogram : nullptr, !given("--colormap"));
}
/// The first picture: names the default field, adapts the first layer's transfer function to the
/// data unless a file or the options chose it (as `chosen` says, where it was adapted already),
/// applies --linear and logs the scene's warnings (unless `warn` is false: the caller logs them
/// once the dataset's ranges are known). Returns the first layer's field index.
int applyDataDefaults(const RenderOptions& o, const CLI::App& cmd, Scene& scene, const Model& model,
                      const DatasetInfo& dataset, const WholeData* whole = nullptr, bool warn = true,
                      const DefaultChoices* chosen = nullptr);
/// The camera: the scene file's, or framing from azimuth and elevation the part of the data the
/// transfer function shows (all of it with --frame-all, or when nothing is visible); explicit
/// position, look-at and up override either.
Camera cameraFromOptions(const RenderOptions& o, const CLI::App& cmd, const SceneDocument& doc, const Model& model,
                         const box3d& visible, const WholeData* whole = nullptr);
/// Whether cameraFromOptions frames what the transfer function shows: the box `visible` it is
/// given, which costs a pass over the data to find, decides nothing otherwise.
bool framesVisibleData(const RenderOptions& o, const CLI::App& cmd, const SceneDocument& doc);
/// The scene document as a file records it: paths made absolute, so that it reads the same from
/// any folder.
SceneDocument withAbsolutePaths(SceneDocument doc);
/// The dataset's name as pictures and pages show it: the last component of its path
/// ("run/plt00100/" is "plt00100"), or the default dataset's description.
std::string datasetLabel(const std::string& input);
/// What the legends write of the dataset (its name), and the whole data's levels and domain
/// where this process holds a part.
LegendText legendText(const std::string& input, const WholeData* whole = nullptr);

} // namespace exa::cli
