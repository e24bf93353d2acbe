// Time series in the library: the steps of a series, value ranges over all of them, and a renderer
// that loads the steps a list of frames needs (the next one on a background thread while the
// current one renders, at most two resident), rebuilds only the values of a step whose hierarchy
// equals the step before it, and renders each frame with the scene applied per step.
#pragma once

#include "exabricks/amr/model.h"
#include "exabricks/core/image.h"
#include "exabricks/io/load.h"
#include "exabricks/render/renderer.h"
#include "exabricks/workflows/frame_plan.h"

#include <functional>
#include <future>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace exa {

/// The steps the inputs name, in the order given: each input a file or dataset, a glob pattern or
/// a folder expanded by expandSeries (in numeric order); explicit files are never re-sorted, and a
/// dataset named twice plays once, where it first appears. Throws exa::Error naming an input
/// that matches nothing.
std::vector<std::string> seriesSteps(const std::vector<std::string>& inputs);

/// The range of a field over every step: from metadata where the format records ranges, else
/// reading only that field. Throws exa::Error naming a step that lacks the field or cannot be
/// read, unless `skipUnreadable`: then such steps are left out and listed.
struct SeriesRange {
  range1f range;
  int fromMetadata = 0;             ///< steps whose range came from metadata
  std::vector<int> unreadable;      ///< with skipUnreadable: the steps left out
  std::vector<std::string> reasons; ///< and why, one message each
};
SeriesRange seriesRange(const std::vector<std::string>& steps, LoadOptions options, const std::string& field,
                        bool skipUnreadable = false);

/// One loaded step: the model, its dataset values and the structure its bricks came from.
struct SeriesStep {
  int index = -1;
  std::shared_ptr<const Model> model;
  DatasetInfo info;
  std::shared_ptr<const ModelStructure> structure; ///< kept for reuse by the next step
  double seconds = 0;                              ///< reading and building
  bool reused = false;                             ///< built over the previous step's structure
  std::shared_ptr<const ParticleSet> particles;    ///< where the series draws them (null: none)
};

/// Loads a step; with `reuse` the previous step's structure serves when the cells are the same
/// (only the values are rebuilt), and the structure is kept for the next step.
/// With `particles`, the step's particles of that species ("" every one) are read too (none
/// where the step holds none).
SeriesStep loadSeriesStep(const std::string& path, const LoadOptions& options, const SeriesStep* previous, bool reuse,
                          const std::optional<std::string>& particles = std::nullopt);

struct SeriesOptions {
  LoadOptions load;           ///< fields to read (empty: all) and build options
  bool prefetch = true;       ///< load the next step a frame list needs beside the render
  bool reuse = true;          ///< rebuild only values when the hierarchy is unchanged
  RendererOptions renderer;   ///< how the march computes
  std::string device = "cpu"; ///< where passes run: cpu, cuda, auto or portable (selectDevice)
  /// Set: each step's particles of this species ("" every one) are read with it and drawn where
  /// the scene shows them.
  std::optional<std::string> particles;
};

struct SeriesStats {
  int loaded = 0, reused = 0; ///< steps loaded, and of those built over the previous structure
  double loadSeconds = 0;     ///< reading and building, summed over the steps
  double waitSeconds = 0;     ///< waiting for a step after the first
  double renderSeconds = 0;
};

/// What renderFrames hands each frame: the frame's number, the step it shows, its scene and
/// camera, and the rendered image (which the receiver may draw on).
using FrameSink =
    std::function<void(int frame, const SeriesStep& step, const Scene& scene, const Frame& camera, Image& image)>;

class SeriesRenderer {
public:
  SeriesRenderer(std::vector<std::string> steps, SeriesOptions options);
  ~SeriesRenderer(); ///< waits for a load in flight
  SeriesRenderer(const SeriesRenderer&) = delete;
  SeriesRenderer& operator=(const SeriesRenderer&) = delete;

  int size() const { return int(steps_.size()); }
  const std::vector<std::string>& steps() const { return steps_; }
  const SeriesOptions& options() const { return options_; }
  const SeriesStats& stats() const { return stats_; }

  /// Makes step k the current one: the prefetched step when it is k, else loaded now.
  const SeriesStep& load(int step);
  /// The current step (index -1 before the first load).
  const SeriesStep& current() const { return current_; }
  /// Starts loading step k on a background thread (nothing when it is current or already coming).
  void prefetch(int step);

  /// Step k rendered with the scene and camera (the step loaded first).
  Image render(int step, const Scene& scene, const Frame& frame);
  /// The given frames of a plan in order, each with the plan's view over `scene` and `frame`, handed
  /// to `sink`; the next step the list needs loads while the current one renders. A failure waits
  /// for the load in flight before it propagates.
  void renderFrames(const FramePlan& plan, const Scene& scene, const Frame& frame, const std::vector<int>& frames,
                    const FrameSink& sink);

private:
  void finishPrefetch() noexcept;

  std::vector<std::string> steps_;
  SeriesOptions options_;
  SeriesStats stats_;
  SeriesStep current_;
  std::unique_ptr<Renderer> renderer_; ///< over the current step
  std::future<SeriesStep> next_;
  int nextStep_ = -1;
};

} // namespace exa
