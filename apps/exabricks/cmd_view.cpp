// exabricks view: the interactive viewer, served to a browser (see docs/viewer.md).
#include "commands.h"
#include "common.h"
#include "scene_options.h"

#include "exabricks/amr/scenes.h"
#include "exabricks/core/log.h"
#include "exabricks/core/text.h"
#include "exabricks/render/defaults.h"
#include "exabricks/render/renderer.h"
#include "exabricks/workflows/coarse_first.h"
#include "exabricks/workflows/series.h"
#include "exabricks/workflows/streamed.h"

#include <filesystem>

#ifdef EXABRICKS_HAVE_VIEWER
#include "view/server.h"

#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <future>
#include <iostream>
#include <pthread.h>
#include <thread>
#include <unistd.h>
#endif

namespace exa::cli {
namespace {

#ifdef EXABRICKS_HAVE_VIEWER
/// This machine's name, for the SSH hint ("localhost" where it has none).
std::string hostName() {
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) != 0 || name[0] == '\0') return "localhost";
  return name;
}
#endif

struct ViewCmdOptions {
  RenderOptions scene;
  std::vector<std::string> inputs; ///< one dataset, or the steps of a series
  std::string host = "127.0.0.1";
  int port = 8765;
  std::string token;
  std::string device = "auto";
  double coarseFirst = 2e6; ///< inputs of more cells show their coarse levels first (0: never)
};

/// Passes the viewer refines to when neither the options nor a scene file say.
constexpr int kDefaultViewerPasses = 8;

#ifdef EXABRICKS_HAVE_VIEWER
/// The datasets the inputs name: one file as itself (as a single input always was), else the
/// steps of a series as `movie` takes them (files, folders, glob patterns), as absolute paths.
std::vector<std::string> viewSteps(const std::vector<std::string>& inputs) {
  namespace fs = std::filesystem;
  if (inputs.empty()) return {};
  const bool pattern = inputs[0].find_first_of("*?[") != std::string::npos;
  if (inputs.size() == 1 && !pattern && !fs::is_directory(inputs[0])) return inputs;
  std::vector<std::string> steps = seriesSteps(inputs);
  for (std::string& s : steps)
    s = fs::absolute(s).lexically_normal().string();
  return steps;
}

/// The dataset the viewer opens: step 0 of a series (loaded through the series renderer, which
/// keeps its structure for the next steps), or the one input.
struct FirstStep {
  std::shared_ptr<SeriesRenderer> series;
  std::shared_ptr<const Model> model;
  DatasetInfo dataset;
  int index = 0;                                       ///< the step shown first
  std::vector<std::pair<int, std::string>> unreadable; ///< steps before it that could not be read
  CoarseFirst coarse;                                  ///< level > 0: `model` holds the coarse levels
  int64_t merged = 1; ///< above 1: `model` holds the coarsest level's cells merged by this per axis
  int mergedLevel = 0;
  bool leavesMerged = false;             ///< `model` holds every cell merged into cubes 2^mergedLevel wide
  std::optional<DefaultChoices> choices; ///< the first transfer function, chosen from `model` already
};

/// What a view shows of a step with the coarse levels `coarse` (level > 0), for the page.
std::string coarseShown(const CoarseFirst& coarse) {
  return strCat("coarse levels: cells ", 1 << coarse.level, " wide and wider (", std::llround(coarse.coarseCells),
                " of ", std::llround(coarse.cells), " cells in boxes)");
}

/// The same for the coarsest level merged (FirstStep::merged).
std::string mergedShown(const FirstStep& f) {
  const double cells = f.model->cellCount();
  return strCat("the coarsest level merged: cells ", int64_t(1) << f.mergedLevel, " wide by ", f.merged, " per axis (",
                std::llround(cells), " cells for ", std::llround(f.coarse.cells), " in boxes)");
}

/// The same for every cell merged (FirstStep::leavesMerged).
std::string leavesShown(const FirstStep& f) {
  return strCat("every cell merged into cubes ", int64_t(1) << f.mergedLevel, " finest cells wide (",
                std::llround(f.model->cellCount()), " cubes for ", std::llround(f.coarse.cells), " cells)");
}

/// The first picture of a large plotfile: its coarsest level merged, and the transfer function
/// chosen from it where the options leave that to the data.
struct MergedFirst {
  std::optional<CoarseLevels> levels;
  std::optional<DefaultChoices> choices;
};

/// The coarsest level of a single step merged to at most `firstCells` cells (loadMergedFirst)
/// and the first transfer function for `scene`, on a thread of its own: they depend on no memory
/// plan, so they are made beside them.
std::future<MergedFirst> mergedBeside(const std::vector<std::string>& steps, const std::string& input,
                                      const LoadOptions& lo, double firstCells, const RenderOptions& o,
                                      const CLI::App& cmd, const Scene& scene) {
  if (steps.size() > 1 || !(firstCells > 0)) return {};
  // Under a budget given, an input whose cells are merged for the first picture is read once, so.
  if (!o.in.memoryBudget.empty() && mergesLeaves(input)) return {};
  return std::async(std::launch::async, [input, lo, firstCells, &o, &cmd, scene] {
    MergedFirst m;
    m.levels = loadMergedFirst(input, lo, coarseFirstLevel(input, firstCells), firstCells);
    if (m.levels && choosesTransferFunction(o)) {
      try {
        const int field = m.levels->model->requireField(scene.layers.at(0).field);
        m.choices = firstTransferFunction(cmd, scene, field, *m.levels->model, m.levels->dataset);
      } catch (const Error&) { // chosen again where it is applied, which says what is wrong
      }
    }
    return m;
  });
}

/// The dataset, or the first readable step of a series (a step that cannot be read is said on
/// stderr and skipped; when none can be read, the first one's error). A dataset of more than
/// `coarseFirst` cells comes as its coarse levels (those cells at most, or the coarsest level
/// alone), and one whose coarsest level alone holds more than `firstCells` as that level merged
/// (`merged`, where it is being read already); under a budget (`mergedCells` above 0), an input
/// without coarse levels as every cell merged into about that many cubes.
FirstStep loadFirst(const std::vector<std::string>& steps, const std::string& input, const LoadOptions& lo,
                    double coarseFirst, double firstCells, std::future<MergedFirst> read, double mergedCells) {
  FirstStep f;
  if (steps.size() <= 1 && coarseFirst > 0) f.coarse = coarseFirstLevel(input, coarseFirst);
  if (mergedCells > 0) {
    // Under a budget, an input without coarse levels to read alone: every cell merged first.
    if (read.valid()) read.wait();
    if (std::optional<CoarseLevels> merged = loadMergedLeavesFirst(input, lo, mergedCells)) {
      f.coarse = CoarseFirst();
      f.coarse.cells = merged->cells;
      f.model = std::move(merged->model);
      f.dataset = std::move(merged->dataset);
      f.mergedLevel = merged->mergedLevel;
      f.leavesMerged = true;
      logNote(strCat("showing ", leavesShown(f), "; every level follows in parts"));
      return f;
    }
    fail(input, ": no cells to merge for a first picture under the memory budget");
  }
  // A coarsest level alone larger than coarseFirst: first a picture of it merged, then the rest.
  const bool large = f.coarse.level > 0 ? f.coarse.coarseCells > firstCells : f.coarse.cells > firstCells;
  if (large && firstCells > 0) {
    const bool early = read.valid();
    MergedFirst m = early ? read.get() : MergedFirst();
    if (!early) m.levels = loadMergedFirst(input, lo, f.coarse, firstCells);
    if (std::optional<CoarseLevels>& merged = m.levels) {
      f.model = std::move(merged->model);
      f.dataset = std::move(merged->dataset);
      f.merged = merged->mergedFactor;
      f.mergedLevel = merged->mergedLevel;
      f.choices = std::move(m.choices);
      logNote(strCat("showing ", mergedShown(f), "; every level follows"));
      return f;
    }
  }
  if (f.coarse.level > 0) {
    // The coarse levels first: a plotfile stores every level's values.
    CoarseLevels levels = loadCoarseLevels(input, lo, f.coarse);
    f.model = std::move(levels.model);
    f.dataset = std::move(levels.dataset);
    logNote(strCat("showing the coarse levels first (cells ", 1 << f.coarse.level, " finest cells wide and wider, ",
                   std::llround(f.coarse.coarseCells), " of ", std::llround(f.coarse.cells),
                   " cells in boxes); every level follows"));
    return f;
  }
  if (steps.size() > 1) {
    SeriesOptions so;
    so.load = lo;
    f.series = std::make_shared<SeriesRenderer>(steps, so);
    for (f.index = 0; f.index < int(steps.size()); ++f.index) {
      try {
        const SeriesStep& first = f.series->load(f.index);
        f.model = first.model;
        f.dataset = first.info;
        break;
      } catch (const Error& e) {
        if (f.index + 1 == int(steps.size()))
          fail("no step of the series can be read; the first: ",
               f.unreadable.empty() ? e.what() : f.unreadable[0].second);
        logWarning(strCat("step ", f.index, " cannot be read, skipped: ", e.what()));
        f.unreadable.emplace_back(f.index, e.what());
      }
    }
  } else {
    f.model = std::make_shared<const Model>(loadModel(input, lo));
    f.dataset = DatasetInfo::of(*f.model);
  }
  return f;
}

/// Images a viewer holds besides its data under a memory budget: a frame of the size the view
/// starts with (--size) composited from parts, and the coarse view's refining buffer and draft.
uint64_t viewerFrameBytes(const Frame& frame) {
  const uint64_t pixels = uint64_t(frame.width) * uint64_t(frame.height);
  return streamedFrameBytes(frame.width, frame.height, frame.samplesPerPixel) + pixels * 2 * (sizeof(vec4f) + 4);
}

/// Under --memory-budget, or for a step too large for the memory available: budget 0 when the
/// step fits (it is viewed as without a budget); else the budget and its parts' plan, with
/// `coarseFirst` set to the cells of the coarse levels the view holds resident
/// (coarseBesideParts) while it draws every level in those parts beside them. Inputs whose coarse levels can be read
/// alone (AMReX, Chombo, Enzo and VTK overlapping AMR files) hold those; inputs of leaf cells only that can be merged
/// (model files, FLASH, NAME.cells, patch-based files of one level) hold every cell merged into cubes instead; others
/// are refused. A budget too small
/// for both is refused naming the smallest that holds both.
struct ViewBudget {
  uint64_t budget = 0;    ///< 0: the step is held whole
  MemoryPlan parts;       ///< the parts, planned beside the coarse levels
  double mergedCells = 0; ///< above 0: no coarse levels; every cell merged into about this many cubes
};
ViewBudget viewBudget(const InputOptions& in, const std::string& input, const LoadOptions& lo, uint64_t frameBytes,
                      double& coarseFirst) {
  const std::optional<uint64_t> budget = memoryBudgetFor(in, input, lo, frameBytes, false);
  if (!budget) return {};
  std::optional<CoarseBeside> beside;
  try {
    beside = coarseBesideParts(input, lo, *budget, frameBytes, coarseFirst, "the viewer");
  } catch (const BudgetTooSmall& refused) {
    failUsage(refused.what());
  }
  if (!beside) return {};
  if (beside->coarse.level == 0 && !(beside->mergedCells > 0))
    failUsage(input, " does not fit in a memory budget of ", formatBytes(*budget),
              ": the viewer shows such a step from its coarse levels (AMReX, Chombo, Enzo and VTK overlapping AMR "
              "files) or every cell merged (model files, FLASH, NAME.cells, files of one level) while it draws every "
              "level in parts; "
              "`render` and `movie` draw it with --memory-budget");
  coarseFirst = beside->coarse.coarseCells;
  return {*budget, std::move(beside->parts), beside->mergedCells};
}

/// Ctrl-C and SIGTERM are taken by one thread (sigwait) that stops the server cleanly; every
/// thread started after this inherits the blocked mask.
sigset_t blockStopSignals() {
  sigset_t stopSignals;
  sigemptyset(&stopSignals);
  sigaddset(&stopSignals, SIGINT);
  sigaddset(&stopSignals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stopSignals, nullptr);
  return stopSignals;
}

/// A series maps one colour range over all its steps (the first step's widened to it) unless
/// --range says LOW,HIGH (`rangeGiven`) or per-step; steps found unreadable on the way are added
/// to `unreadable`.
void applySeriesRange(const FirstStep& first, const std::vector<std::string>& steps, const LoadOptions& lo,
                      bool rangeGiven, bool perStep, Scene& scene,
                      std::vector<std::pair<int, std::string>>& unreadable) {
  if (!first.series || rangeGiven) return;
  if (perStep) {
    scene.layers[0].tf.valueRange = range1f();
    return;
  }
  const Model& model = *first.model;
  const int field = model.requireField(scene.layers[0].field);
  const SeriesRange r = seriesRange(steps, lo, model.fieldNames[size_t(field)], true);
  const range1f overSteps = r.range;
  for (size_t k = 0; k < r.unreadable.size(); ++k)
    if (std::none_of(first.unreadable.begin(), first.unreadable.end(),
                     [&](const auto& u) { return u.first == r.unreadable[k]; })) {
      logWarning(strCat("step ", r.unreadable[k], " cannot be read, marked on the page: ", r.reasons[k]));
      unreadable.emplace_back(r.unreadable[k], r.reasons[k]);
    }
  TransferFunction& tf = scene.layers[0].tf;
  tf = widenedForSeries(tf, first.dataset.valueRanges.at(size_t(field)), overSteps);
  logNote(strCat("colour range over all ", steps.size(), " steps: [", tf.valueRange.lower, ", ", tf.valueRange.upper,
                 "] (values over [", overSteps.lower, ", ", overSteps.upper,
                 "]); --range per-step or LOW,HIGH to choose"));
}

/// How the view gets from what it shows first to every level: in parts under a memory budget
/// (after the coarse levels, where it shows the coarsest level merged first), or by reading the
/// coarse levels and then the whole step on a thread of its own.
void addRefinement(view::ViewContent& content, const FirstStep& first, const std::string& input, const LoadOptions& lo,
                   const ViewBudget& budgets) {
  const uint64_t budget = budgets.budget;
  const std::string shown = first.leavesMerged ? leavesShown(first)
                            : first.merged > 1 ? mergedShown(first)
                                               : coarseShown(first.coarse);
  const CoarseFirst coarse = first.coarse;
  auto coarseLevels = [input, lo, coarse] {
    CoarseLevels c = loadCoarseLevels(input, lo, coarse);
    return std::make_pair(c.model, c.dataset);
  };
  if (budget) {
    // Every level in parts, planned beside the coarse levels the view holds.
    content.parts = std::make_shared<StreamedStep>(input, lo, budgets.parts, first.model.get());
    content.budget = budget;
    const std::string parts =
        strCat("every level follows in ", content.parts->parts(), " parts within a budget of ", formatBytes(budget));
    content.coarse = {shown, parts};
    if (first.merged > 1 && !first.leavesMerged) content.refine.push_back({coarseLevels, {coarseShown(coarse), parts}});
    logNote(strCat("memory budget ", formatBytes(budget), ": a still view is drawn from every level in ",
                   content.parts->parts(), " parts, its drafts from ",
                   first.leavesMerged ? "every cell merged" : "the coarse levels"));
    return;
  }
  if (first.merged == 1 && first.coarse.level == 0) return;
  content.coarse = {shown, "reading the finer levels"};
  if (first.merged > 1 && coarse.level > 0)
    content.refine.push_back({coarseLevels, {coarseShown(coarse), "reading the finer levels"}});
  content.refine.push_back({[input, lo] {
                              auto model = std::make_shared<const Model>(loadModel(input, lo));
                              return std::make_pair(std::shared_ptr<const Model>(model), DatasetInfo::of(*model));
                            },
                            {}});
}

/// A viewer's server, bound before the dataset is read (a taken port fails at once) and its
/// address printed as soon as the viewer knows it will serve (announce(): a browser opened then
/// waits for the first picture), and the thread that takes Ctrl-C and SIGTERM (`stopSignals`,
/// blocked in every thread): while the dataset is still being read they end the process, then
/// they stop the server cleanly.
class BoundViewer {
public:
  BoundViewer(const view::ServerOptions& options, const sigset_t& stopSignals) : server_(options) {
    server_.bind();
    waiter_ = std::thread([this, stopSignals] {
      int signal = 0;
      sigwait(&stopSignals, &signal);
      if (ending_ || (signal != SIGINT && signal != SIGTERM)) return;
      if (!serving_) { // the dataset is still being read: nothing to stop cleanly
        logNote("viewer stopped");
        std::fflush(nullptr);
        std::_Exit(0);
      }
      server_.stop();
    });
  }
  ~BoundViewer() {
    ending_ = true;
    pthread_kill(waiter_.native_handle(), SIGTERM); // wakes the waiter
    waiter_.join();
  }
  BoundViewer(const BoundViewer&) = delete;
  BoundViewer& operator=(const BoundViewer&) = delete;

  /// Prints the address, and how to reach it.
  void announce(const std::string& name) const {
    std::cout << server_.url() << std::endl;
    if (logLevel() >= LogLevel::Warning) {
      std::fprintf(stderr,
                   "exabricks: viewing %s at %s\n"
                   "  from another machine: ssh -L %d:localhost:%d %s, then open the address there\n"
                   "  Ctrl-C stops the viewer\n",
                   name.c_str(), server_.url().c_str(), server_.port(), server_.port(), hostName().c_str());
    }
  }

  /// Serves the content until Ctrl-C, SIGTERM or the server's own end.
  void serve(view::ViewContent content) {
    server_.show(std::move(content));
    serving_ = true;
    server_.run();
    server_.stop();
  }

private:
  view::Server server_;
  std::thread waiter_;
  std::atomic<bool> serving_{false}, ending_{false};
};

void run(const ViewCmdOptions& given, const CLI::App& cmd) {
  ViewCmdOptions o = given;
  const std::vector<std::string> steps = viewSteps(o.inputs);
  if (!steps.empty()) o.scene.in.input = steps[0];
  // A series maps one range over all its steps unless --range says LOW,HIGH or per-step.
  bool perStep = false;
  if (o.scene.range.size() == 1 && (o.scene.range[0] == "global" || o.scene.range[0] == "per-step")) {
    perStep = o.scene.range[0] == "per-step";
    o.scene.range.clear();
  }
  const sigset_t stopSignals = blockStopSignals();

  if (o.port < 0 || o.port > 65535) failUsage("--port must be in 0..65535 (0: any free port)");
  if (!o.token.empty() && o.token.size() < 16) failUsage("--token must have at least 16 characters");
  SceneDocument doc = sceneFromOptions(o.scene, cmd);
  if (!cmd.count("--spp") && o.scene.sceneFile.empty() && !(doc.frame.noiseTarget > 0.f))
    doc.frame.samplesPerPixel = kDefaultViewerPasses;

  view::ServerOptions options;
  options.host = o.host;
  options.port = o.port;
  options.token = o.token;
  options.device = o.device;
  if (o.device != "auto" && o.device != "cpu") resolveDevice(o.device); // refuse an unusable one before serving
  // The GPU runtime's start (tens of milliseconds to seconds), beside the reads, for the first frame.
  std::future<void> gpuProbe;
  if (o.device == "auto") gpuProbe = std::async(std::launch::async, [] { cudaStatus(); });
  // Bound before the dataset loads: a taken port fails at once.
  BoundViewer viewer(options, stopSignals);

  Timer loadTimer;
  LoadOptions lo = o.scene.in.loadOptions(false);
  lo.fields.clear(); // every field: the page can switch between them
  double coarseFirst = o.coarseFirst;
  if (steps.size() > 1 && !o.scene.in.memoryBudget.empty())
    failUsage("--memory-budget views one step; a series' steps are each held whole");
  const uint64_t frameBytes = viewerFrameBytes(doc.frame);
  std::future<MergedFirst> merged = mergedBeside(steps, doc.input, lo, o.coarseFirst, o.scene, cmd, doc.scene);
  const ViewBudget budget =
      steps.size() > 1 ? ViewBudget() : viewBudget(o.scene.in, doc.input, lo, frameBytes, coarseFirst);
  viewer.announce(o.scene.in.name()); // after a budget's refusal, before anything else is read
  const FirstStep first = loadFirst(steps, doc.input, lo, coarseFirst, steps.size() > 1 ? 0 : o.coarseFirst,
                                    std::move(merged), budget.mergedCells);
  if (first.series) doc.input = steps[size_t(first.index)];
  const std::shared_ptr<const Model>& model = first.model;
  const DatasetInfo& dataset = first.dataset;
  applyDataDefaults(o.scene, cmd, doc.scene, *model, dataset, nullptr, true, first.choices ? &*first.choices : nullptr);
  std::vector<std::pair<int, std::string>> unreadable = first.unreadable;
  applySeriesRange(first, steps, lo, !o.scene.range.empty(), perStep, doc.scene, unreadable);
  doc.frame.camera = cameraFromOptions(o.scene, cmd, doc, *model, visibleBoundsOf(*model, dataset, doc.scene));
  doc.frame.validate();
  doc.hasCamera = true;
  doc = withAbsolutePaths(doc);
  logInfo(strCat("loaded and built in ", loadTimer.seconds(), " s"));

  view::ViewContent content;
  content.model = model;
  content.dataset = dataset;
  content.input = doc.input == kEmbeddedInput ? std::string() : doc.input;
  content.name = datasetLabel(o.inputs.empty() ? o.scene.in.input : o.inputs[0]);
  content.initial = doc;
  content.load = lo;
  addRefinement(content, first, doc.input, lo, budget);
  if (first.series) {
    content.series = first.series;
    content.steps = steps;
    content.firstStep = first.index;
    content.unreadable = unreadable;
  }
  viewer.serve(std::move(content));
  logNote("viewer stopped");
  if (first.coarse.level > 0 || first.merged > 1 || first.leavesMerged) {
    // The whole dataset may still be being read on its own thread: end the process here, before
    // static objects that thread may use are destroyed.
    std::fflush(nullptr);
    std::_Exit(0);
  }
}
#else
void run(const ViewCmdOptions&, const CLI::App&) {
  fail("this exabricks was built without the viewer: install pkg-config, libcpp-httplib-dev and libturbojpeg0-dev "
       "and build again");
}
#endif

} // namespace

void addView(CLI::App& app) {
  auto o = std::make_shared<ViewCmdOptions>();
  CLI::App* cmd = app.add_subcommand("view", "Explore a dataset interactively in a web browser");
  o->scene.add(*cmd);
  o->scene.in.addMemoryBudget(*cmd);
  // A series' steps replace the single INPUT of the render options.
  cmd->remove_option(cmd->get_option("input"));
  cmd->add_option("inputs", o->inputs,
                  "Dataset, or the steps of a time series: files, folders or glob patterns (numeric order)");
  cmd->add_option("--port", o->port, "Port to listen on (0: any free port)")->capture_default_str();
  cmd->add_option("--host", o->host, "Address to listen on (127.0.0.1: this machine only)")->capture_default_str();
  addDeviceOption(*cmd, o->device);
  cmd->add_option("--token", o->token, "Access token (default: a random one, printed with the address)");
  cmd->add_option("--coarse-first", o->coarseFirst,
                  "An AMReX plotfile with more cells in its boxes shows its coarse levels (at most this many "
                  "cells) at once, then every level (0: every level from the start)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->callback([o, cmd] { run(*o, *cmd); });
}

} // namespace exa::cli
