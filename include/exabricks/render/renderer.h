// Ray casting of AMR data through the active brick regions (paper §4-§5): volume ray marching
// with space skipping by the transfer function, adaptive steps of half a region's finest cell
// width, mid-interval samples with opacity correction, basis reconstruction with analytic
// gradients and front-to-back compositing; several fields with their own transfer functions;
// implicit iso-surfaces found by root finding in their own region set; triangle meshes;
// clipping planes and a clip box; ambient occlusion on surfaces.
//
// The renderer holds a Scene; setScene() compares the new scene with the current one and
// rebuilds only what changed (transfer functions -> visible regions and traversal; iso-values
// -> iso region set; meshes -> mesh BVH). renderPass() adds one sample per pixel to a
// caller-owned FrameBuffer, with random numbers from (pixel, frame index, seed), so N passes
// equal one N-sample render bit for bit, for any thread count. Passes can be cancelled from
// another thread between tiles and allocate nothing once the buffer has its size.
//
// Per ray: clip [tmin, tmax] by the planes and the box, find the nearest mesh hit (Embree) and
// the nearest iso-surface hit before it, integrate the volume up to that surface, then composite
// the shaded surface behind the volume.
#pragma once

#include "exabricks/amr/particles.h"
#include "exabricks/core/image.h"
#include "exabricks/render/frame_buffer.h"
#include "exabricks/render/scene.h"

#include <array>
#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace exa {

struct Model;
struct GradientFields; // amr/gradients.h

/// Dataset-wide values the renderer needs, explicit so that a renderer that sees only part of
/// the data can be given the whole dataset's values. `of()` computes them once from a model.
struct DatasetInfo {
  float referenceWidth = 1.f;       ///< lattice units: opacity is per this width; fixed steps use it
  double worldDiagonal = 1.0;       ///< default ambient-occlusion length is a tenth of it
  std::vector<range1f> valueRanges; ///< per field: the default transfer-function range
  float extentCells = 1.f;          ///< the data's longest side in finest cells
  float defaultOpacityScale = 1.f;  ///< a ray through the whole data gathers an optical depth of ~8

  static DatasetInfo of(const Model& model);
  /// The values of a dataset whose finest level, lattice bounds of the cells, world scale and
  /// per-field value ranges are known (for example agreed by the processes that hold its parts).
  static DatasetInfo from(int finestLevel, const box3i& cellBounds, const vec3d& worldScale,
                          std::vector<range1f> valueRanges);
  /// These values, once checked to fit `model`: a value range per field, a positive finite
  /// reference width.
  const DatasetInfo& checkedFor(const Model& model) const;
};

/// The colour of a level in the level debug view (levels 0..7, cycling): distinct hues, finest warm.
vec3f debugLevelColor(int level);

/// The nearest surface along a ray.
struct SurfaceHit {
  enum Kind { Mesh, Iso, Particle } kind = Mesh;
  double distance = 0; ///< world distance from the ray origin along the unit direction
  vec3d position{0.0}; ///< world
  vec3f normal{0.f};   ///< world, unit, facing the ray origin
  int index = 0;       ///< mesh number, iso-value number, or particle (in the drawn particles' order)
};

/// What setScene() rebuilt, and how long each part took.
struct SceneUpdate {
  bool volume = false;    ///< layer tables, visible regions and traversal
  bool iso = false;       ///< iso region set
  bool meshes = false;    ///< mesh BVH
  bool particles = false; ///< the particles' spheres and their hierarchy
  double volumeSeconds = 0, isoSeconds = 0, meshSeconds = 0;
  /// A GPU renderer: bytes copied to the device (only what changed) and the time it took.
  uint64_t deviceBytes = 0;
  double deviceSeconds = 0;
  double seconds() const { return volumeSeconds + isoSeconds + meshSeconds + deviceSeconds; }
};

/// Where a renderer's passes run.
enum class Device {
  Cpu,      ///< CPU threads with the batched, vectorised march (the default)
  Cuda,     ///< an NVIDIA GPU through CUDA
  Portable, ///< CPU threads running the GPU's per-ray code (one sample at a time): for comparisons
};

/// "cpu", "cuda" or "portable"; "auto" is CUDA where a GPU is present, else the CPU. Throws
/// exa::Error for another name, or for "cuda" where no GPU can be used (saying why).
Device resolveDevice(const std::string& name);
const char* deviceName(Device device);

class Renderer;
/// Moves the renderer to the device `choice` names ("cpu", "cuda", "portable" or "auto") for its
/// current scene and returns the device in use: "auto" takes the GPU where one is present and the
/// scene has nothing the GPU lacks (else the CPU, saying why on the log); the others throw where
/// they cannot be used.
Device selectDevice(Renderer& renderer, const std::string& choice);

/// What the machine offers for Device::Cuda.
struct CudaStatus {
  bool built = false; ///< this build has the CUDA back end
  int devices = 0;    ///< GPUs the CUDA runtime sees
  std::string name;   ///< the first one's name
  uint64_t totalBytes = 0, freeBytes = 0;
  std::string problem; ///< why Device::Cuda cannot be used (empty when it can)
};
CudaStatus cudaStatus();
/// The GPU this process uses of `devices`: EXABRICKS_CUDA_DEVICE where set; else, where an MPI
/// launcher started several processes on the node (its local rank: Open MPI, MPICH / PMI, Slurm),
/// local rank k takes GPU k mod devices, so that the processes of a node split its GPUs; else 0.
int cudaDeviceOfProcess(int devices);
/// The "device" object of `info --json`: whether the CUDA back end is built, the GPUs it sees,
/// what "auto" chooses, and the bytes a GPU renderer holds for `model`'s structures and per field.
std::string deviceInfoJson(const Model& model);

/// A device renderer's memory: bytes per structure held on the device.
struct DeviceMemory {
  std::vector<std::pair<std::string, uint64_t>> structures;
  uint64_t total() const {
    uint64_t t = 0;
    for (const auto& s : structures)
      t += s.second;
    return t;
  }
};

/// What a GPU renderer holds for a model: its structures, and one field's values (smooth shading
/// holds four times as many: the values with their gradients).
struct DeviceFootprint {
  DeviceMemory model; ///< bricks, regions, region brick lists, region k-d tree
  uint64_t fieldBytes = 0;
};
DeviceFootprint deviceFootprint(const Model& model);

/// How the renderer computes, not what it shows: switches that benchmarks and tests use to
/// compare variants of the volume march. Images are the same whatever they are set to, to float
/// round-off (the tests hold them to it); none of them is a scene setting.
struct RendererOptions {
  /// The march's batches with SIMD (amr/basis_batch.h, render/shade_batch.h) for the instruction
  /// set chosen at run time; off: the same batches lane after lane through the scalar functions.
  bool vectorized = true;
  /// After samples that the transfer function hides, reconstruct the next batch's values first
  /// and their gradients only if one of them shows.
  bool lazyGradients = true;
  /// Fill each batch with the samples of consecutive region segments (reconstructed over the
  /// union of their regions' brick lists); off: one batch per segment.
  bool joinSegments = true;
  /// Path tracing: delta tracking against a majorant grid (macrocells over the regions) as well
  /// as the regions' majorants; off: the regions' majorants alone.
  bool majorantGrid = true;
  friend bool operator==(const RendererOptions&, const RendererOptions&) = default;
};

/// Controls of one pass: a share of the tiles, cancellation and progress.
struct PassControl {
  /// Tiles tileBegin, tileBegin + tileStride, ... below tileEnd (-1: all), row-major.
  int tileBegin = 0, tileEnd = -1, tileStride = 1;
  /// Optional, one entry per tile of the buffer: of the tiles above, only those whose entry is
  /// not 0 (null: all of them).
  const std::vector<uint8_t>* tileMask = nullptr;
  /// The tiles selected among `tileCount`, in order, into `tiles` (its memory kept).
  void selected(int tileCount, std::vector<int>& tiles) const;
  /// Checked before every tile; once true, the pass adds no further tile and returns false.
  const std::atomic<bool>* cancel = nullptr;
  /// Called from worker threads after each tile with (tiles done, tiles in the pass).
  std::function<void(uint64_t, uint64_t)> progress;
  /// Under a noise target (NoiseRounds), called with the tile passes planned so far for the
  /// selected tiles, at the start and whenever a round plans more: a progress total that grows.
  std::function<void(uint64_t)> planned;
};

/// What a first view frames, in lattice units: the regions that may show the volume, the cells in
/// them drawn at a tenth of the largest opacity or more, and the regions that may hold an
/// iso-surface. Renderers that each hold one part of a dataset (processes, a step held in parts)
/// give theirs within their part, and the union frames the whole as one renderer over it would.
struct VisibleExtent {
  box3f volume, opaque, iso;
  void extend(const VisibleExtent& other);
  /// Each box clipped to the lattice box `part` (closed: a face shared with it counts).
  VisibleExtent within(const box3l& part) const;
  /// The framed lattice box: the opaque cells with a margin of a twentieth of their size, within
  /// the volume's regions (the regions alone where no cell is that opaque), and the iso regions.
  box3f framed() const;
};

/// Passes every tile takes before its noise is estimated (Frame::noiseTarget).
constexpr int kNoiseFirstPasses = 16;
/// The same for a denoised frame (Frame::denoise): the filter averages each pixel's passes with
/// its neighbours', so fewer estimate the noise as well. Three: on the shared samples the same
/// noise target in 0.84 to 1.01 times the time of four (and four in 0.6 to 0.8 times that of
/// eight), the denoised picture's low frequencies 0.04 to 0.14/255 further from a converged
/// render than with four (docs/performance.md).
constexpr int kDenoisedFirstPasses = 3;

/// How the rounds to a noise target measure: per tile, the noise a buffer's passes leave in the
/// picture made of them (`measure`: one value per tile), and whether any of the processes that
/// share the frame's tiles takes another round (`agree`, given this one's wish; null: alone).
struct TileNoiseEstimate {
  std::function<void(const FrameBuffer& buffer, std::vector<float>& tileNoise)> measure;
  std::function<bool(bool more)> agree;
};

/// Whether a frame of the scene is denoised: Frame::denoise, path tracing, no debug view.
bool denoises(const Scene& scene, const Frame& frame);

/// Passes to a frame's noise target, tile by tile (Renderer::renderSampled, progressive views):
/// next() names the tiles that take the next pass and its frame index, those holding the fewest
/// passes among the tiles that want more, so that every tile takes its passes in order. A tile
/// wants kNoiseFirstPasses, then, while its noise (FrameBuffer::tileNoise) is above the target,
/// the passes its noise predicts (between a sixteenth more and twice as many; four times as many
/// where a denoised estimate's tiles that want more come to less than an eighth of a pass over
/// the frame, since each estimate filters again), at most the frame's samplesPerPixel.
class NoiseRounds {
public:
  /// Whether a frame of the scene takes its passes to its noise target (path tracing, a target
  /// above 0, more than one sample per pixel, no debug view).
  static bool applies(const Scene& scene, const Frame& frame);
  /// Starts over for the tiles `control` selects in `buffer` (to be cleared).
  void start(const Frame& frame, const FrameBuffer& buffer, const PassControl& control);
  bool started() const { return !goal_.empty(); }
  /// The next pass: `control`'s mask (this object's) selects its tiles and `frameIndex` is its
  /// index; false when every tile holds its passes.
  /// `estimate`, where given, measures the tiles' noise instead of FrameBuffer::tileNoise (the
  /// denoised picture's: denoisedNoise()).
  bool next(const Frame& frame, const FrameBuffer& buffer, const vec3f& background, PassControl& control,
            int& frameIndex, const TileNoiseEstimate* estimate = nullptr);

private:
  void tellPlanned(const PassControl& control) const;
  std::vector<uint32_t> goal_;
  std::vector<uint8_t> mask_;
  std::vector<float> noise_;
};

class Renderer {
public:
  explicit Renderer(const Model& model);
  Renderer(const Model& model, const DatasetInfo& dataset);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// Makes `scene` current, rebuilding only what differs from the current scene. Throws
  /// exa::Error (and keeps the previous scene) when a setting is invalid or names an unknown
  /// field.
  SceneUpdate setScene(const Scene& scene);
  const Scene& scene() const;
  /// The particles beside the model (null: none), drawn where the scene's particle style shows
  /// them; the renderer keeps the set and builds their spheres at the next setScene. The set
  /// must not change while the renderer holds it.
  void setParticles(std::shared_ptr<const ParticleSet> particles);
  /// Spheres drawn for the particles (0 where none are shown).
  size_t particleCount() const;
  /// How the following passes compute (RendererOptions); takes effect at once, rebuilding only the
  /// path tracer's majorants when majorantGrid changes.
  void setOptions(const RendererOptions& options);
  const RendererOptions& options() const;
  /// Where the following passes run. Device::Cuda copies the model (bricks, regions, k-d tree,
  /// the fields in use) to the GPU once and, at each setScene, only what changed. Throws
  /// exa::Error where the device cannot be used, or where the current scene needs a feature the
  /// device does not have (the renderer then stays where it was).
  void setDevice(Device device);
  Device device() const;
  /// Memory the device holds for this renderer (empty on the CPU).
  DeviceMemory deviceMemory() const;
  const DatasetInfo& dataset() const;
  const Model& model() const;

  /// Adds pass `frame.frameIndex` (one sample per pixel) to the buffer, which must have the
  /// frame's size. Returns false when cancelled (only whole tiles were added).
  bool renderPass(const Frame& frame, FrameBuffer& buffer, const PassControl& control = {}) const;
  /// Adds passes (frame index = the passes the buffer holds) until the buffer holds `passes`;
  /// false when cancelled.
  bool renderPasses(const Frame& frame, FrameBuffer& buffer, int passes, const PassControl& control = {}) const;
  /// Every pass of a frame, into a cleared buffer, for the tiles the control selects: passes
  /// 0..samplesPerPixel-1, or with a noise target (Frame::noiseTarget) when path tracing, each
  /// tile's passes 0..n-1 for the n that brings its noise (FrameBuffer::tileNoise) to the target
  /// (at least kNoiseFirstPasses, at most samplesPerPixel): a tile equals the same tile of an
  /// n-sample render. False when cancelled.
  /// `estimate`, where given, measures the noise instead (NoiseRounds::next).
  bool renderSampled(const Frame& frame, FrameBuffer& buffer, const PassControl& control = {},
                     const TileNoiseEstimate* estimate = nullptr) const;
  /// A whole frame: renderSampled into a fresh buffer, resolved.
  Image render(const Frame& frame, RenderStats* stats = nullptr) const;

  /// Restricts primary rays to the inside of a world box, for a renderer that holds one part of
  /// a dataset (data-parallel rendering: the parts' images composite front to back into the
  /// whole image); faces may lie at infinity. Volume, iso-surfaces and meshes are all limited to
  /// the box; ambient-occlusion rays are not (they see the data the renderer holds). The default
  /// box (box3d()) restricts nothing; an empty box that is not the default one shows nothing.
  void setDomain(const box3d& world);
  const box3d& domain() const;

  /// Smooth shading's gradient fields of model field `field` as built so far (in the bricks that
  /// the scenes and domain have let samples read), once a scene needed them (null before). A
  /// renderer made again over the same model can adopt them (before its scene is set) instead of
  /// building those bricks' again.
  const GradientFields* gradients(int field) const;
  void adoptGradients(int field, GradientFields gradients);

  /// The nearest (clipped) mesh, particle or iso-surface hit along a world ray; false when there
  /// is none.
  bool pick(const vec3d& origin, const vec3d& direction, SurfaceHit& hit) const;
  /// Regions that may be visible under the current transfer functions.
  size_t visibleRegions() const;
  /// What a first view frames (VisibleExtent), in lattice units.
  VisibleExtent visibleExtent() const;
  /// World box of the regions that may show the volume (when it is on) or hold an iso-surface
  /// (empty when there are none), narrowed to the clearly visible cells: what a first view frames.
  box3d visibleBounds() const;
  /// Regions that may hold an iso-surface.
  size_t isoRegions() const;
  size_t meshCount() const;
  /// The traversal in use for the volume.
  TraversalKind traversalInUse() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

} // namespace exa
