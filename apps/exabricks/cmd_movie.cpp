// exabricks movie: one frame per time step and/or frames along a camera path, written as
// numbered PNGs and encoded with ffmpeg (see docs/movies.md): plan (the series, the scene and the
// frames), render (through the library's SeriesRenderer; under MPI each process renders a share)
// and encode.
#include "commands.h"
#include "common.h"
#include "mpi/processes.h"
#include "scene_options.h"

#include "exabricks/core/files.h"
#include "exabricks/core/log.h"
#include "exabricks/documents/image.h"
#include "exabricks/documents/scene_file.h"
#include "exabricks/render/defaults.h"
#include "exabricks/render/renderer.h"
#include "exabricks/workflows/encode.h"
#include "exabricks/workflows/series.h"
#include "exabricks/workflows/streamed.h"

#include <nlohmann/json.hpp>

#include <tbb/task_group.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <mutex>
#include <sstream>
#include <thread>
#include <unistd.h>

namespace exa::cli {
namespace {

namespace fs = std::filesystem;

struct MovieCmdOptions {
  RenderOptions scene;
  MarchFlags march;
  std::vector<std::string> inputs;
  std::string output;
  double fps = 24;
  std::string frames; ///< A:B, inclusive, 0-based
  int orbit = 0;      ///< frames around the data
  int flyIn = 0;      ///< frames of a fly-in
  int pathFrames = 0; ///< frames along the scene file's camera path
  int framesPerStep = 1;
  std::string framesDir;
  bool noPrefetch = false;
  bool noReuse = false;
  bool json = false;
};

enum class RangeMode { Global, PerStep, Fixed };

/// What the plan decides: the steps, the scene, the frames, and where they go.
struct MoviePlan {
  std::vector<std::string> paths;
  RenderOptions ro; ///< the options, --range's movie words taken out
  RangeMode rangeMode = RangeMode::Fixed;
  SceneDocument doc;
  LoadOptions lo;
  FramePlan frames;
  int first = 0, last = 0; ///< the frames this run renders (--frames)
  bool toFolder = false;   ///< only frames, no movie file
  std::string ext, framesDir;
  std::vector<int> todo; ///< this process's frames still to render
};

std::string formatSeconds(double s) {
  if (s < 60) return strCat(int(std::lround(s)), " s");
  const int m = int(s / 60);
  return strCat(m, " min ", int(std::lround(s - 60 * m)), " s");
}

/// The frame counts: one frame per step (times --frames-per-step), or along the camera path of a
/// single step. An orbit, fly-in or --path-frames with a series sets the frame count, and time
/// advances across it: the camera moves while the steps play.
FramePlan planFrames(const MovieCmdOptions& o, const CLI::App& cmd, int steps, bool pathFromScene) {
  const int pathCount = o.orbit ? o.orbit : o.flyIn ? o.flyIn : o.pathFrames;
  const char* pathOption = o.orbit ? "--orbit" : o.flyIn ? "--fly-in" : "--path-frames";
  if ((o.orbit || o.flyIn) && pathFromScene)
    failUsage("--orbit and --fly-in replace the scene file's camera path: use one");
  if (o.pathFrames && !pathFromScene) failUsage("--path-frames needs a scene file with a camera_path");
  if (steps > 1 && pathCount) {
    if (cmd.count("--frames-per-step"))
      failUsage(pathOption, " ", pathCount, " sets the movie's frame count, and the ", steps,
                " steps are spread over it: leave out --frames-per-step");
    if (pathCount < steps)
      failUsage(pathOption, " ", pathCount, " gives fewer frames than the series has steps (", steps,
                "): every step needs a frame; use at least ", steps);
    return FramePlan::spread(steps, pathCount);
  }
  if (steps > 1) return FramePlan::perStep(steps, o.framesPerStep);
  FramePlan plan;
  plan.frames = std::max(1, pathCount ? pathCount : (pathFromScene ? int(std::lround(o.fps * 5)) : 1));
  return plan;
}

/// --frames A:B (either end may be left out); a slice past the end renders what is there.
void frameRange(const std::string& text, int frames, int& first, int& last) {
  first = 0;
  last = frames - 1;
  if (text.empty()) return;
  const size_t colon = text.find(':');
  try {
    if (colon == std::string::npos) throw std::invalid_argument("");
    first = text.substr(0, colon).empty() ? 0 : std::stoi(text.substr(0, colon));
    last = text.substr(colon + 1).empty() ? frames - 1 : std::stoi(text.substr(colon + 1));
  } catch (...) {
    failUsage("--frames expects A:B (first and last frame, from 0), got '", text, "'");
  }
  if (first < 0 || last < first || first >= frames)
    failUsage("--frames ", text, " is outside the movie's frames 0..", frames - 1);
  if (last >= frames) {
    // The last batch job of an array sized generously.
    if (mpi::processes().root())
      logNote(strCat("--frames ", text, ": the movie has ", frames, " frames (0..", frames - 1,
                     "), so this renders frames ", first, "..", frames - 1));
    last = frames - 1;
  }
}

/// Plan, first part: the options checked, the series, the range mode, the scene and the frames.
MoviePlan planMovie(const MovieCmdOptions& o, const CLI::App& cmd) {
  if (!(o.fps > 0 && o.fps <= 1000)) failUsage("--fps must be in (0, 1000]");
  if (o.orbit < 0 || o.flyIn < 0 || o.pathFrames < 0) failUsage("frame counts must not be negative");
  if ((o.orbit > 0) + (o.flyIn > 0) > 1) failUsage("--orbit and --fly-in exclude each other");
  if (o.framesPerStep < 1 || o.framesPerStep > 10000) failUsage("--frames-per-step must be in 1..10000");
  MoviePlan p;
  // What to encode: a video by its extension, or only frames into a folder.
  p.ext = fs::path(o.output).extension().string();
  p.toFolder = p.ext.empty() || fs::is_directory(o.output);
  if (!p.toFolder && p.ext != ".mp4" && p.ext != ".webm")
    failUsage("-o ", o.output, ": write .mp4 (H.264), .webm (VP9) or a folder for the frames alone");
  p.framesDir = !o.framesDir.empty() ? o.framesDir : p.toFolder ? o.output : o.output + ".frames";
  if (!p.toFolder) checkOutputFolder(o.output);

  p.paths = o.inputs.empty() ? std::vector<std::string>{""} : seriesSteps(o.inputs);
  const int steps = int(p.paths.size());
  p.ro = o.scene;
  std::vector<std::string>& range = p.ro.range;
  if (range.size() == 1 && (range[0] == "global" || range[0] == "per-step")) {
    p.rangeMode = range[0] == "global" ? RangeMode::Global : RangeMode::PerStep;
    range.clear();
  } else if (range.empty()) {
    p.rangeMode = steps > 1 ? RangeMode::Global : RangeMode::PerStep;
  }
  if (steps > 1 && !cmd.count("--frame-all") && !cmd.count("--position"))
    p.ro.frameAll = true; // the domain stays in view
  if (!o.inputs.empty()) p.ro.in.input = p.paths[0];
  p.doc = sceneFromOptions(p.ro, cmd);
  if (o.inputs.empty()) p.paths = {p.doc.input}; // the scene file's input, or the default dataset
  p.doc.input.clear();
  p.lo = p.ro.in.loadOptions(false);
  p.lo.fields = neededFields(p.doc.scene);
  p.frames = planFrames(o, cmd, steps, !p.doc.path.empty());
  frameRange(o.frames, p.frames.frames, p.first, p.last);
  const double seconds = p.frames.frames / o.fps;
  if (steps > 1 && !p.toFolder && !cmd.count("--frames-per-step") && p.frames.frames == steps && seconds < 2.0 &&
      mpi::processes().root()) {
    const int hold = std::max(2, int(std::ceil(std::min(1.0, 4.0 / steps) * o.fps)));
    logNote(strCat("the movie shows each of its ", steps, " steps for one frame: ", std::round(seconds * 100) / 100,
                   " s at ", o.fps, " frames per second; --frames-per-step ", hold, " holds each step for ",
                   std::round(hold / o.fps * 100) / 100, " s (or lower --fps)"));
  }
  return p;
}

/// The camera of the first picture, and the orbit or fly-in around what it shows (`visible`, or
/// the whole `domain` with --frame-all or when nothing is visible).
void frameMovie(const MovieCmdOptions& o, const CLI::App& cmd, MoviePlan& p, const Model& model, const box3d& domain,
                const box3d& visible, const WholeData* whole = nullptr) {
  const RenderOptions& ro = p.ro;
  const box3d target = ro.frameAll || visible.empty() ? domain : visible;
  p.doc.frame.camera = cameraFromOptions(ro, cmd, p.doc, model, visible, whole);
  if (o.flyIn) p.doc.path = flyInPath(target, ro.azimuth, ro.elevation, ro.fov, ro.ortho);
  p.doc.frame.validate();
  p.doc.hasCamera = true;
  if (o.orbit) p.frames.orbit = OrbitView{target, ro.azimuth, ro.elevation, ro.fov, ro.ortho};
  p.frames.path = p.doc.path;
}

/// Plan, second part: step 0 fixes the first picture (field, transfer-function defaults, value
/// range, camera) for every slice of the movie, whichever frames this process renders.
void planFirstPicture(const MovieCmdOptions& o, const CLI::App& cmd, MoviePlan& p, SeriesRenderer& series) {
  mpi::onEveryProcess("read the first step", [&] { series.load(0); });
  const SeriesStep& first = series.current();
  const Model& model0 = *first.model;
  Scene& scene = p.doc.scene;
  RenderOptions& ro = p.ro;
  applyDataDefaults(ro, cmd, scene, model0, first.info);
  const int steps = series.size();
  if (p.rangeMode == RangeMode::Global && steps > 1) {
    const int field = model0.requireField(scene.layers[0].field);
    const SeriesRange r = seriesRange(p.paths, p.lo, model0.fieldNames[size_t(field)]);
    TransferFunction& tf = scene.layers[0].tf;
    tf = widenedForSeries(tf, first.info.valueRanges.at(size_t(field)), r.range);
    logNote(strCat("colour range over all ", steps, " steps: [", tf.valueRange.lower, ", ", tf.valueRange.upper,
                   "] (values over [", r.range.lower, ", ", r.range.upper, "])",
                   r.fromMetadata ? strCat(" (", r.fromMetadata, " from metadata)") : std::string(),
                   "; --range per-step or LOW,HIGH to choose"));
  } else if (p.rangeMode == RangeMode::PerStep && !cmd.count("--range")) {
    scene.layers[0].tf.valueRange = range1f();
  }
  frameMovie(o, cmd, p, model0, model0.worldBounds(), visibleBoundsOf(model0, first.info, scene));
}

/// Plan, last part: the manifest. Frames already rendered for this very movie are kept (a movie
/// split over several jobs with --frames is joined by running the command again without it);
/// under MPI the processes take interleaved frames and the first one records the movie.
void planFrameShare(const MovieCmdOptions& o, MoviePlan& p) {
  fs::create_directories(p.framesDir);
  const nlohmann::json manifest = {{"inputs", nlohmann::json(p.paths)},
                                   {"scene", nlohmann::json::parse(writeSceneJson(p.doc))},
                                   {"frames", p.frames.frames},
                                   {"frames_per_step", o.framesPerStep},
                                   {"orbit", o.orbit},
                                   {"fly_in", o.flyIn}};
  const std::string manifestPath = (fs::path(p.framesDir) / "movie.json").string();
  bool sameMovie = false;
  if (std::ifstream in(manifestPath); in) {
    try {
      sameMovie = nlohmann::json::parse(in) == manifest;
    } catch (...) {
      sameMovie = false;
    }
  }
  std::vector<int> todo;
  for (int i = p.first; i <= p.last; ++i)
    if (!(sameMovie && fs::exists(framePath(p.framesDir, i)))) todo.push_back(i);
  mpi::barrier();
  if (mpi::processes().root()) {
    const std::string manifestText = manifest.dump(2) + "\n";
    writeFileAtomic(manifestPath, manifestText.data(), manifestText.size());
    writeSceneFile((fs::path(p.framesDir) / "scene.json").string(), withAbsolutePaths(p.doc));
  }
  p.todo = mpi::shareOf(todo);
}

/// Render: this process's frames through the series renderer (the next step loading while one
/// renders), each with its legends written as a PNG, with a progress line. The PNGs are encoded
/// and written by tasks beside the rendering (as many at once as there are cores), so that a fast
/// renderer does not wait for the encoder. A process that fails stops all of them. Returns the
/// frames rendered.
int renderMovie(const MoviePlan& p, SeriesRenderer& series) {
  const bool showProgress = logLevel() >= LogLevel::Warning;
  const bool tty = isatty(STDERR_FILENO);
  int done = 0;
  Timer loop;
  tbb::task_group writers;
  std::atomic<int> writing{0};
  const int maxWriting = std::max(2, int(std::thread::hardware_concurrency()));
  std::mutex failedMutex;
  std::exception_ptr failed;
  auto write = [&](int i, const SeriesStep& step, const Scene& scene, const Frame& frame, Image& image) {
    // The annotation names each frame's own step.
    drawLegends(scene, frame, *step.model, step.info, legendText(p.paths[size_t(step.index)]), image);
    while (writing.load() >= maxWriting)
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    ++writing;
    writers.run([&, path = framePath(p.framesDir, i), picture = std::move(image), keepAlpha = scene.keepAlpha,
                 background = scene.background] {
      try {
        writePng(path, picture, keepAlpha, background);
      } catch (...) {
        std::lock_guard<std::mutex> lock(failedMutex);
        if (!failed) failed = std::current_exception();
      }
      --writing;
    });
    ++done;
    if (!showProgress) return;
    const double per = loop.seconds() / done;
    const std::string line = strCat("frame ", i, " (", done, " of ", p.todo.size(), ", step ", step.index + 1, " of ",
                                    series.size(), "): ", std::round(per * 100) / 100, " s per frame, ETA ",
                                    formatSeconds(per * double(p.todo.size() - size_t(done))));
    if (tty)
      std::fprintf(stderr, "\r\033[K%s", line.c_str());
    else
      std::fprintf(stderr, "%s\n", line.c_str());
  };
  auto endLine = [&] {
    if (showProgress && tty && done) std::fprintf(stderr, "\n");
  };
  mpi::onEveryProcess("render its frames", [&] {
    try {
      series.renderFrames(p.frames, p.doc.scene, p.doc.frame, p.todo, write);
    } catch (...) {
      writers.wait();
      endLine();
      throw;
    }
    writers.wait();
    endLine();
    if (failed) std::rethrow_exception(failed);
  });
  return done;
}

/// Encode (on the first process, once every frame of the movie is there): ffmpeg into a temporary
/// file moved into place. Returns the movie written, or empty (frames only, frames missing, or
/// no ffmpeg: each says so).
std::string encodeMovie(const MovieCmdOptions& o, const MoviePlan& p, int missing) {
  if (p.toFolder) return {};
  const int frames = p.frames.frames;
  MovieEncoding e;
  e.framesDir = p.framesDir;
  e.fps = o.fps;
  e.output = o.output;
  if (missing) {
    logNote(strCat("frames ", p.first, "..", p.last, " are in ", p.framesDir, "; ", missing, " of ", frames,
                   " frames are still to render (other --frames slices); run this command again without "
                   "--frames to render what is missing and encode ",
                   o.output));
    return {};
  }
  if (!encodeFrames(e)) {
    logWarning(strCat("ffmpeg is not installed, so ", o.output, " was not encoded; the ", frames, " frames are in ",
                      p.framesDir,
                      ". Install ffmpeg and run this command again, or encode them with: ", encodeCommandExample(e)));
    return {};
  }
  logInfo(strCat("encoded ", frames, " frames into ", o.output));
  return o.output;
}

void printSummary(const MovieCmdOptions& o, const MoviePlan& p, const SeriesRenderer& series, int done,
                  const std::string& encoded, int missing, double seconds) {
  const SeriesStats& s = series.stats();
  const nlohmann::json j{{"frames", p.frames.frames},
                         {"rendered", done},
                         {"first", p.first},
                         {"last", p.last},
                         {"steps", series.size()},
                         {"steps_loaded", s.loaded},
                         {"steps_reused", s.reused},
                         {"frames_dir", p.framesDir},
                         {"output", encoded},
                         {"missing_frames", missing},
                         {"seconds", seconds},
                         {"render_seconds", s.renderSeconds},
                         {"load_seconds", s.loadSeconds},
                         {"load_wait_seconds", s.waitSeconds},
                         {"prefetch", !o.noPrefetch},
                         {"reuse", !o.noReuse}};
  std::cout << j.dump(2) << "\n";
}

/// Under a memory budget: one step open at a time (no prefetch), each held in the parts its plan
/// makes (one part when it fits), kept resident across its frames while the budget holds them,
/// every frame drawn part by part front to back as `render --memory-budget` draws it.
class BudgetedMovie {
public:
  BudgetedMovie(const MovieCmdOptions& o, const CLI::App& cmd, MoviePlan& p, uint64_t budget)
      : o_(o), cmd_(cmd), p_(p), budget_(budget), options_(o.march.options()),
        frameBytes_(streamedFrameBytes(p.doc.frame.width, p.doc.frame.height, p.doc.frame.samplesPerPixel)) {
    if (o.march.device != "auto" && o.march.device != "cpu")
      failUsage("--memory-budget draws on the CPU; --device ", o.march.device, " holds the whole step");
  }

  void run() {
    Timer total;
    firstPicture();
    planFrameShare(o_, p_);
    const int done = renderFrames();
    int missing = 0;
    for (int i = 0; i < p_.frames.frames; ++i)
      missing += fs::exists(framePath(p_.framesDir, i)) ? 0 : 1;
    const std::string encoded = encodeMovie(o_, p_, missing);
    if (!o_.json) return;
    const nlohmann::json j{{"frames", p_.frames.frames},
                           {"rendered", done},
                           {"first", p_.first},
                           {"last", p_.last},
                           {"steps", int(p_.paths.size())},
                           {"steps_loaded", stepsOpened_},
                           {"frames_dir", p_.framesDir},
                           {"output", encoded},
                           {"missing_frames", missing},
                           {"seconds", total.seconds()},
                           {"render_seconds", renderSeconds_},
                           {"memory",
                            {{"budget_bytes", budget_},
                             {"parts_read", partsRead_},
                             {"largest_parts", largestParts_},
                             {"peak_rss_bytes", peakResidentBytes()}}}};
    std::cout << j.dump(2) << "\n";
  }

private:
  StreamedStep& open(int k) {
    if (current_ == k) return *step_;
    if (step_) partsRead_ += step_->partsRead();
    step_.reset(); // the step before is dropped before the next is read
    step_ = std::make_unique<StreamedStep>(p_.paths[size_t(k)], p_.lo,
                                           planWithin(p_.paths[size_t(k)], p_.lo, budget_, frameBytes_));
    step_->setParticles(particlesFor(p_.doc.scene, p_.paths[size_t(k)]));
    current_ = k;
    ++stepsOpened_;
    largestParts_ = std::max(largestParts_, step_->parts());
    return *step_;
  }

  WholeData whole(StreamedStep& step) {
    const StepSurvey& survey = step.survey();
    return WholeData{survey.cellBounds, survey.levels, step.partialData()};
  }

  /// Step 0's defaults and camera, as planFirstPicture takes them from a whole step; a range over
  /// the series from the files' metadata where they record it, else from each step's parts.
  void firstPicture() {
    StreamedStep& first = open(0);
    Scene& scene = p_.doc.scene;
    WholeData w = whole(first);
    applyDataDefaults(p_.ro, cmd_, scene, first.skeleton(), first.survey().dataset, &w);
    const int steps = int(p_.paths.size());
    if (p_.rangeMode == RangeMode::Global && steps > 1) {
      const std::string field =
          first.skeleton().fieldNames[size_t(first.skeleton().requireField(scene.layers[0].field))];
      range1f values;
      for (int k = 0; k < steps; ++k)
        if (const std::optional<range1f> r = fieldRangeFromMetadata(p_.paths[size_t(k)], field))
          values.extend(*r);
        else
          values.extend(open(k).survey().dataset.valueRanges.at(size_t(open(k).skeleton().requireField(field))));
      StreamedStep& step0 = open(0);
      TransferFunction& tf = scene.layers[0].tf;
      tf = widenedForSeries(tf, step0.survey().dataset.valueRanges.at(size_t(step0.skeleton().requireField(field))),
                            values);
      logNote(strCat("colour range over all ", steps, " steps: [", tf.valueRange.lower, ", ", tf.valueRange.upper,
                     "]; --range per-step or LOW,HIGH to choose"));
    } else if (p_.rangeMode == RangeMode::PerStep && !cmd_.count("--range")) {
      scene.layers[0].tf.valueRange = range1f();
    }
    StreamedStep& step0 = open(0);
    w = whole(step0);
    frameMovie(o_, cmd_, p_, step0.skeleton(), step0.skeleton().world.toWorld(w.cellBounds),
               step0.visibleBounds(scene, options_), &w);
  }

  int renderFrames() {
    int done = 0;
    Timer loop;
    for (const int i : p_.todo) {
      const int k = p_.frames.stepOf(i);
      StreamedStep& step = open(k);
      Scene scene = p_.doc.scene;
      Frame frame = p_.doc.frame;
      p_.frames.view(i, scene, frame);
      FrameBuffer buffer(frame.width, frame.height);
      Timer timer;
      renderStreamed(step, scene, options_, frame, buffer);
      renderSeconds_ += timer.seconds();
      Image image = buffer.resolve();
      const WholeData w = whole(step);
      drawLegends(scene, frame, step.skeleton(), step.survey().dataset, legendText(p_.paths[size_t(k)], &w), image);
      writePng(framePath(p_.framesDir, i), image, scene.keepAlpha, scene.background);
      ++done;
      if (logLevel() >= LogLevel::Warning)
        std::fprintf(stderr, "frame %d (%d of %zu, step %d of %zu, %d parts): %.2f s per frame\n", i, done,
                     p_.todo.size(), k + 1, p_.paths.size(), step.parts(), loop.seconds() / done);
    }
    if (step_) partsRead_ += step_->partsRead();
    step_.reset();
    current_ = -1;
    return done;
  }

  const MovieCmdOptions& o_;
  const CLI::App& cmd_;
  MoviePlan& p_;
  uint64_t budget_;
  RendererOptions options_;
  uint64_t frameBytes_;
  std::unique_ptr<StreamedStep> step_;
  int current_ = -1;
  int stepsOpened_ = 0, largestParts_ = 0;
  uint64_t partsRead_ = 0;
  double renderSeconds_ = 0;
};

void run(const MovieCmdOptions& o, const CLI::App& cmd) {
  MoviePlan plan = planMovie(o, cmd);
  // A movie under --memory-budget holds every step within it; without the flag, a first step too
  // large for the memory available sets the budget the whole movie keeps.
  const Frame& f = plan.doc.frame;
  const uint64_t frameBytes = streamedFrameBytes(f.width, f.height, f.samplesPerPixel);
  if (const std::optional<uint64_t> budget =
          memoryBudgetFor(plan.ro.in, plan.paths[0], plan.lo, frameBytes, mpi::processes().size > 1);
      budget &&
      (!plan.ro.in.memoryBudget.empty() || planWithin(plan.paths[0], plan.lo, *budget, frameBytes).streamed()))
    return BudgetedMovie(o, cmd, plan, *budget).run();
  Timer total;
  SeriesOptions so;
  so.load = plan.lo;
  so.prefetch = !o.noPrefetch;
  so.reuse = !o.noReuse;
  so.renderer = o.march.options();
  so.device = o.march.device;
  if (plan.doc.scene.particles.show) so.particles = plan.doc.scene.particles.species;
  SeriesRenderer series(plan.paths, so);
  planFirstPicture(o, cmd, plan, series);
  planFrameShare(o, plan);
  const int done = renderMovie(plan, series);
  if (!mpi::processes().root()) return;
  int missing = 0;
  for (int i = 0; i < plan.frames.frames; ++i)
    missing += fs::exists(framePath(plan.framesDir, i)) ? 0 : 1;
  const std::string encoded = encodeMovie(o, plan, missing);
  if (o.json) printSummary(o, plan, series, done, encoded, missing, total.seconds());
}

} // namespace

void addMovie(CLI::App& app) {
  auto o = std::make_shared<MovieCmdOptions>();
  CLI::App* cmd = app.add_subcommand("movie", "Render a time series and/or a camera path to a movie");
  o->scene.add(*cmd);
  o->scene.in.addMemoryBudget(*cmd);
  o->march.add(*cmd);
  // The movie's inputs replace the single INPUT of the render options.
  cmd->remove_option(cmd->get_option("input"));
  cmd->add_option("inputs", o->inputs, "Datasets: files, folders or glob patterns (numeric order)");
  cmd->add_option("-o,--output", o->output, "Movie to write: .mp4 or .webm, or a folder for the PNG frames")
      ->required();
  cmd->add_option("--fps", o->fps, "Frames per second")->capture_default_str();
  cmd->add_option("--frames", o->frames, "Render only frames A:B (from 0, inclusive), e.g. one slice per job");
  cmd->add_option("--orbit", o->orbit, "N frames around the data at --elevation, starting at --azimuth");
  cmd->add_option("--fly-in", o->flyIn, "N frames flying in to the default view");
  cmd->add_option("--path-frames", o->pathFrames, "Frames along the scene file's camera_path (default: 5 s)");
  cmd->add_option("--frames-per-step", o->framesPerStep, "Frames per time step")->capture_default_str();
  cmd->add_option("--frames-dir", o->framesDir, "Folder of the numbered PNG frames (default: OUTPUT.frames)");
  cmd->add_flag("--no-prefetch", o->noPrefetch, "Load each step only when its frames start (no overlap)");
  cmd->add_flag("--no-reuse", o->noReuse, "Build every step's bricks and regions, even for an unchanged hierarchy");
  cmd->add_flag("--json", o->json, "Print a JSON summary on stdout");
  cmd->callback([o, cmd] { run(*o, *cmd); });
}

} // namespace exa::cli
