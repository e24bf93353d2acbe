// exabricks movie: one frame per time step and/or frames along a camera path, written as
// numbered PNGs and encoded with ffmpeg (see docs/movies.md).
#include "commands.h"
#include "common.h"
#include "parallel.h"
#include "scene_options.h"

#include "exabricks/core/files.h"
#include "exabricks/core/log.h"
#include "exabricks/documents/image.h"
#include "exabricks/documents/scene_file.h"
#include "exabricks/io/series.h"
#include "exabricks/render/renderer.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <future>
#include <iostream>
#include <memory>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>
#include <unordered_set>

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

/// One loaded time step: the model, its dataset values and the structure its bricks came from.
struct Step {
  std::shared_ptr<const Model> model;
  DatasetInfo info;
  std::shared_ptr<const ModelStructure> structure;
  double seconds = 0;
  bool reused = false;
};

Step loadStep(const std::string& path, const LoadOptions& lo, const Step* previous, bool reuse) {
  Timer timer;
  Step step;
  if (detectInput(path) == InputKind::Model) {
    step.model = std::make_shared<const Model>(loadModel(path, lo));
  } else {
    CellSet cells = loadCells(path, lo);
    if (reuse && previous && previous->structure && previous->structure->matches(cells, lo.build)) {
      step.model =
          std::make_shared<const Model>(rebuildValues(*previous->model, *previous->structure, std::move(cells)));
      step.structure = previous->structure;
      step.reused = true;
    } else {
      auto structure = std::make_shared<ModelStructure>();
      step.model = std::make_shared<const Model>(buildModel(std::move(cells), lo.build, *structure));
      if (reuse) step.structure = std::move(structure);
    }
  }
  step.info = DatasetInfo::of(*step.model);
  step.seconds = timer.seconds();
  return step;
}

/// The range of the named field over every step: from metadata where the format records ranges,
/// else reading only that field.
range1f seriesRange(const std::vector<std::string>& paths, LoadOptions lo, const std::string& field,
                    int& fromMetadata) {
  range1f all;
  fromMetadata = 0;
  lo.fields = {field};
  for (const std::string& path : paths) {
    if (const std::optional<range1f> r = fieldRangeFromMetadata(path, field)) {
      all.extend(*r);
      ++fromMetadata;
      continue;
    }
    if (detectInput(path) == InputKind::Model) {
      const Model m = loadModel(path, lo);
      for (float v : m.fieldValues.at(size_t(m.requireField(field))))
        all.extend(v);
      continue;
    }
    const CellSet cells = loadCells(path, lo);
    const int f = cells.fieldIndex(field);
    if (f < 0) fail(path, ": no field '", field, "' (the series' first step has it)");
    for (float v : cells.fields[size_t(f)].values)
      all.extend(v);
  }
  return all;
}

/// The movie's steps: inputs in the order given, a glob pattern or a folder expanded into its
/// datasets in numeric order (explicit files are never re-sorted: `movie b a` plays b, then a);
/// a dataset named twice plays once, where it first appears.
std::vector<std::string> seriesSteps(const std::vector<std::string>& inputs) {
  std::vector<std::string> out;
  std::unordered_set<std::string> seen;
  for (const std::string& input : inputs)
    for (std::string& path : expandSeries({input}))
      if (seen.insert(path).second) out.push_back(std::move(path));
  return out;
}

std::string findProgram(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "/usr/bin:/bin");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    const std::string candidate = (dir.empty() ? "." : dir) + "/" + name;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
  }
  return {};
}

/// Runs a program with arguments (no shell); returns its exit status (-1 when it cannot start).
int runProgram(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (const std::string& a : args)
    argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string framePath(const std::string& dir, int frame) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%05d.png", frame);
  return (fs::path(dir) / name).string();
}

std::string formatSeconds(double s) {
  if (s < 60) return strCat(int(std::lround(s)), " s");
  const int m = int(s / 60);
  return strCat(m, " min ", int(std::lround(s - 60 * m)), " s");
}

void run(const MovieCmdOptions& o, const CLI::App& cmd) {
  auto given = [&](const char* name) { return cmd.count(name) > 0; };
  if (!(o.fps > 0 && o.fps <= 1000)) failUsage("--fps must be in (0, 1000]");
  if (o.orbit < 0 || o.flyIn < 0 || o.pathFrames < 0) failUsage("frame counts must not be negative");
  if ((o.orbit > 0) + (o.flyIn > 0) > 1) failUsage("--orbit and --fly-in exclude each other");
  if (o.framesPerStep < 1 || o.framesPerStep > 10000) failUsage("--frames-per-step must be in 1..10000");

  // What to encode: a video by its extension, or only frames into a folder.
  const std::string ext = fs::path(o.output).extension().string();
  const bool toFolder = ext.empty() || (fs::is_directory(o.output));
  if (!toFolder && ext != ".mp4" && ext != ".webm")
    failUsage("-o ", o.output, ": write .mp4 (H.264), .webm (VP9) or a folder for the frames alone");
  const std::string framesDir = !o.framesDir.empty() ? o.framesDir : toFolder ? o.output : o.output + ".frames";

  // The series and the range mode.
  const std::vector<std::string> paths = o.inputs.empty() ? std::vector<std::string>{""} : seriesSteps(o.inputs);
  const int steps = int(paths.size());
  RenderOptions ro = o.scene;
  RangeMode rangeMode = RangeMode::Fixed;
  if (ro.range.size() == 1 && (ro.range[0] == "global" || ro.range[0] == "per-step")) {
    rangeMode = ro.range[0] == "global" ? RangeMode::Global : RangeMode::PerStep;
    ro.range.clear();
  } else if (ro.range.empty()) {
    rangeMode = steps > 1 ? RangeMode::Global : RangeMode::PerStep;
  }
  if (steps > 1 && !given("--frame-all") && !given("--position")) ro.frameAll = true; // the domain stays in view
  SceneDocument doc = sceneFromOptions(ro, cmd);
  doc.input.clear();
  LoadOptions lo = ro.in.loadOptions(false);
  lo.fields = neededFields(doc.scene);

  // Frames: one per step (times --frames-per-step), or along the camera path of a single step.
  // An orbit, fly-in or --path-frames with a series sets the frame count, and time advances
  // across it: the camera moves while the steps play.
  const bool pathFromScene = !doc.path.empty();
  const int pathCount = o.orbit ? o.orbit : o.flyIn ? o.flyIn : o.pathFrames;
  const char* pathOption = o.orbit ? "--orbit" : o.flyIn ? "--fly-in" : "--path-frames";
  if ((o.orbit || o.flyIn) && pathFromScene)
    failUsage("--orbit and --fly-in replace the scene file's camera path: use one");
  if (o.pathFrames && !pathFromScene) failUsage("--path-frames needs a scene file with a camera_path");
  if (steps > 1 && pathCount) {
    if (given("--frames-per-step"))
      failUsage(pathOption, " ", pathCount, " sets the movie's frame count, and the ", steps,
                " steps are spread over it: leave out --frames-per-step");
    if (pathCount < steps)
      failUsage(pathOption, " ", pathCount, " gives fewer frames than the series has steps (", steps,
                "): every step needs a frame; use at least ", steps);
  }
  int frames = steps > 1 ? (pathCount ? pathCount : steps * o.framesPerStep)
                         : (pathCount ? pathCount : (pathFromScene ? int(std::lround(o.fps * 5)) : 1));
  frames = std::max(frames, 1);
  int first = 0, last = frames - 1;
  if (!o.frames.empty()) {
    const size_t colon = o.frames.find(':');
    try {
      if (colon == std::string::npos) throw std::invalid_argument("");
      first = o.frames.substr(0, colon).empty() ? 0 : std::stoi(o.frames.substr(0, colon));
      last = o.frames.substr(colon + 1).empty() ? frames - 1 : std::stoi(o.frames.substr(colon + 1));
    } catch (...) {
      failUsage("--frames expects A:B (first and last frame, from 0), got '", o.frames, "'");
    }
    if (first < 0 || last < first || first >= frames)
      failUsage("--frames ", o.frames, " is outside the movie's frames 0..", frames - 1);
    if (last >= frames) {
      // A slice past the end (the last batch job of an array sized generously) renders what is there.
      if (parallel::processes().root())
        logNote(strCat("--frames ", o.frames, ": the movie has ", frames, " frames (0..", frames - 1,
                       "), so this renders frames ", first, "..", frames - 1));
      last = frames - 1;
    }
  }
  auto stepOf = [&](int frame) {
    if (steps <= 1) return 0;
    if (pathCount) return std::min(steps - 1, int(int64_t(frame) * steps / frames));
    return std::min(steps - 1, frame / o.framesPerStep);
  };

  // Step 0 fixes the first picture (field, transfer-function defaults, camera) for every slice
  // of the movie, whichever frames this process renders.
  Timer total;
  const bool reuse = !o.noReuse;
  Step firstStep;
  std::string loadError;
  try {
    firstStep = loadStep(paths[0], lo, nullptr, reuse);
  } catch (const std::exception& e) {
    loadError = e.what();
  }
  parallel::agreeOrFail(loadError, "read the first step");
  const parallel::Processes& procs = parallel::processes();
  const Model& model0 = *firstStep.model;
  applyDataDefaults(ro, cmd, doc.scene, model0, firstStep.info);
  if (rangeMode == RangeMode::Global && steps > 1) {
    int fromMetadata = 0;
    const std::string& name = model0.fieldNames[size_t(model0.requireField(doc.scene.layers[0].field))];
    const range1f r = seriesRange(paths, lo, name, fromMetadata);
    doc.scene.layers[0].tf.valueRange = r;
    logNote(strCat("colour range over all ", steps, " steps: [", r.lower, ", ", r.upper, "]",
                   fromMetadata ? strCat(" (", fromMetadata, " from metadata)") : std::string(),
                   "; --range per-step or LOW,HIGH to choose"));
  } else if (rangeMode == RangeMode::PerStep && !given("--range")) {
    doc.scene.layers[0].tf.valueRange = range1f();
  }
  box3d domain;
  {
    const box3i cb = model0.cellBounds();
    domain = box3d(model0.world.toWorld(vec3d(cb.lower)), model0.world.toWorld(vec3d(cb.upper)));
  }
  Renderer framing(model0, firstStep.info);
  framing.setScene(doc.scene);
  const box3d target = ro.frameAll || framing.visibleBounds().empty() ? domain : framing.visibleBounds();
  doc.frame.camera = cameraFromOptions(ro, cmd, doc, model0, framing.visibleBounds());
  if (o.flyIn) doc.path = flyInPath(target, ro.azimuth, ro.elevation, ro.fov, ro.ortho);
  doc.frame.validate();
  doc.hasCamera = true;

  auto frameSetup = [&](int i, Scene& scene, Frame& frame) {
    scene = doc.scene;
    frame = doc.frame;
    if (o.orbit) {
      frame.camera = orbitCamera(target, ro.azimuth, ro.elevation, ro.fov, ro.ortho, i, frames);
    } else if (!doc.path.empty()) {
      const double t = doc.path.frameTime(i, frames);
      frame.camera = doc.path.cameraAt(t);
      doc.path.applySettings(t, scene);
    }
  };

  // Frames already rendered for this very movie are kept (a movie split over several jobs with
  // --frames is joined by running the command again without it).
  fs::create_directories(framesDir);
  nlohmann::json manifest = {{"inputs", nlohmann::json(paths)},
                             {"scene", nlohmann::json::parse(writeSceneJson(doc))},
                             {"frames", frames},
                             {"frames_per_step", o.framesPerStep},
                             {"orbit", o.orbit},
                             {"fly_in", o.flyIn},
                             {"overlays", {ro.colorbar, ro.annotate}}};
  const std::string manifestPath = (fs::path(framesDir) / "movie.json").string();
  bool sameMovie = false;
  {
    std::ifstream in(manifestPath);
    if (in) {
      try {
        sameMovie = nlohmann::json::parse(in) == manifest;
      } catch (...) {
        sameMovie = false;
      }
    }
  }
  std::vector<int> todo;
  for (int i = first; i <= last; ++i)
    if (!(sameMovie && fs::exists(framePath(framesDir, i)))) todo.push_back(i);
  // Under MPI the processes take interleaved frames; the first one records the movie.
  parallel::barrier();
  if (procs.root()) {
    const std::string manifestText = manifest.dump(2) + "\n";
    writeFileAtomic(manifestPath, manifestText.data(), manifestText.size());
    writeSceneFile((fs::path(framesDir) / "scene.json").string(), withAbsolutePaths(doc));
  }
  if (procs.size > 1) {
    std::vector<int> mine;
    for (size_t n = 0; n < todo.size(); ++n)
      if (int(n % size_t(procs.size)) == procs.rank) mine.push_back(todo[n]);
    todo = std::move(mine);
  }

  // Render, loading step k+1 while step k renders (at most two steps resident).
  const bool showProgress = logLevel() >= LogLevel::Warning;
  const bool tty = isatty(STDERR_FILENO);
  double renderSeconds = 0, loadSeconds = firstStep.seconds, waitSeconds = 0;
  int reusedSteps = 0, loadedSteps = 1;
  int currentStep = 0;
  Step current = std::move(firstStep);
  std::future<Step> next;
  int nextStep = -1;
  auto startPrefetch = [&](int step) {
    if (step >= steps || step == nextStep) return;
    nextStep = step;
    const Step* prev = &current;
    next = std::async(std::launch::async, [&, step, prev] { return loadStep(paths[size_t(step)], lo, prev, reuse); });
  };
  std::unique_ptr<Renderer> renderer;
  RenderOptions overlays = ro; // --annotate names each frame's own step
  int done = 0;
  Timer loop;
  std::string renderError;
  try {
    for (size_t n = 0; n < todo.size(); ++n) {
      const int i = todo[n];
      const int step = stepOf(i);
      if (step != currentStep) {
        Timer wait;
        if (nextStep == step) {
          Step loaded = next.get();
          nextStep = -1;
          renderer.reset();
          current = std::move(loaded);
        } else {
          if (next.valid()) next.get();
          nextStep = -1;
          renderer.reset();
          current = loadStep(paths[size_t(step)], lo, &current, reuse);
        }
        waitSeconds += wait.seconds();
        loadSeconds += current.seconds;
        reusedSteps += current.reused ? 1 : 0;
        ++loadedSteps;
        currentStep = step;
      }
      if (!renderer) {
        renderer = std::make_unique<Renderer>(*current.model, current.info);
        renderer->setOptions(o.march.options());
      }
      // The next step this process needs, loaded beside the render.
      if (!o.noPrefetch)
        for (size_t m = n + 1; m < todo.size(); ++m)
          if (stepOf(todo[m]) != step) {
            startPrefetch(stepOf(todo[m]));
            break;
          }
      Scene scene;
      Frame frame;
      frameSetup(i, scene, frame);
      renderer->setScene(scene);
      Timer t;
      Image image = renderer->render(frame);
      renderSeconds += t.seconds();
      overlays.in.input = paths[size_t(step)];
      drawOverlays(overlays, scene, frame, *current.model, current.info,
                   current.model->requireField(scene.layers[0].field), image);
      writePng(framePath(framesDir, i), image, scene.keepAlpha, scene.background);
      ++done;
      if (showProgress) {
        const double per = loop.seconds() / done;
        const std::string line = strCat("frame ", i, " (", done, " of ", todo.size(), ", step ", step + 1, " of ",
                                        steps, "): ", std::round(per * 100) / 100, " s per frame, ETA ",
                                        formatSeconds(per * double(todo.size() - size_t(done))));
        if (tty)
          std::fprintf(stderr, "\r\033[K%s", line.c_str());
        else
          std::fprintf(stderr, "%s\n", line.c_str());
      }
    }
    if (next.valid()) next.get();
  } catch (const std::exception& e) {
    renderError = e.what();
    try {
      if (next.valid()) next.get();
    } catch (...) {
    }
  }
  if (showProgress && tty && done) std::fprintf(stderr, "\n");

  // Encode when every frame of the movie is there (under MPI, once every process is done; a
  // process that failed stops all of them).
  parallel::agreeOrFail(renderError, "render its frames");
  if (!procs.root()) return;
  int missing = 0;
  for (int i = 0; i < frames; ++i)
    missing += fs::exists(framePath(framesDir, i)) ? 0 : 1;
  std::string encoded;
  if (!toFolder) {
    const std::string pattern = (fs::path(framesDir) / "frame_%05d.png").string();
    const bool webm = ext == ".webm";
    const std::string fpsText = strCat(o.fps);
    const std::string example =
        strCat("ffmpeg -framerate ", fpsText, " -i ", pattern,
               webm ? " -c:v libvpx-vp9 -b:v 0 -crf 32 " : " -c:v libx264 -pix_fmt yuv420p -crf 18 ", o.output);
    const std::string ffmpeg = findProgram("ffmpeg");
    if (missing) {
      logNote(strCat("frames ", first, "..", last, " are in ", framesDir, "; ", missing, " of ", frames,
                     " frames are still to render (other --frames slices); run this command again without "
                     "--frames to render what is missing and encode ",
                     o.output));
    } else if (ffmpeg.empty()) {
      logWarning(strCat("ffmpeg is not installed, so ", o.output, " was not encoded; the ", frames, " frames are in ",
                        framesDir, ". Install ffmpeg and run this command again, or encode them with: ", example));
    } else {
      const std::string temporary = strCat(o.output, ".encoding-", ::getpid(), ext);
      std::vector<std::string> args{ffmpeg,  "-y", "-loglevel", "error", "-framerate",
                                    fpsText, "-i", pattern,     "-vf",   "pad=ceil(iw/2)*2:ceil(ih/2)*2"};
      if (webm)
        args.insert(args.end(), {"-c:v", "libvpx-vp9", "-b:v", "0", "-crf", "32", "-pix_fmt", "yuv420p", "-f", "webm"});
      else
        args.insert(args.end(),
                    {"-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", "18", "-movflags", "+faststart", "-f", "mp4"});
      args.push_back(temporary);
      const int rc = runProgram(args);
      std::error_code ec;
      if (rc != 0) {
        fs::remove(temporary, ec);
        fail(o.output, ": ffmpeg failed (exit status ", rc, "); the frames are in ", framesDir, "; try: ", example);
      }
      fs::rename(temporary, o.output, ec);
      if (ec) {
        fs::remove(temporary, ec);
        fail(o.output, ": cannot move the encoded movie into place: ", ec.message());
      }
      encoded = o.output;
      logInfo(strCat("encoded ", frames, " frames into ", o.output));
    }
  }

  if (o.json) {
    nlohmann::json j{{"frames", frames},
                     {"rendered", done},
                     {"first", first},
                     {"last", last},
                     {"steps", steps},
                     {"steps_loaded", loadedSteps},
                     {"steps_reused", reusedSteps},
                     {"frames_dir", framesDir},
                     {"output", encoded},
                     {"missing_frames", missing},
                     {"seconds", total.seconds()},
                     {"render_seconds", renderSeconds},
                     {"load_seconds", loadSeconds},
                     {"load_wait_seconds", waitSeconds},
                     {"prefetch", !o.noPrefetch},
                     {"reuse", reuse}};
    std::cout << j.dump(2) << "\n";
  }
}

} // namespace

void addMovie(CLI::App& app) {
  auto o = std::make_shared<MovieCmdOptions>();
  CLI::App* cmd = app.add_subcommand("movie", "Render a time series and/or a camera path to a movie");
  o->scene.add(*cmd);
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
