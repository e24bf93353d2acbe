// Ray casting of AMR data through the active brick regions (paper §4-§5): volume ray marching
// with space skipping by the transfer function, adaptive steps of half a region's finest cell
// width, mid-interval samples with opacity correction, basis reconstruction with analytic
// gradients and front-to-back compositing; several fields with their own transfer functions;
// implicit iso-surfaces found by root finding in their own region set; triangle meshes;
// clipping planes and a clip box; ambient occlusion on surfaces. The same image for any thread
// count.
//
// Per ray: clip [tmin, tmax] by the planes and the box, find the nearest mesh hit (Embree) and
// the nearest iso-surface hit before it, integrate the volume up to that surface, then composite
// the shaded surface behind the volume.
#pragma once

#include "exabricks/accel/traversal.h"
#include "exabricks/io/image.h"
#include "exabricks/render/camera.h"
#include "exabricks/render/transfer_function.h"

#include <memory>
#include <string>
#include <vector>

namespace exa {

enum class Shading { Analytic, Central, ClampedCentral, None };
enum class DebugView { None, Level, Brick, Region, Steps };
/// How samples are placed: adaptive (per region, half its finest cell width) or fixed (half
/// the dataset's finest cell width everywhere).
enum class Sampling { Adaptive, Fixed };
/// How a sample's value is reconstructed: from the bricks its region lists (the method), or by
/// locating every contributing cell in a k-d tree over the bricks (the paper's baseline).
enum class Reconstruction { Regions, CellLocation };

struct TriangleMesh;

/// One volume field and its transfer function.
struct VolumeLayer {
  int field = 0;
  TransferFunction tf;
};

/// Implicit iso-surfaces of one field at one or more values.
struct IsoSurfaces {
  int field = -1;                 ///< -1: none
  std::vector<float> values;
  /// Linear-RGB colour per iso-value (cycled when fewer than values), used without colorField.
  std::vector<vec3f> colors;
  int colorField = -1;            ///< >= 0: colour by this field's value at the hit point ...
  TransferFunction colorTf;       ///< ... through this colour map and value range
};

/// Removes the half-space the normal points into: points x with dot(x - point, normal) > 0.
struct ClipPlane {
  vec3d point{0.0};
  vec3d normal{1.0, 0.0, 0.0};
};

struct RenderOptions {
  int width = 800, height = 800;
  int samplesPerPixel = 1;
  float rate = 1.f;               ///< quality factor: step = finest width x 0.5 / rate
  bool jitter = true;             ///< per-pixel random offset of the sample positions
  uint64_t seed = 0;
  bool earlyTermination = true;
  float terminationOpacity = 0.98f;
  Shading shading = Shading::Analytic;
  bool headlight = true;          ///< light from the eye; else from lightDirection
  vec3f lightDirection{-1.f, -1.f, -1.f}; ///< world direction light travels along
  float ambient = 0.3f, diffuse = 0.7f, specular = 0.25f, shininess = 40.f;
  /// Region traversal. With autoTraversal the renderer picks per transfer function: Embree when
  /// few regions are visible (it skips hidden space in its BVH), the k-d tree otherwise (cheaper
  /// per step); see docs/performance.md for the measurements behind the threshold.
  bool autoTraversal = true;
  TraversalKind traversal = TraversalKind::KdTree;
  float embreeBelowVisibleFraction = 0.15f;
  bool spaceSkipping = true;
  Sampling sampling = Sampling::Adaptive;
  Reconstruction reconstruction = Reconstruction::Regions;
  DebugView debug = DebugView::None;
  bool progress = false;          ///< progress line on a terminal

  bool volume = true;             ///< integrate the volume (off: surfaces only)
  /// Clipping (world space): every plane removes its half-space; the box, when not empty,
  /// keeps only its inside. Applies to volume and iso-surfaces, and to meshes with clipMeshes.
  std::vector<ClipPlane> clipPlanes;
  box3d clipBox;
  bool clipMeshes = false;
  /// Ambient occlusion on surface hits: rays per hit (0: off), their length in world units (0:
  /// a tenth of the data's world diagonal), and whether the volume also attenuates them.
  int aoRays = 0;
  float aoLength = 0.f;
  bool aoVolume = false;
};

/// The nearest surface along a ray.
struct SurfaceHit {
  enum Kind { Mesh, Iso } kind = Mesh;
  double distance = 0;     ///< world distance from the ray origin along the unit direction
  vec3d position{0.0};     ///< world
  vec3f normal{0.f};       ///< world, unit, facing the ray origin
  int index = 0;           ///< mesh number, or iso-value number
};

struct RenderStats {
  double seconds = 0;             ///< wall time of the frame(s)
  uint64_t rays = 0;
  uint64_t samples = 0;           ///< reconstructed samples (value + gradient each)
  uint64_t regionsVisited = 0;    ///< segments integrated
  uint64_t surfaceHits = 0;       ///< primary rays that ended on a mesh or iso-surface
  uint64_t isoSamples = 0;        ///< samples taken to find iso-surfaces (incl. root finding)
  uint64_t aoRays = 0;
  double samplesPerSecond() const { return seconds > 0 ? double(samples) / seconds : 0; }
};

class Renderer {
public:
  Renderer(const Model& model, int field, const RenderOptions& options);
  ~Renderer();

  /// Sets the transfer function of the renderer's field (a single volume layer) and rebuilds
  /// the set of visible regions; returns the update time in seconds (visibility + traversal).
  double setTransferFunction(const TransferFunction& tf);
  /// Several fields, each with its own transfer function. A sample's opacities add up as
  /// optical depths, alpha = 1 - prod(1 - alpha_i), and its colour is the opacity-weighted mean
  /// of the layers' shaded colours; a region is visible when any layer may see it.
  double setVolumeLayers(const std::vector<VolumeLayer>& layers);
  /// Sets the iso-surfaces and rebuilds their own region set (regions whose value range holds an
  /// iso-value); returns the rebuild time in seconds.
  double setIsoSurfaces(const IsoSurfaces& iso);
  /// Regions that may hold an iso-surface.
  size_t isoRegions() const;
  /// Adds a triangle mesh (world space) drawn in a linear-RGB colour.
  void addMesh(const TriangleMesh& mesh, const vec3f& color);
  size_t meshCount() const;

  /// The nearest (clipped) mesh or iso-surface hit along a world ray; false when there is none.
  bool pick(const vec3d& origin, const vec3d& direction, SurfaceHit& hit) const;
  /// Regions that may be visible under the current transfer function.
  size_t visibleRegions() const;
  /// The traversal in use (after setTransferFunction).
  TraversalKind traversalInUse() const;

  /// Renders one frame of options.samplesPerPixel samples per pixel.
  Image render(const Camera& camera, RenderStats* stats = nullptr) const;

  const RenderOptions& options() const { return options_; }
  RenderOptions& options() { return options_; }

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  RenderOptions options_;
};

} // namespace exa
