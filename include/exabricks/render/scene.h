// What is rendered (Scene) and how one frame is taken (Frame), as plain values that a caller
// edits between frames; the Renderer updates only what a change needs. Scenes and frames read
// from and write to JSON (the format of `exabricks render --scene`), see docs/rendering.md.
#pragma once

#include "exabricks/accel/traversal.h"
#include "exabricks/core/mesh.h"
#include "exabricks/render/camera.h"
#include "exabricks/render/camera_path.h"
#include "exabricks/render/sample_math.h"
#include "exabricks/render/transfer_function.h"

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace exa {

/// How volume samples get the normal they are lit with. Smooth (the default): a gradient field
/// reconstructed like the values, from per-cell central differences of the reconstruction one
/// cell width each way (amr/gradients.h). The basis interpolant has kinks at cell centres and
/// support faces, so its exact gradient jumps there and, lit, draws the cell lattice; the
/// reconstructed gradient field is continuous. Analytic: that exact gradient (cheaper). Central:
/// central differences half the region's finest width each way, at every sample. None: unlit.
/// ("clamped", an earlier name, reads as Smooth.)
enum class Shading { Analytic, Central, Smooth, None };
enum class DebugView { None, Level, Brick, Region, Steps };
/// How samples are placed: adaptive (per region, half its finest cell width) or fixed (half
/// the dataset's finest cell width everywhere).
enum class Sampling { Adaptive, Fixed };
/// How a sample's value is reconstructed: from the bricks its region lists (the method), or by
/// locating every contributing cell in a k-d tree over the bricks (the paper's baseline).
enum class Reconstruction { Regions, CellLocation };
/// How light is computed: the ray marcher (emission and absorption with local shading), or the
/// volume path tracer (delta tracking, single and multiple scattering, environment and sun).
enum class Integrator { March, PathTrace };

/// One volume field and its transfer function. An empty field name is the dataset's default
/// field ("scalar", else the first); an empty value range is the field's range, and an opacity
/// scale of 0 is the dataset's default scale (DatasetInfo).
struct VolumeLayer {
  std::string field;
  TransferFunction tf = defaultTransferFunction();
  friend bool operator==(const VolumeLayer&, const VolumeLayer&) = default;
};

/// Implicit iso-surfaces of one field at one or more values.
struct IsoSurfaces {
  std::string field;         ///< empty: the first volume layer's field
  std::vector<float> values; ///< none: no iso-surfaces
  /// Linear-RGB colour per iso-value (cycled when fewer than values), used without colorField.
  std::vector<vec3f> colors;
  std::string colorField; ///< not empty: colour by this field's value at the hit point ...
  TransferFunction colorTf = defaultTransferFunction("cool-to-warm"); ///< ... through this map and range
  friend bool operator==(const IsoSurfaces&, const IsoSurfaces&) = default;
};

/// A triangle mesh drawn in one linear-RGB colour. `source` names the file it came from, which
/// is what a scene file records (a mesh without one is written inline).
struct SceneMesh {
  std::shared_ptr<const TriangleMesh> mesh;
  vec3f color{0.8f};
  std::string source;
  friend bool operator==(const SceneMesh&, const SceneMesh&) = default;
};

/// Particles drawn as spheres with the volume: hidden by what is in front of them, dimming what is
/// behind, shaded and coloured like the other surfaces. Their positions and attributes come with
/// the dataset (Renderer::setParticles); this says which and how.
struct ParticleStyle {
  bool show = false;
  std::string species; ///< empty: every species
  float radius = 0.f;  ///< world units; 0: 1/800 of the data's diagonal
  /// Above 0: the radius in pixels at the distance of the camera's look-at point, which
  /// resolveParticleRadius turns into radius (nearer spheres look larger, as spheres do).
  float radiusPixels = 0.f;
  /// Not empty: radius x cbrt(value / the attribute's largest value), a sphere's volume in
  /// proportion to the attribute (mass); particles whose value is not above zero are not drawn.
  std::string radiusBy;
  vec3f color = srgbToLinear(vec3f(1.f, 0.7f, 0.35f)); ///< linear RGB, where not coloured by an attribute
  std::string colorBy;                                 ///< not empty: coloured by this attribute through colorTf ...
  TransferFunction colorTf = defaultTransferFunction("plasma"); ///< ... its map, range (empty: the data's) and log
  friend bool operator==(const ParticleStyle&, const ParticleStyle&) = default;
};

/// Removes the half-space the normal points into: points x with dot(x - point, normal) > 0.
struct ClipPlane {
  vec3d point{0.0};
  vec3d normal{1.0, 0.0, 0.0};
  friend bool operator==(const ClipPlane&, const ClipPlane&) = default;
};

/// Clipping (world space): every plane removes its half-space; the box, when not empty, keeps
/// only its inside. Applies to volume and iso-surfaces, and to meshes and particles with `meshes`.
struct Clipping {
  std::vector<ClipPlane> planes;
  box3d box;
  bool meshes = false;
  friend bool operator==(const Clipping&, const Clipping&) = default;
};

struct Light {
  bool headlight = true;             ///< light from the eye; else from direction
  vec3f direction{-1.f, -1.f, -1.f}; ///< world direction light travels along
  ShadingTerms terms;
};

/// Ambient occlusion on surface hits: rays per hit (0: off), their length in world units (0: a
/// tenth of the data's world diagonal), and whether the volume also attenuates them.
struct AmbientOcclusion {
  int rays = 0;
  float length = 0.f;
  bool volume = false;
};

/// How the volume is integrated. With autoTraversal the renderer picks per transfer function:
/// Embree when few regions are visible (it skips hidden space in its BVH), the k-d tree
/// otherwise (cheaper per step); docs/performance-log.md has the measurements behind the threshold.
struct Integration {
  Sampling sampling = Sampling::Adaptive;
  Reconstruction reconstruction = Reconstruction::Regions;
  bool autoTraversal = true;
  TraversalKind traversal = TraversalKind::KdTree;
  float embreeBelowVisibleFraction = 0.15f;
  bool spaceSkipping = true;
  bool uniformStride = true; ///< longer steps where the look is uniform (regionStride)
  bool earlyTermination = true;
  float terminationOpacity = 0.98f;
  Integrator integrator = Integrator::March;
  friend bool operator==(const Integration&, const Integration&) = default;
};

/// The volume path tracer's medium and lights (Integrator::PathTrace). The transfer function's
/// opacity gives the extinction, its colour the scattering colour; `albedo` is the share of
/// extinction that scatters (Henyey-Greenstein phase function of anisotropy `anisotropy`), the
/// rest absorbs and emits `emission` times the colour (a layer's transfer function may give its
/// own albedo per value). Light comes from the environment (linear RGB radiance: `environment` at
/// the horizon, blending linearly in the sine of the elevation to `sky` at the zenith, along the
/// camera's up direction, and to `ground` at the nadir; either unset is the horizon's, so that
/// without both the environment is uniform) and a sun: a directional light travelling along
/// `sunDirection` (world) with irradiance `sunIntensity`, its disc `sunAngle` degrees across
/// (0: a point).
struct PathTracing {
  float albedo = 0.8f;
  float anisotropy = 0.f;
  int bounces = 4;
  float emission = 0.f;
  vec3f environment{1.f, 1.f, 1.f};
  std::optional<vec3f> sky, ground;
  vec3f sunDirection{-1.f, -1.f, -1.f};
  float sunIntensity = 0.f;
  float sunAngle = 0.53f;
  friend bool operator==(const PathTracing&, const PathTracing&) = default;
};

/// Legends drawn over the rendered image (render/legends.h): the colour bar of the first layer
/// (with the volume on and no debug view), the annotation (dataset name, field, simulation time
/// and cycle, domain outline) and, with the level debug view, the legend of the level colours.
struct Legends {
  bool colorBar = false;
  bool annotation = false;
  bool levelLegend = false;
  friend bool operator==(const Legends&, const Legends&) = default;
};

struct Scene {
  std::vector<VolumeLayer> layers{VolumeLayer{}}; ///< several fields: summed optical depth
  bool volume = true;                             ///< integrate the volume (off: surfaces only)
  IsoSurfaces iso;
  std::vector<SceneMesh> meshes;
  ParticleStyle particles;
  Clipping clip;
  Light light;
  Shading shading = Shading::Smooth;
  AmbientOcclusion ao;
  Integration integration;
  PathTracing pathTracing;
  DebugView debug = DebugView::None;
  /// Linear RGB, used when images are written. Black: the volume emits light, and faint
  /// structure shows against black where it vanishes against white.
  vec3f background{0.f};
  bool keepAlpha = false; ///< images keep alpha instead of the background
  Legends legends;        ///< drawn after rendering, where images are written or shown

  /// A scene of one volume layer.
  static Scene volumeOf(const TransferFunction& tf, const std::string& field = {});
  /// Throws exa::Error naming the first invalid setting.
  void validate() const;
};

/// One frame: camera, size and sampling. `frameIndex` selects the random numbers of a
/// progressive pass (pixel jitter and sample offsets come from pixel, frame index and seed);
/// `samplesPerPixel` is the number of passes a full image takes, and pixel positions are
/// jittered only when it is above one, so passes 0..N-1 of a frame with samplesPerPixel N sum
/// to the same image as one N-sample render.
struct Frame {
  Camera camera;
  int width = 800, height = 800;
  int samplesPerPixel = 1;
  /// Above 0: path-traced passes stop, tile by tile, once the noise a tile's passes estimate
  /// (the standard error of its 8-bit sRGB values, RMS over its pixels) is at most this many
  /// 1/255 steps, after at least kNoiseFirstPasses and at most samplesPerPixel passes.
  float noiseTarget = 0.f;
  /// Path tracing: the picture is denoised (render/denoise.h), guided by the frame ray-marched;
  /// a noise target is then the denoised picture's.
  bool denoise = false;
  int frameIndex = 0;
  float rate = 1.f;   ///< quality factor: step = region's finest width x 0.5 / rate
  bool jitter = true; ///< random offsets of the sample positions
  uint64_t seed = 0;
  /// Optional per-pixel depth limit, width x height values row by row (row 0 at the top), which
  /// the caller keeps alive while rendering: nothing farther along a pixel's rays is drawn
  /// (volume, iso-surfaces, meshes), as where opaque geometry drawn by others hides the rest.
  /// A value is a world distance along the ray from its origin, or with depthLimitPlanar the
  /// depth along the view direction from the camera's plane (what a z-buffer holds); +inf is no
  /// limit. Never part of scene files.
  const float* depthLimit = nullptr;
  bool depthLimitPlanar = false;
  /// Optional, per pixel (row-major, width × height), kept alive by the caller: the opacity that
  /// the data in front of the renderer's domain gathered along each pixel's ray in this pass (a
  /// step drawn part by part, front to back). A ray then starts with it, so that early termination
  /// and surfaces behind see what one ray through all the data sees; the pass's colour is this
  /// part's light already dimmed by the front, and its opacity the total. Never part of scene files.
  const float* frontOpacity = nullptr;

  /// A cheap draft of this frame: 1/divisor of the resolution per axis (at least one pixel)
  /// and the given sampling rate (without the depth limit when the resolution changes).
  Frame preview(int divisor, float previewRate) const;
  /// Throws exa::Error naming the first invalid setting.
  void validate() const;
};

/// With particles.radiusPixels above 0: particles.radius set to that many of the frame's pixels at
/// the distance of its camera's look-at point (front ends call it before Renderer::setScene; a
/// camera moving nearer or farther then rebuilds the spheres).
void resolveParticleRadius(Scene& scene, const Frame& frame);

/// A scene file: the scene, the frame, and optionally the input they were made for.
struct SceneDocument {
  std::string input; ///< dataset path, empty when not recorded
  Scene scene;
  Frame frame;
  bool hasCamera = false; ///< the document set a camera (else the caller frames the data)
  CameraPath path;        ///< movies: camera keyframes (empty: the camera stays)
};

/// Writes a scene document as JSON (every setting, colours in sRGB), numbers that hold single
/// precision values in their shortest form (0.3, not 0.30000001192092896).
std::string writeSceneJson(const SceneDocument& doc);
/// The same document with every number exact, on one line: a key that tells any two scenes apart.
std::string exactSceneJson(const SceneDocument& doc);
/// Reads JSON written by writeSceneJson, or any subset of its keys (the rest keep their
/// defaults). Meshes named by file keep their `source` and no data: documents/scene_file.h reads them.
/// Errors name `source` and the offending key.
SceneDocument readSceneJson(const std::string& text, const std::string& source);

} // namespace exa
