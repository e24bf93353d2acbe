#include "exabricks/workflows/series.h"

#include "exabricks/io/particles.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"
#include "exabricks/io/series.h"
#include "exabricks/render/denoise.h"

#include <unordered_set>

namespace exa {

std::vector<std::string> seriesSteps(const std::vector<std::string>& inputs) {
  std::vector<std::string> out;
  std::unordered_set<std::string> seen;
  for (const std::string& input : inputs)
    for (std::string& path : expandSeries({input}))
      if (seen.insert(path).second) out.push_back(std::move(path));
  return out;
}

namespace {

/// The range of one step's field (counted in `fromMetadata` where the format records it).
range1f stepRange(const std::string& path, const LoadOptions& options, const std::string& field, int& fromMetadata) {
  if (const std::optional<range1f> r = fieldRangeFromMetadata(path, field)) {
    ++fromMetadata;
    return *r;
  }
  range1f range;
  if (detectInput(path) == InputKind::Model) {
    const Model m = loadModel(path, options);
    for (float v : m.fieldValues.at(size_t(m.requireField(field))))
      range.extend(v);
    return range;
  }
  const CellSet cells = loadCells(path, options);
  const int f = cells.fieldIndex(field);
  if (f < 0) fail(path, ": no field '", field, "' (the series' first step has it)");
  for (float v : cells.fields[size_t(f)].values)
    range.extend(v);
  return range;
}

} // namespace

SeriesRange seriesRange(const std::vector<std::string>& steps, LoadOptions options, const std::string& field,
                        bool skipUnreadable) {
  SeriesRange out;
  options.fields = {field};
  for (size_t i = 0; i < steps.size(); ++i) {
    try {
      out.range.extend(stepRange(steps[i], options, field, out.fromMetadata));
    } catch (const Error& e) {
      if (!skipUnreadable) throw;
      out.unreadable.push_back(int(i));
      out.reasons.push_back(e.what());
    }
  }
  return out;
}

SeriesStep loadSeriesStep(const std::string& path, const LoadOptions& options, const SeriesStep* previous, bool reuse,
                          const std::optional<std::string>& particles) {
  Timer timer;
  SeriesStep step;
  if (detectInput(path) == InputKind::Model) {
    step.model = std::make_shared<const Model>(loadModel(path, options));
  } else {
    CellSet cells = loadCells(path, options);
    if (reuse && previous && previous->structure && previous->structure->matches(cells, options.build)) {
      step.model =
          std::make_shared<const Model>(rebuildValues(*previous->model, *previous->structure, std::move(cells)));
      step.structure = previous->structure;
      step.reused = true;
    } else {
      auto structure = std::make_shared<ModelStructure>();
      step.model = std::make_shared<const Model>(buildModel(std::move(cells), options.build, *structure));
      if (reuse) step.structure = std::move(structure);
    }
  }
  step.info = DatasetInfo::of(*step.model);
  if (particles) step.particles = readParticlesIfAny(path, *particles);
  step.seconds = timer.seconds();
  return step;
}

SeriesRenderer::SeriesRenderer(std::vector<std::string> steps, SeriesOptions options)
    : steps_(std::move(steps)), options_(std::move(options)) {
  if (steps_.empty()) fail("a series needs at least one step");
}

SeriesRenderer::~SeriesRenderer() { finishPrefetch(); }

void SeriesRenderer::finishPrefetch() noexcept {
  try {
    if (next_.valid()) next_.get();
  } catch (...) {
  }
  nextStep_ = -1;
}

const SeriesStep& SeriesRenderer::load(int step) {
  if (step < 0 || step >= size()) fail("step ", step, " is outside the series' steps 0..", size() - 1);
  if (step == current_.index) return current_;
  const bool first = !current_.model;
  Timer wait;
  if (nextStep_ == step) {
    SeriesStep loaded = next_.get();
    nextStep_ = -1;
    renderer_.reset();
    current_ = std::move(loaded);
  } else {
    if (next_.valid()) next_.get();
    nextStep_ = -1;
    renderer_.reset();
    SeriesStep loaded = loadSeriesStep(steps_[size_t(step)], options_.load, first ? nullptr : &current_, options_.reuse,
                                       options_.particles);
    current_ = std::move(loaded);
  }
  current_.index = step;
  if (!first) stats_.waitSeconds += wait.seconds();
  stats_.loadSeconds += current_.seconds;
  stats_.reused += current_.reused ? 1 : 0;
  ++stats_.loaded;
  return current_;
}

void SeriesRenderer::prefetch(int step) {
  if (step < 0 || step >= size() || step == nextStep_ || step == current_.index) return;
  if (next_.valid()) next_.get();
  nextStep_ = step;
  const SeriesStep* previous = current_.model ? &current_ : nullptr;
  next_ = std::async(std::launch::async, [this, step, previous] {
    return loadSeriesStep(steps_[size_t(step)], options_.load, previous, options_.reuse, options_.particles);
  });
}

Image SeriesRenderer::render(int step, const Scene& scene, const Frame& frame) {
  load(step);
  const bool fresh = !renderer_;
  if (fresh) {
    renderer_ = std::make_unique<Renderer>(*current_.model, current_.info);
    renderer_->setOptions(options_.renderer);
    renderer_->setParticles(current_.particles);
  }
  Scene placed = scene;
  resolveParticleRadius(placed, frame);
  renderer_->setScene(placed);
  if (fresh) selectDevice(*renderer_, options_.device);
  Timer t;
  Image image = renderPicture(*renderer_, frame);
  stats_.renderSeconds += t.seconds();
  return image;
}

void SeriesRenderer::renderFrames(const FramePlan& plan, const Scene& scene, const Frame& frame,
                                  const std::vector<int>& frames, const FrameSink& sink) {
  try {
    for (size_t n = 0; n < frames.size(); ++n) {
      const int i = frames[n];
      const int step = plan.stepOf(i);
      load(step);
      // The next step this list needs, loaded beside the render.
      if (options_.prefetch)
        for (size_t m = n + 1; m < frames.size(); ++m)
          if (plan.stepOf(frames[m]) != step) {
            prefetch(plan.stepOf(frames[m]));
            break;
          }
      Scene s = scene;
      Frame f = frame;
      plan.view(i, s, f);
      Image image = render(step, s, f);
      sink(i, current_, s, f, image);
    }
    if (next_.valid()) next_.get();
  } catch (...) {
    finishPrefetch();
    throw;
  }
}

} // namespace exa
