// Steps larger than memory: a memory budget for the whole process, the k-d partition of the step
// whose largest part (with its halo) fits in it, parts read one at a time and kept while they fit
// (least recently used first out), and frames rendered part by part front to back, composited as
// data-parallel rendering composites the processes' parts, so that a frame equals the in-core one.
#pragma once

#include "exabricks/amr/model.h"
#include "exabricks/amr/partition.h"
#include "exabricks/core/error.h"
#include "exabricks/io/load.h"
#include "exabricks/render/defaults.h"
#include "exabricks/render/renderer.h"

#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace exa {

/// A budget that cannot hold the process and the smallest part it can be split into.
class BudgetTooSmall : public Error {
public:
  BudgetTooSmall(std::string what, uint64_t smallestBudget, uint64_t fixed, uint64_t partBytes, uint64_t perCell,
                 const std::string& why = "");

  std::string situation;      ///< the refusal without its smallest budget
  uint64_t smallest;          ///< the smallest budget that works, bytes
  uint64_t fixedBytes;        ///< the process without data (MemoryPlan::fixedBytes)
  uint64_t smallestPartBytes; ///< what the largest part of the finest partition needs beside it
  uint64_t bytesPerCell;      ///< MemoryPlan::bytesPerCell
};

/// This process's resident memory now (VmRSS), its peak so far (VmHWM) and the memory the system
/// can still give (MemAvailable), in bytes; 0 where unknown.
uint64_t residentBytesNow();
uint64_t peakResidentBytes();
uint64_t availableMemoryBytes();

/// What a resident part costs per cell it holds (halo included) when `fields` fields are loaded:
/// the values, smooth shading's gradients, bricks, regions, the renderer's structures and the
/// build's working memory (cell records and slot indices, none for inputs built from their
/// boxes), as measured on AMReX and generated inputs (docs/performance.md).
uint64_t bytesPerResidentCell(size_t fields, bool fromBoxes);

/// Bytes rounded up to a whole mebibyte: the unit a refusal names its smallest budget in.
inline uint64_t wholeMebibytes(uint64_t bytes) { return ((bytes + (uint64_t(1) << 20) - 1) >> 20) << 20; }

/// How a step is held under a memory budget.
struct MemoryPlan {
  uint64_t budget = 0;       ///< the whole process's resident memory, bytes
  uint64_t fixedBytes = 0;   ///< the process without data: code, libraries, frame buffers
  uint64_t bytesPerCell = 0; ///< bytesPerResidentCell of the loaded fields
  double cells = 0;          ///< the step's cells (census)
  KdPartition partition = KdPartition::whole();
  int coarsestLevel = 0;
  box3l cellBounds;               ///< the census's exact bounds of the cells (empty: unknown)
  std::vector<double> levelCells; ///< the census's cells per level (empty: unknown)
  std::vector<double> partCells;  ///< per part, the cells it holds with its halo (estimated)

  bool streamed() const { return partition.parts() > 1; }
  /// Whether the step fits in the budget in one piece.
  bool fitsWhole() const;
  /// The estimated resident bytes of part p, and of the largest part.
  uint64_t partBytes(int part) const;
  uint64_t largestPartBytes() const;
};

/// Plans `input` (its census: AMReX and NAME.cells from their headers and records, other inputs
/// by reading their cells) for a process that holds `frameBytes` of images besides its data: in
/// one piece when the step fits in the budget, else the fewest k-d parts (balanced by cells, cut
/// only at multiples of the coarsest cell width) whose largest part with its halo fits beside the
/// process. Throws BudgetTooSmall with the smallest budget that works when none does.
MemoryPlan planMemory(const std::string& input, const LoadOptions& options, uint64_t budget, uint64_t frameBytes);

/// planMemory's figures without its partition (in one piece, whether or not the step fits):
/// the process without data, the bytes per cell and the census's counts.
MemoryPlan sizeMemory(const std::string& input, const LoadOptions& options, uint64_t budget, uint64_t frameBytes);

/// Without a budget given: none (hold the step whole, as before) when the step's estimated
/// resident bytes fit in three quarters of the memory the system has available, or when its
/// cells cannot be counted without reading them; else that budget, with a note on stderr.
std::optional<uint64_t> budgetForLargeStep(const std::string& input, const LoadOptions& options, uint64_t frameBytes);

/// What the whole step is, gathered from its parts.
struct StepSurvey {
  DatasetInfo dataset;
  box3i cellBounds;
  std::vector<int> levels;          ///< levels that hold cells
  uint64_t cells = 0;               ///< every part's owned cells
  std::vector<uint64_t> levelCells; ///< per level (index = level), owned cells
  uint64_t bricks = 0, regions = 0; ///< summed over the parts' models (halos included)
};

class PartCache;

/// A step held in parts, one resident at a time, or as many as the budget holds. A part built
/// once is kept on disk (an unlinked model file in the temporary folder, where it has room) and
/// read from there when it is needed again: an orbit rereads no source file and builds nothing
/// twice.
class StreamedStep {
public:
  /// The step's world, fields and simulation come from `like` (a model of some of its levels,
  /// read with the same options) or, without it, from the first part that holds cells.
  StreamedStep(std::string input, LoadOptions options, MemoryPlan plan, const Model* like = nullptr);
  ~StreamedStep();
  StreamedStep(const StreamedStep&) = delete;
  StreamedStep& operator=(const StreamedStep&) = delete;

  const MemoryPlan& plan() const { return plan_; }
  int parts() const { return plan_.partition.parts(); }
  /// A model holding no cells but the step's world, fields, units and simulation state: what the
  /// front ends ask of a model that is not a part's cells.
  const Model& skeleton() const { return skeleton_; }
  /// The whole step's values, gathered from every part as it is read: the first call reads the
  /// parts not read yet.
  const StepSurvey& survey();
  /// What the census knows of the whole step without reading it: its cells, their levels and
  /// bounds, and its dataset values without value ranges (empty ranges); none where the census
  /// cannot say. Equal to the survey in all of these.
  const std::optional<StepSurvey>& outline() const { return outline_; }
  /// Whether renderers of `scene` need the survey (the value ranges of a layer without its own,
  /// or no outline to build them from): renderer() then surveys the step first.
  bool needsSurvey(const Scene& scene) const;
  /// Part p's lattice box and its world box (the renderer's domain).
  const box3l& partBox(int part) const { return plan_.partition.box(part); }
  box3d partWorldBox(int part) const { return skeleton_.world.toWorld(partBox(part)); }
  /// Part p's model, read and built unless resident (null when the part holds no cells). Makes
  /// room first by dropping the least recently used parts. Valid until the next call.
  const Model* part(int part);
  /// The particles every part's renderer draws where its scene shows them (each part's renderer
  /// holds all of them; its domain keeps what it draws to its part).
  void setParticles(std::shared_ptr<const ParticleSet> particles) { particles_ = std::move(particles); }
  /// Part p's renderer over the step's dataset values, set to `scene` and `options`.
  Renderer* renderer(int part, const Scene& scene, const RendererOptions& options);
  /// Calls visit(model, owned box) for every part that holds cells, resident parts first.
  void forEachPart(const std::function<void(const Model&, const box3l&)>& visit);
  /// The defaults' view of the step: every part's owned cells counted.
  PartialData partialData();
  /// Parts front to back as `camera` sees them.
  std::vector<int> order(const Camera& camera) const;
  /// Union of what each part's renderer may show within its part (a first view frames it).
  box3d visibleBounds(const Scene& scene, const RendererOptions& options);
  /// Reconstructs `field` at world points, each in the part that holds it (every part read at
  /// most once): `found[i]` false where no cell has weight, or the point is not finite.
  void sample(int field, const std::vector<vec3d>& points, std::vector<double>& values, std::vector<vec3d>& gradients,
              std::vector<bool>& found);
  /// What `info --json` prints of the step: its cells per level, bounds, fields and ranges, and
  /// the plan ("memory": budget, parts, the largest part, parts read, peak resident memory).
  std::string infoJson(const std::string& name, double seconds);

  int residentParts() const { return int(resident_.size()); }
  /// Estimated bytes of the resident parts.
  uint64_t residentBytes() const;
  /// Parts read so far (a part read again after it was dropped counts again).
  uint64_t partsRead() const { return reads_; }
  /// Of those, the parts read back from the disk cache instead of built from the step.
  uint64_t partsFromDisk() const;
  /// Smooth shading's gradient fields of a part and field read back from the disk cache.
  uint64_t gradientsFromDisk() const;

private:
  struct Resident;
  struct Snapshot;
  Resident& bring(int part);
  /// Every part, the resident ones first (most recently used first): an order that reads least.
  std::vector<int> residentFirst() const;
  /// Throws when the input's files changed since the step was opened (a step being written).
  void checkUnchanged() const;
  /// Adds part p's model (null: no cells) to the survey, once; the last part completes it.
  void gather(int part, const Model* model);
  /// The survey, once every part is gathered and the skeleton is known.
  void finishSurvey();
  static std::optional<StepSurvey> outlineOf(const MemoryPlan& plan, const LoadOptions& options, const Model& skeleton);
  struct Gathering {
    int finest = kMaxLevel;
    std::vector<uint64_t> levelCells;
    box3i cellBounds;
    uint64_t bricks = 0, regions = 0;
    std::vector<range1f> ranges;
  };
  std::string input_;
  LoadOptions options_;
  MemoryPlan plan_;
  Model skeleton_;
  std::optional<StepSurvey> survey_;
  std::optional<StepSurvey> outline_;
  std::vector<bool> gathered_; ///< per part: added to gathering_
  Gathering gathering_;
  std::list<Resident> resident_; ///< most recently used first
  uint64_t reads_ = 0;
  std::unique_ptr<Snapshot> snapshot_;
  std::unique_ptr<PartCache> cache_;
  std::shared_ptr<const ParticleSet> particles_;
};

/// Renders `frame` (every pass) into `buffer` from the step's parts, front to back, each pass
/// composited over the parts as data-parallel rendering composites them. False when cancelled.
/// The passes are drawn in rounds, each reading the parts once; with `afterRound`, the first
/// round is one pass (a picture of every level after one read of each part) and `afterRound`
/// is called with the passes in `buffer` after every round but the last.
bool renderStreamed(StreamedStep& step, const Scene& scene, const RendererOptions& options, const Frame& frame,
                    FrameBuffer& buffer, const PassControl& control = {},
                    const std::function<void(const FrameBuffer&, int passes)>& afterRound = {});

/// Bytes of the images a frame of this size and samples per pixel holds while it is composited
/// from parts (the output buffer, one part's pass and the per-pass composites).
uint64_t streamedFrameBytes(int width, int height, int samplesPerPixel);

} // namespace exa
