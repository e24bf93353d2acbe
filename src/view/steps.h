// The datasets a viewer shows: one, or the steps of a time series given at start. The current
// step is what /api/info, the histogram and new requests use; changing it loads the step (or takes
// it from the prefetch, which the series renderer keeps one step ahead) and rebuilds only values
// where the hierarchy is unchanged.
#pragma once

#include "exabricks/amr/model.h"
#include "exabricks/io/load.h"
#include "exabricks/workflows/series.h"

#include <nlohmann/json.hpp>

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace exa::view {

/// One dataset as the server uses it.
struct StepView {
  int index = 0;
  std::shared_ptr<const Model> model;
  DatasetInfo dataset;
  std::string input; ///< the path scene files record (absolute), or empty for the default dataset
};

/// What is known of a step: its name, and its simulation time and cycle once it was loaded.
struct StepFacts {
  std::string path, name;
  bool loaded = false;
  SimulationState simulation;
  std::string error; ///< why the step could not be read (empty: readable, or not tried)
};

class ViewSteps {
public:
  /// Marks a step that could not be read: the page shows it as such and playing skips it.
  void markUnreadable(int index, const std::string& why);
  /// A single dataset (no series renderer), or a series whose renderer has its current step
  /// loaded; `paths` are the steps' absolute paths; `load`: how a single dataset was read.
  ViewSteps(StepView first, std::shared_ptr<SeriesRenderer> series, std::vector<std::string> paths,
            LoadOptions load = {});

  int size() const { return int(facts_.size()); }
  bool isSeries() const { return series_ != nullptr; }
  StepView current() const;
  /// The paths of the steps, in order.
  std::vector<std::string> paths() const;
  /// Makes step `index` current and starts loading the one after it (the first after the last,
  /// as the page's play loops). Throws exa::Error for an index outside the steps.
  StepView select(int index);
  /// The steps (name, time, cycle where known) and the current step.
  nlohmann::json describe() const;
  /// A field's value range over every step (computed once per field).
  range1f rangeOf(const std::string& field);
  /// How the steps are read (the series renderer's options for a series).
  LoadOptions loadOptions() const;
  /// Reads the current step again with NaN and infinite values refused or made holes, and every
  /// later step the same way; `report` gets the holes' counts. Throws exa::Error (and keeps the
  /// current step as it was) when the step cannot be read so.
  StepView setNonFinite(NonFinite policy, LoadReport* report = nullptr);

  /// The current step's data, read again in full (its coarse levels were shown first).
  void refine(std::shared_ptr<const Model> model, const DatasetInfo& dataset);

private:
  void record(const StepView& step);

  mutable std::mutex mutex_;
  mutable std::mutex loadMutex_; ///< one load at a time (the series renderer is not shared)
  StepView current_;
  std::shared_ptr<SeriesRenderer> series_;
  LoadOptions load_; ///< a single dataset's
  std::vector<StepFacts> facts_;
  std::map<std::string, range1f> ranges_;
};

nlohmann::json simulationJson(const SimulationState& s);

} // namespace exa::view
