// exabricks render: volume rendering of an AMR field to PNG or JPEG (and optionally PFM).
#include "commands.h"
#include "common.h"
#include "mpi/data_parallel.h"
#include "mpi/processes.h"
#include "scene_options.h"

#include "exabricks/amr/basis_batch.h"
#include "exabricks/core/files.h"
#include "exabricks/core/log.h"
#include "exabricks/core/text.h"
#include "exabricks/documents/image.h"
#include "exabricks/documents/scene_file.h"
#include "exabricks/render/defaults.h"
#include "exabricks/render/denoise.h"
#include "exabricks/render/renderer.h"
#include "exabricks/render/scene_vocabulary.h"
#include "exabricks/workflows/streamed.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>

namespace exa::cli {
namespace {

struct RenderCmdOptions {
  RenderOptions scene;
  MarchFlags march;
  std::string output;
  std::string floatOutput;
  int bits = 8;
  bool stats = false;
  bool json = false;
  int frames = 1;
  std::string writeScene;
  std::string distribute = "image";
};

/// What a render measured, for --json and --stats.
struct RenderReport {
  RenderStats stats;
  size_t frames = 1; ///< timed frames (the median's)
  SceneUpdate update;
  double loadSeconds = 0;
  double meanPasses = 0; ///< samples per pixel taken, averaged (below the count with a noise target)
  Image image;           ///< the frame (on the root): the passes' mean, or denoised
  bool denoised = false;
  double guideSeconds = 0, filterSeconds = 0; ///< a denoised frame's guide and filter (in its seconds)
  bool dataParallel = false, part = false;
  std::vector<double> partCells, partRss; ///< per process, where several render
};

/// The samples per pixel a frame took, averaged; said where a noise target chose them.
double noteSamplesTaken(const Scene& scene, const Frame& frame, const FrameBuffer& buffer) {
  const double mean = buffer.meanPasses();
  if (NoiseRounds::applies(scene, frame))
    logNote(strCat("noise target ", frame.noiseTarget, "/255: ", std::round(mean * 10) / 10,
                   " samples per pixel on average (", frame.samplesPerPixel, " at most)"));
  return mean;
}

/// Renders the frame into the buffer (samplesPerPixel passes, with its progress: Progress) and
/// its image into the report (denoised where the frame asks: the guide, the passes to the
/// denoised picture's noise target, the filter, all in the frame's seconds); with --stats, a
/// warm-up and then --frames timed frames, their median kept.
void renderTimed(const RenderCmdOptions& o, Renderer& renderer, const Frame& frame, FrameBuffer& buffer,
                 bool dataParallel, const std::vector<int>& order, RenderReport& report) {
  const bool showProgress = logLevel() >= LogLevel::Warning;
  const bool root = mpi::processes().root();
  auto renderFrame = [&]() {
    Timer whole;
    std::optional<DenoiseGuide> guide;
    std::optional<TileNoiseEstimate> estimate;
    Image measured; // one process's rounds to a noise target end with their picture
    const bool alone = mpi::processes().size == 1;
    if (!dataParallel && denoises(renderer.scene(), frame)) {
      guide = renderDenoiseGuide(renderer, frame);
      estimate = mpi::wholeImage(denoisedNoise(*guide, renderer.scene().background, alone ? &measured : nullptr));
    }
    buffer.clear();
    const uint64_t share = dataParallel ? 1 : uint64_t(mpi::processes().size);
    Progress progress("rendering",
                      (uint64_t(buffer.tileCount()) + share - 1) / share * uint64_t(frame.samplesPerPixel));
    if (!showProgress) progress.finish();
    PassControl control;
    control.progress = [&](uint64_t, uint64_t) { progress.advance(1); };
    control.planned = [&](uint64_t passes) { progress.setTotal(passes); };
    if (dataParallel)
      mpi::renderFrameComposited(&renderer, frame, buffer, order, control);
    else
      mpi::renderFrame(renderer, frame, buffer, control, estimate ? &*estimate : nullptr);
    progress.finish();
    RenderStats stats = buffer.stats();
    report.denoised = guide.has_value();
    if (guide) {
      Timer filter;
      if (alone && NoiseRounds::applies(renderer.scene(), frame))
        report.image = std::move(measured);
      else if (root)
        report.image = denoise(buffer, *guide, renderer.scene().background);
      report.guideSeconds = guide->seconds;
      report.filterSeconds = filter.seconds();
      stats.seconds = whole.seconds();
    } else if (root) {
      report.image = buffer.resolve();
    }
    return stats;
  };
  if (!o.stats) {
    report.stats = renderFrame();
    if (root) report.meanPasses = noteSamplesTaken(renderer.scene(), frame, buffer);
    return;
  }
  renderFrame(); // warm-up, not counted
  std::vector<double> frameSeconds;
  for (int f = 0; f < o.frames; ++f) {
    report.stats = renderFrame();
    frameSeconds.push_back(report.stats.seconds);
  }
  std::sort(frameSeconds.begin(), frameSeconds.end());
  report.stats.seconds = frameSeconds[frameSeconds.size() / 2];
  report.frames = frameSeconds.size();
  report.meanPasses = buffer.meanPasses();
}

/// The statistics as one JSON object on stdout.
void printJson(const RenderCmdOptions& o, const Frame& frame, const Renderer& renderer, const Model& model,
               const RenderReport& r) {
  nlohmann::json j;
  j["output"] = o.output;
  j["width"] = frame.width;
  j["height"] = frame.height;
  j["samples_per_pixel"] = frame.samplesPerPixel;
  j["noise_target"] = frame.noiseTarget;
  j["mean_samples_per_pixel"] = r.meanPasses;
  j["denoised"] = r.denoised;
  if (r.denoised) j["denoise_seconds"] = {{"guide", r.guideSeconds}, {"filter", r.filterSeconds}};
  j["frame_seconds"] = r.stats.seconds;
  j["frames"] = r.frames;
  j["rays"] = r.stats.rays;
  j["samples"] = r.stats.samples;
  j["regions_visited"] = r.stats.regionsVisited;
  j["samples_per_second"] = r.stats.samplesPerSecond();
  j["visible_regions"] = renderer.visibleRegions();
  j["regions"] = model.regions.regions.size();
  j["transfer_function_update_seconds"] = r.update.volumeSeconds;
  j["load_seconds"] = r.loadSeconds;
  j["traversal"] = nameOf(renderer.traversalInUse());
  j["simd"] = renderer.options().vectorized ? batchTargetName() : "off";
  j["surface_hits"] = r.stats.surfaceHits;
  j["iso_samples"] = r.stats.isoSamples;
  j["ao_rays"] = r.stats.aoRays;
  j["iso_regions"] = renderer.isoRegions();
  j["iso_update_seconds"] = r.update.isoSeconds;
  j["meshes"] = renderer.meshCount();
  j["device"] = deviceJson(renderer);
  j["device_upload_seconds"] = r.update.deviceSeconds;
  if (mpi::processes().size > 1 || r.part) {
    j["processes"] = mpi::processes().size;
    j["distribute"] = o.distribute;
    j["composite_seconds"] = mpi::lastCombineSeconds();
    if (r.dataParallel) j["composite_wait_seconds"] = mpi::lastWaitSeconds();
  }
  if (!r.partCells.empty()) {
    nlohmann::json ranks = nlohmann::json::array();
    for (size_t k = 0; k < r.partCells.size(); ++k)
      ranks.push_back(
          {{"rank", k}, {"resident_cells", uint64_t(r.partCells[k])}, {"peak_rss_bytes", uint64_t(r.partRss[k])}});
    j["ranks"] = ranks;
  }
  std::cout << j.dump(2) << "\n";
}

/// The statistics as text on stdout.
void printStats(const RenderCmdOptions& o, const Scene& scene, const Renderer& renderer, const Model& model,
                const RenderReport& r) {
  std::printf("frame time       %.4f s (median of %d after one warm-up)\n", r.stats.seconds, o.frames);
  if (r.denoised)
    std::printf("denoised         guide %.4f s, filter %.4f s (in the frame time)\n", r.guideSeconds, r.filterSeconds);
  std::printf("rays             %llu\n", (unsigned long long)r.stats.rays);
  std::printf("samples          %llu (%.2f per ray)\n", (unsigned long long)r.stats.samples,
              double(r.stats.samples) / double(std::max<uint64_t>(r.stats.rays, 1)));
  std::printf("regions visited  %llu (%.2f per ray)\n", (unsigned long long)r.stats.regionsVisited,
              double(r.stats.regionsVisited) / double(std::max<uint64_t>(r.stats.rays, 1)));
  std::printf("samples/s        %.3fM\n", r.stats.samplesPerSecond() / 1e6);
  std::printf("visible regions  %zu of %zu (transfer function update %.4f s)\n", renderer.visibleRegions(),
              model.regions.regions.size(), r.update.volumeSeconds);
  std::printf("traversal        %s\n", renderer.traversalInUse() == TraversalKind::Embree ? "embree" : "kd-tree");
  if (renderer.device() != Device::Cpu) {
    const DeviceMemory memory = renderer.deviceMemory();
    std::printf("device           %s%s, %.1f MiB held, copied in %.4f s\n", deviceName(renderer.device()),
                renderer.device() == Device::Cuda ? (" (" + cudaStatus().name + ")").c_str() : "",
                double(memory.total()) / 1048576.0, r.update.deviceSeconds);
  }
  if (!scene.iso.values.empty())
    std::printf("iso regions      %zu of %zu (built in %.4f s), %llu iso samples\n", renderer.isoRegions(),
                model.regions.regions.size(), r.update.isoSeconds, (unsigned long long)r.stats.isoSamples);
  if (!scene.iso.values.empty() || !scene.meshes.empty())
    std::printf("surface hits     %llu, ambient occlusion rays %llu\n", (unsigned long long)r.stats.surfaceHits,
                (unsigned long long)r.stats.aoRays);
  std::printf("load + build     %.3f s\n", r.loadSeconds);
}

/// Writes the image of a render: legends, the empty-image warning, the outputs.
void writeOutputs(const RenderCmdOptions& o, const SceneDocument& doc, Image image, const Model& model,
                  const DatasetInfo& dataset, const WholeData* whole, size_t visibleRegions, size_t regions) {
  const ImageFormat format = imageFormatFor(o.output, o.bits);
  drawLegends(doc.scene, doc.frame, model, dataset, legendText(doc.input, whole), image);
  if (imageIsEmpty(image))
    logWarning(strCat("the image is empty: nothing in view is visible (", visibleRegions, " of ", regions,
                      " regions may be; check --range, --opacity and the camera)"));
  writeImage(o.output, image, format, doc.scene.keepAlpha, doc.scene.background);
  if (!o.floatOutput.empty()) writePfm(o.floatOutput, image, doc.scene.background);
  logInfo(strCat("wrote ", o.output));
}

/// A step larger than the budget: read and drawn part by part, front to back, one part (or as
/// many as fit) resident at a time.
void runStreamed(const RenderCmdOptions& o, const CLI::App& cmd, SceneDocument& doc, const LoadOptions& lo,
                 MemoryPlan plan) {
  Timer loadTimer;
  if (o.march.device != "auto" && o.march.device != "cpu")
    failUsage("--memory-budget draws on the CPU; --device ", o.march.device, " holds the whole step");
  logInfo(strCat("memory budget ", formatBytes(plan.budget), ": ", plan.partition.parts(), " parts of at most ",
                 formatBytes(plan.largestPartBytes()), " each, besides ", formatBytes(plan.fixedBytes)));
  StreamedStep step(doc.input, lo, std::move(plan));
  step.setParticles(particlesFor(doc.scene, doc.input));
  Scene& scene = doc.scene;
  Frame& frame = doc.frame;
  // Automatic choices and a layer without a range of its own need the values of every part: a
  // pass over the parts before the frame. Otherwise the census's outline serves until the
  // frame's own reads have gathered the survey, and the scene's warnings follow the frame.
  const bool surveyFirst = choosesTransferFunction(o.scene) || step.needsSurvey(scene);
  const StepSurvey& early = surveyFirst ? step.survey() : *step.outline();
  WholeData whole{early.cellBounds, early.levels, step.partialData()};
  const Model& model = step.skeleton();
  applyDataDefaults(o.scene, cmd, scene, model, early.dataset, &whole, surveyFirst);
  const RendererOptions options = o.march.options();
  // Each part is read to find what is visible only where the camera frames it.
  const box3d visible = framesVisibleData(o.scene, cmd, doc) ? step.visibleBounds(scene, options) : box3d();
  frame.camera = cameraFromOptions(o.scene, cmd, doc, model, visible, &whole);
  frame.validate();
  doc.hasCamera = true;
  const double loadSeconds = loadTimer.seconds();
  if (!o.writeScene.empty()) writeSceneFile(o.writeScene, withAbsolutePaths(doc));

  FrameBuffer buffer(frame.width, frame.height);
  Timer renderTimer;
  Progress progress("rendering",
                    uint64_t(step.parts()) * uint64_t(buffer.tileCount()) * uint64_t(frame.samplesPerPixel));
  if (logLevel() < LogLevel::Warning) progress.finish();
  PassControl control;
  control.progress = [&](uint64_t, uint64_t) { progress.advance(1); };
  renderStreamed(step, scene, options, frame, buffer, control);
  progress.finish();
  const double renderSeconds = renderTimer.seconds();
  const StepSurvey& survey = step.survey(); // gathered by the frame's reads
  if (!surveyFirst)
    for (const std::string& w : sceneWarnings(scene, model, survey.dataset))
      logWarning(w);
  writeOutputs(o, doc, buffer.resolve(), model, survey.dataset, &whole, 0, 0);
  const RenderStats& stats = buffer.stats();
  if (o.json) {
    nlohmann::json j;
    j["output"] = o.output;
    j["width"] = frame.width;
    j["height"] = frame.height;
    j["samples_per_pixel"] = frame.samplesPerPixel;
    j["frame_seconds"] = renderSeconds;
    j["rays"] = stats.rays;
    j["samples"] = stats.samples;
    j["load_seconds"] = loadSeconds;
    j["memory"] = {{"budget_bytes", step.plan().budget},
                   {"parts", step.parts()},
                   {"parts_read", step.partsRead()},
                   {"resident_parts", step.residentParts()},
                   {"resident_bytes_estimate", step.residentBytes()},
                   {"cells", survey.cells},
                   {"peak_rss_bytes", peakResidentBytes()}};
    std::cout << j.dump(2) << "\n";
  } else if (o.stats) {
    std::printf("frame time       %.4f s (%d parts, %llu read)\n", renderSeconds, step.parts(),
                (unsigned long long)step.partsRead());
    std::printf("samples          %llu\n", (unsigned long long)stats.samples);
    std::printf("load + survey    %.3f s\n", loadSeconds);
    std::printf("peak memory      %s of a %s budget\n", formatBytes(peakResidentBytes()).c_str(),
                formatBytes(step.plan().budget).c_str());
  }
}

/// Spheres sized in pixels wait for the camera, which frames what the first scene shows (volume
/// and iso-surfaces): the first scene holds them back, and they are built once, when it is known.
bool spheresInPixels(const Scene& scene) { return scene.particles.show && scene.particles.radiusPixels > 0.f; }

void sizeSpheresInPixels(Renderer& renderer, const Scene& scene, const Frame& frame) {
  if (!spheresInPixels(scene)) return;
  Scene placed = scene;
  resolveParticleRadius(placed, frame);
  renderer.setScene(placed);
}

void run(const RenderCmdOptions& o, const CLI::App& cmd) {
  if (o.frames < 1 || o.frames > 1000) failUsage("--frames must be in 1..1000");
  const ImageFormat format = imageFormatFor(o.output, o.bits);
  checkOutputFolder(o.output);
  if (!formatKeepsAlpha(format) && cmd.count("--alpha"))
    failUsage("--alpha needs a PNG or OpenEXR output (", o.output, " has no alpha channel)");
  SceneDocument doc = sceneFromOptions(o.scene, cmd);
  Scene& scene = doc.scene;
  Frame& frame = doc.frame;

  if (o.distribute != "image" && o.distribute != "data")
    failUsage("--distribute must be image or data, not '", o.distribute, "'");
  const bool dataParallel = o.distribute == "data";
  Timer loadTimer;
  LoadOptions lo = o.scene.in.loadOptions(false);
  lo.fields = neededFields(scene);
  if (std::optional<MemoryPlan> plan =
          memoryPlanFor(o.scene.in, doc.input, lo, streamedFrameBytes(frame.width, frame.height, frame.samplesPerPixel),
                        dataParallel || mpi::processes().size > 1))
    return runStreamed(o, cmd, doc, lo, std::move(*plan));
  // Image-parallel (and one process): every process holds the whole model. Data-parallel: each
  // holds its part and the halo. If one process cannot read its data, all of them stop with an
  // error instead of waiting for it.
  std::optional<Model> loaded;
  std::optional<mpi::DataPart> part;
  if (dataParallel) {
    part.emplace(mpi::loadDataPart(doc.input, lo));
  } else {
    mpi::onEveryProcess("read the input", [&] { loaded.emplace(loadModel(doc.input, lo)); });
  }
  const Model& model = part ? part->model : *loaded;
  const WholeData* whole = part ? &part->whole : nullptr;
  const bool root = mpi::processes().root();
  const double loadSeconds = loadTimer.seconds();
  const DatasetInfo dataset = part ? part->dataset : DatasetInfo::of(model);
  applyDataDefaults(o.scene, cmd, scene, model, dataset, whole);

  Renderer renderer(model, dataset);
  renderer.setOptions(o.march.options());
  if (part) renderer.setDomain(part->worldBox());
  renderer.setParticles(particlesFor(scene, doc.input));
  Scene first = scene;
  first.particles.show = first.particles.show && !spheresInPixels(scene);
  SceneUpdate update = renderer.setScene(first);
  {
    Timer upload;
    selectDevice(renderer, o.march.device);
    update.deviceSeconds += upload.seconds();
  }
  if (!scene.iso.values.empty())
    logInfo(strCat("iso-surface regions: ", renderer.isoRegions(), " of ", model.regions.regions.size(), ", built in ",
                   update.isoSeconds, " s"));
  frame.camera = cameraFromOptions(o.scene, cmd, doc, model,
                                   part ? mpi::agreedVisibleBounds(renderer, *part) : renderer.visibleBounds(), whole);
  frame.validate();
  sizeSpheresInPixels(renderer, scene, frame);
  const std::vector<int> order = part ? part->order(frame.camera) : std::vector<int>();
  doc.hasCamera = true;
  if (!o.writeScene.empty() && root) writeSceneFile(o.writeScene, withAbsolutePaths(doc));

  FrameBuffer buffer(frame.width, frame.height);
  RenderReport report;
  report.update = update;
  report.loadSeconds = loadSeconds;
  report.dataParallel = dataParallel;
  report.part = part.has_value();
  renderTimed(o, renderer, frame, buffer, dataParallel, order, report);
  // What each process holds, for the statistics (collectives: every process takes part).
  if (part || mpi::processes().size > 1) {
    report.partCells = mpi::allGather(double(model.cellCount()));
    report.partRss = mpi::allGather(double(peakResidentBytes()));
  }
  if (!root) return; // the first process writes the image and the statistics
  writeOutputs(o, doc, std::move(report.image), model, dataset, whole, renderer.visibleRegions(),
               model.regions.regions.size());
  if (o.json)
    printJson(o, frame, renderer, model, report);
  else if (o.stats)
    printStats(o, scene, renderer, model, report);
}

} // namespace

void addRender(CLI::App& app) {
  auto o = std::make_shared<RenderCmdOptions>();
  CLI::App* cmd = app.add_subcommand("render", "Volume-render a field to a PNG or JPEG image");
  o->scene.add(*cmd);
  o->scene.in.addMemoryBudget(*cmd);
  o->march.add(*cmd);
  cmd->add_option("-o,--output", o->output,
                  "Image to write: .png, .jpg / .jpeg, .exr (linear, premultiplied alpha, 32-bit float) or .pfm")
      ->required();
  cmd->add_option("--bits", o->bits, "Bits per channel of a PNG output: 8 or 16")->capture_default_str();
  cmd->add_option("--float", o->floatOutput, "Also write the float image as PFM");
  cmd->add_flag("--stats", o->stats, "Time the frame after a warm-up and print statistics");
  cmd->add_option("--frames", o->frames, "Frames to time with --stats (median)")->capture_default_str();
  cmd->add_flag("--json", o->json, "Print statistics as one JSON object on stdout");
  cmd->add_option("--write-scene", o->writeScene, "Write the scene and frame in effect as a JSON scene file");
  cmd->add_option("--distribute", o->distribute,
                  "Under MPI: image (every process holds the data and renders a share of the tiles) or data "
                  "(each holds a part of the domain with its halo; images composited)")
      ->capture_default_str();
  cmd->callback([o, cmd] { run(*o, *cmd); });
}

} // namespace exa::cli
