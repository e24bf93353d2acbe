#include "steps.h"

#include "exabricks/core/error.h"

#include <filesystem>

namespace exa::view {

using json = nlohmann::json;

namespace {

/// The name the page shows: the file or folder name.
std::string stepName(const std::string& path) {
  if (path.empty()) return "default dataset";
  const std::filesystem::path p = std::filesystem::path(path).lexically_normal();
  const std::string name = (p.has_filename() ? p.filename() : p.parent_path().filename()).string();
  return name.empty() ? path : name;
}

} // namespace

json simulationJson(const SimulationState& s) {
  return {{"time", s.hasTime() ? json(s.time) : json(nullptr)},
          {"cycle", s.hasCycle() ? json(s.cycle) : json(nullptr)}};
}

ViewSteps::ViewSteps(StepView first, std::shared_ptr<SeriesRenderer> series, std::vector<std::string> paths,
                     LoadOptions load)
    : current_(std::move(first)), series_(std::move(series)), load_(std::move(load)) {
  if (paths.empty()) paths.push_back(current_.input);
  for (const std::string& p : paths)
    facts_.push_back(StepFacts{p, stepName(p), false, {}, {}});
  record(current_);
  if (series_ && series_->options().prefetch) series_->prefetch((current_.index + 1) % size());
}

void ViewSteps::markUnreadable(int index, const std::string& why) {
  std::lock_guard<std::mutex> lock(mutex_);
  facts_.at(size_t(index)).error = why;
}

void ViewSteps::record(const StepView& step) {
  StepFacts& f = facts_.at(size_t(step.index));
  f.loaded = true;
  f.error.clear();
  f.simulation = step.model->simulation;
}

void ViewSteps::refine(std::shared_ptr<const Model> model, const DatasetInfo& dataset) {
  std::lock_guard<std::mutex> lock(mutex_);
  current_.model = std::move(model);
  current_.dataset = dataset;
}

StepView ViewSteps::current() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return current_;
}

std::vector<std::string> ViewSteps::paths() const {
  std::vector<std::string> out;
  for (const StepFacts& f : facts_)
    out.push_back(f.path);
  return out;
}

StepView ViewSteps::select(int index) {
  if (index < 0 || index >= size())
    fail("step ", index, " is outside the series' steps 0..", size() - 1, " (", size(), " given at start)");
  std::lock_guard<std::mutex> load(loadMutex_);
  if (!series_ || index == current().index) return current();
  const SeriesStep* loaded = nullptr;
  try {
    loaded = &series_->load(index);
  } catch (const Error& e) {
    markUnreadable(index, e.what());
    throw;
  }
  const SeriesStep& s = *loaded;
  StepView step{index, s.model, s.info, facts_.at(size_t(index)).path};
  if (series_->options().prefetch) series_->prefetch((index + 1) % size());
  std::lock_guard<std::mutex> lock(mutex_);
  current_ = step;
  record(step);
  return step;
}

json ViewSteps::describe() const {
  std::lock_guard<std::mutex> load(loadMutex_); // the series' statistics change while a step loads
  std::lock_guard<std::mutex> lock(mutex_);
  json steps = json::array();
  for (const StepFacts& f : facts_) {
    json j = simulationJson(f.simulation);
    j["name"] = f.name;
    j["loaded"] = f.loaded;
    if (!f.error.empty()) j["error"] = f.error;
    steps.push_back(j);
  }
  json out{{"steps", steps}, {"current", current_.index}, {"series", series_ != nullptr}};
  if (series_) {
    const SeriesStats& s = series_->stats();
    out["stats"] = {{"loaded", s.loaded}, {"reused", s.reused}, {"load_seconds", s.loadSeconds}};
  }
  return out;
}

range1f ViewSteps::rangeOf(const std::string& field) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (const auto it = ranges_.find(field); it != ranges_.end()) return it->second;
    if (!series_) return current_.dataset.valueRanges.at(size_t(current_.model->requireField(field)));
  }
  LoadOptions options = series_->options().load;
  const range1f r = seriesRange(paths(), options, field, true).range; // unreadable steps left out
  std::lock_guard<std::mutex> lock(mutex_);
  ranges_[field] = r;
  return r;
}

LoadOptions ViewSteps::loadOptions() const {
  std::lock_guard<std::mutex> load(loadMutex_);
  return series_ ? series_->options().load : load_;
}

StepView ViewSteps::setNonFinite(NonFinite policy, LoadReport* report) {
  std::lock_guard<std::mutex> load(loadMutex_);
  LoadOptions lo = series_ ? series_->options().load : load_;
  lo.nonFinite = policy;
  auto counts = std::make_shared<LoadReport>();
  lo.report = counts;
  StepView step = current();
  std::shared_ptr<SeriesRenderer> fresh;
  if (series_) {
    SeriesOptions so = series_->options();
    so.load = lo;
    fresh = std::make_shared<SeriesRenderer>(paths(), so);
    const SeriesStep& s = fresh->load(step.index);
    step = StepView{step.index, s.model, s.info, step.input};
  } else {
    auto model = std::make_shared<const Model>(loadModel(step.input, lo));
    step = StepView{step.index, model, DatasetInfo::of(*model), step.input};
  }
  lo.report.reset();
  if (report) *report = *counts;
  if (fresh) {
    series_ = fresh; // the one it replaces waits for its prefetch
    if (series_->options().prefetch) series_->prefetch((step.index + 1) % size());
  }
  load_ = lo;
  std::lock_guard<std::mutex> lock(mutex_);
  current_ = step;
  ranges_.clear();
  record(step);
  return step;
}

} // namespace exa::view
