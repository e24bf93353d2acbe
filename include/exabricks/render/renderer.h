// Volume ray marching through the active brick regions (paper §4-§5): space skipping by the
// transfer function, adaptive steps of half a region's finest cell width, mid-interval samples
// with opacity correction, basis reconstruction with analytic gradients, front-to-back
// compositing. The same image for any thread count.
#pragma once

#include "exabricks/accel/traversal.h"
#include "exabricks/io/image.h"
#include "exabricks/render/camera.h"
#include "exabricks/render/transfer_function.h"

#include <memory>
#include <string>

namespace exa {

enum class Shading { Analytic, Central, ClampedCentral, None };
enum class DebugView { None, Level, Brick, Region, Steps };
/// How samples are placed: adaptive (per region, half its finest cell width) or fixed (half
/// the dataset's finest cell width everywhere).
enum class Sampling { Adaptive, Fixed };
/// How a sample's value is reconstructed: from the bricks its region lists (the method), or by
/// locating every contributing cell in a k-d tree over the bricks (the paper's baseline).
enum class Reconstruction { Regions, CellLocation };

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
};

struct RenderStats {
  double seconds = 0;             ///< wall time of the frame(s)
  uint64_t rays = 0;
  uint64_t samples = 0;           ///< reconstructed samples (value + gradient each)
  uint64_t regionsVisited = 0;    ///< segments integrated
  double samplesPerSecond() const { return seconds > 0 ? double(samples) / seconds : 0; }
};

class Renderer {
public:
  Renderer(const Model& model, int field, const RenderOptions& options);
  ~Renderer();

  /// Sets the transfer function and rebuilds the set of visible regions; returns the update
  /// time in seconds (visibility + traversal structure).
  double setTransferFunction(const TransferFunction& tf);
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
