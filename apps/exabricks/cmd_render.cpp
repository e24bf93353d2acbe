// exabricks render: volume rendering of an AMR field to PNG (and optionally PFM).
#include "commands.h"
#include "common.h"

#include "exabricks/core/log.h"
#include "exabricks/io/image.h"
#include "exabricks/render/renderer.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <unistd.h>

namespace exa::cli {
namespace {

struct RenderCmdOptions {
  InputOptions in;
  std::string output;
  std::string floatOutput;
  std::string size = "800x800";
  int spp = 1;
  float rate = 1.f;
  uint64_t seed = 0;
  bool noJitter = false;
  std::string colormap = "viridis";
  std::string tfFile;
  std::vector<float> opacity;       ///< x0 a0 x1 a1 ... in normalised value
  float opacityScale = 0.f;         ///< 0: chosen from the dataset's size
  std::vector<float> range;
  bool logScale = false;
  std::vector<double> position, lookAt, up;
  double fov = 40.0;
  bool ortho = false;
  double azimuth = 30.0, elevation = 25.0;
  std::vector<float> background{1.f, 1.f, 1.f};
  bool alpha = false;
  std::string shading = "analytic";
  std::string light = "headlight";
  std::string traversal = "auto";
  bool noSkip = false;
  bool noEarlyTermination = false;
  std::string sampling = "adaptive";
  std::string reconstruction = "regions";
  std::string debug = "none";
  bool stats = false;
  bool json = false;
  int frames = 1;
};

template <typename T> T pick(const std::string& what, const std::string& value,
                             std::initializer_list<std::pair<const char*, T>> choices) {
  std::string names;
  for (const auto& [name, v] : choices) {
    if (value == name) return v;
    names += (names.empty() ? "" : ", ") + std::string(name);
  }
  fail("unknown ", what, " '", value, "' (choose from: ", names, ")");
}

vec3d toVec(const std::vector<double>& v, const char* what) {
  if (v.size() != 3) fail(what, " needs three numbers x,y,z");
  return {v[0], v[1], v[2]};
}

void parseSize(const std::string& s, int& w, int& h) {
  char x = 0;
  std::istringstream in(s);
  if (!(in >> w >> x >> h) || x != 'x' || !in.eof() || w < 1 || h < 1 || w > 32768 || h > 32768)
    fail("--size expects WIDTHxHEIGHT with each in 1..32768, got '", s, "'");
}

TransferFunction makeTransferFunction(const RenderCmdOptions& o, const Model& model) {
  TransferFunction tf;
  if (!o.tfFile.empty()) {
    tf = readTransferFunction(o.tfFile);
  } else {
    tf.colorMap = builtinColorMap(o.colormap);
  }
  if (!o.opacity.empty()) {
    if (o.opacity.size() % 2 != 0 || o.opacity.size() < 2)
      fail("--opacity expects pairs 'x,alpha' of normalised value and opacity");
    tf.opacity.clear();
    for (size_t i = 0; i < o.opacity.size(); i += 2) {
      if (!(o.opacity[i] >= 0.f && o.opacity[i] <= 1.f && o.opacity[i + 1] >= 0.f && o.opacity[i + 1] <= 1.f))
        fail("--opacity values must lie in [0, 1]");
      if (i > 0 && !(o.opacity[i] > o.opacity[i - 2])) fail("--opacity positions must increase");
      tf.opacity.push_back({o.opacity[i], o.opacity[i + 1]});
    }
  }
  if (!o.range.empty()) {
    if (o.range.size() != 2 || !(o.range[0] < o.range[1])) fail("--range expects LOW,HIGH with LOW < HIGH");
    tf.valueRange = range1f{o.range[0], o.range[1]};
  }
  if (o.logScale) tf.logScale = true;
  if (o.opacityScale > 0.f) {
    tf.opacityScale = o.opacityScale;
  } else if (o.tfFile.empty()) {
    // Opacity is per finest cell: by default a ray through the whole dataset at full opacity
    // gathers an optical depth of about eight.
    const box3i b = model.cellBounds();
    int finest = kMaxLevel;
    for (const Brick& br : model.bricks) finest = std::min(finest, br.level);
    const float extentCells = float(reduceMax(b.size())) / float(1 << finest);
    tf.opacityScale = std::min(1.f, 8.f / std::max(1.f, extentCells));
  }
  return tf;
}

void run(const RenderCmdOptions& o) {
  RenderOptions ro;
  parseSize(o.size, ro.width, ro.height);
  if (o.spp < 1 || o.spp > 65536) fail("--spp must be in 1..65536");
  if (o.frames < 1 || o.frames > 1000) fail("--frames must be in 1..1000");
  ro.samplesPerPixel = o.spp;
  ro.rate = o.rate;
  ro.seed = o.seed;
  ro.jitter = !o.noJitter;
  ro.shading = pick<Shading>("shading", o.shading,
                             {{"analytic", Shading::Analytic}, {"central", Shading::Central},
                              {"clamped", Shading::ClampedCentral}, {"none", Shading::None}});
  ro.autoTraversal = o.traversal == "auto";
  if (!ro.autoTraversal)
    ro.traversal = pick<TraversalKind>("traversal", o.traversal,
                                       {{"kd", TraversalKind::KdTree}, {"embree", TraversalKind::Embree}});
  ro.sampling = pick<Sampling>("sampling", o.sampling, {{"adaptive", Sampling::Adaptive}, {"fixed", Sampling::Fixed}});
  ro.reconstruction = pick<Reconstruction>("reconstruction", o.reconstruction,
                                           {{"regions", Reconstruction::Regions},
                                            {"cells", Reconstruction::CellLocation}});
  ro.debug = pick<DebugView>("debug view", o.debug,
                             {{"none", DebugView::None}, {"level", DebugView::Level}, {"brick", DebugView::Brick},
                              {"region", DebugView::Region}, {"steps", DebugView::Steps}});
  if (o.light != "headlight") {
    std::vector<float> d;
    std::istringstream in(o.light);
    for (std::string part; std::getline(in, part, ',');) {
      try {
        d.push_back(std::stof(part));
      } catch (...) {
        fail("--light expects 'headlight' or a direction x,y,z, got '", o.light, "'");
      }
    }
    if (d.size() != 3 || (d[0] == 0 && d[1] == 0 && d[2] == 0))
      fail("--light expects 'headlight' or a non-zero direction x,y,z");
    ro.headlight = false;
    ro.lightDirection = vec3f(d[0], d[1], d[2]);
  }
  ro.spaceSkipping = !o.noSkip;
  ro.earlyTermination = !o.noEarlyTermination;
  ro.progress = logLevel() >= LogLevel::Warning && isatty(STDERR_FILENO) && !o.json;
  if (o.background.size() != 3) fail("--background expects r,g,b (sRGB, 0..1)");
  for (float c : o.background)
    if (!(c >= 0.f && c <= 1.f)) fail("--background components must lie in [0, 1]");

  Timer loadTimer;
  const Model model = loadModel(o.in.input, o.in.loadOptions(true));
  const double loadSeconds = loadTimer.seconds();
  const int field = model.requireField(o.in.field);
  const TransferFunction tf = makeTransferFunction(o, model);

  Renderer renderer(model, field, ro);
  const double updateSeconds = renderer.setTransferFunction(tf);

  const box3i cb = model.cellBounds();
  const box3d worldBox(model.world.toWorld(vec3d(cb.lower)), model.world.toWorld(vec3d(cb.upper)));
  Camera camera = Camera::frame(worldBox, o.azimuth, o.elevation, o.fov, o.ortho);
  if (!o.position.empty()) camera.position = toVec(o.position, "--position");
  if (!o.lookAt.empty()) camera.lookAt = toVec(o.lookAt, "--look-at");
  if (!o.up.empty()) camera.up = toVec(o.up, "--up");
  if (!(o.fov > 0 && o.fov < 180)) fail("--fov must be in (0, 180) degrees");
  const vec3d forward = camera.lookAt - camera.position;
  if (length(forward) == 0 || length(cross(forward, camera.up)) == 0)
    fail("degenerate camera: position equals look-at, or up is parallel to the view direction");

  RenderStats stats;
  Image image;
  std::vector<double> frameSeconds;
  if (o.stats) {
    RenderStats warm;
    renderer.render(camera, &warm); // warm-up, not counted
    for (int f = 0; f < o.frames; ++f) {
      image = renderer.render(camera, &stats);
      frameSeconds.push_back(stats.seconds);
    }
    std::sort(frameSeconds.begin(), frameSeconds.end());
    stats.seconds = frameSeconds[frameSeconds.size() / 2];
  } else {
    image = renderer.render(camera, &stats);
  }
  const vec3f bg(srgbToLinear(o.background[0]), srgbToLinear(o.background[1]), srgbToLinear(o.background[2]));
  writePng(o.output, image, o.alpha, bg);
  if (!o.floatOutput.empty()) writePfm(o.floatOutput, image, bg);
  logInfo(strCat("wrote ", o.output));

  if (o.json) {
    nlohmann::json j;
    j["output"] = o.output;
    j["width"] = ro.width;
    j["height"] = ro.height;
    j["samples_per_pixel"] = ro.samplesPerPixel;
    j["frame_seconds"] = stats.seconds;
    j["frames"] = frameSeconds.empty() ? 1 : frameSeconds.size();
    j["rays"] = stats.rays;
    j["samples"] = stats.samples;
    j["regions_visited"] = stats.regionsVisited;
    j["samples_per_second"] = stats.samplesPerSecond();
    j["visible_regions"] = renderer.visibleRegions();
    j["regions"] = model.regions.regions.size();
    j["transfer_function_update_seconds"] = updateSeconds;
    j["load_seconds"] = loadSeconds;
    j["traversal"] = renderer.traversalInUse() == TraversalKind::Embree ? "embree" : "kd";
    std::cout << j.dump(2) << "\n";
  } else if (o.stats) {
    std::printf("frame time       %.4f s (median of %d after one warm-up)\n", stats.seconds, o.frames);
    std::printf("rays             %llu\n", (unsigned long long)stats.rays);
    std::printf("samples          %llu (%.2f per ray)\n", (unsigned long long)stats.samples,
                double(stats.samples) / double(std::max<uint64_t>(stats.rays, 1)));
    std::printf("regions visited  %llu (%.2f per ray)\n", (unsigned long long)stats.regionsVisited,
                double(stats.regionsVisited) / double(std::max<uint64_t>(stats.rays, 1)));
    std::printf("samples/s        %.3fM\n", stats.samplesPerSecond() / 1e6);
    std::printf("visible regions  %zu of %zu (transfer function update %.4f s)\n", renderer.visibleRegions(),
                model.regions.regions.size(), updateSeconds);
    std::printf("traversal        %s\n", renderer.traversalInUse() == TraversalKind::Embree ? "embree" : "kd-tree");
    std::printf("load + build     %.3f s\n", loadSeconds);
  }
}

} // namespace

void addRender(CLI::App& app) {
  auto o = std::make_shared<RenderCmdOptions>();
  CLI::App* cmd = app.add_subcommand("render", "Volume-render a field to a PNG image");
  o->in.add(*cmd);
  cmd->add_option("-o,--output", o->output, "PNG file to write")->required();
  cmd->add_option("--float", o->floatOutput, "Also write the float image as PFM");
  cmd->add_option("--size", o->size, "Image size WIDTHxHEIGHT")->capture_default_str();
  cmd->add_option("--spp", o->spp, "Jittered samples per pixel, accumulated")->capture_default_str();
  cmd->add_option("--rate", o->rate, "Quality factor: samples per half finest cell width")->capture_default_str();
  cmd->add_option("--seed", o->seed, "Seed of the per-pixel jitter")->capture_default_str();
  cmd->add_flag("--no-jitter", o->noJitter, "Sample every ray at the same offsets");
  cmd->add_option("--colormap", o->colormap, "Built-in colour map")->capture_default_str();
  cmd->add_option("--tf", o->tfFile, "Transfer function file (ParaView preset or exabricks JSON)");
  cmd->add_option("--opacity", o->opacity, "Opacity points x,alpha,... over the normalised value")->delimiter(',');
  cmd->add_option("--opacity-scale", o->opacityScale, "Multiplies the opacity (default: from the dataset size)");
  cmd->add_option("--range", o->range, "Value range LOW,HIGH mapped by the transfer function")->delimiter(',');
  cmd->add_flag("--log", o->logScale, "Map values logarithmically");
  cmd->add_option("--position", o->position, "Camera position x,y,z (world)")->delimiter(',');
  cmd->add_option("--look-at", o->lookAt, "Camera target x,y,z (world)")->delimiter(',');
  cmd->add_option("--up", o->up, "Camera up vector x,y,z")->delimiter(',');
  cmd->add_option("--fov", o->fov, "Vertical field of view in degrees")->capture_default_str();
  cmd->add_flag("--ortho", o->ortho, "Orthographic projection");
  cmd->add_option("--azimuth", o->azimuth, "Default view: degrees around +z")->capture_default_str();
  cmd->add_option("--elevation", o->elevation, "Default view: degrees above the x-y plane")->capture_default_str();
  cmd->add_option("--background", o->background, "Background colour r,g,b (sRGB, 0..1)")->delimiter(',');
  cmd->add_flag("--alpha", o->alpha, "Keep the alpha channel instead of a background");
  cmd->add_option("--shading", o->shading, "analytic, central, clamped or none")->capture_default_str();
  cmd->add_option("--light", o->light, "headlight, or the direction x,y,z light travels")->capture_default_str();
  cmd->add_option("--traversal", o->traversal, "Region traversal: auto, kd or embree")->capture_default_str();
  cmd->add_flag("--no-skip", o->noSkip, "Disable space skipping");
  cmd->add_flag("--no-early-termination", o->noEarlyTermination, "Integrate every ray to its end");
  cmd->add_option("--sampling", o->sampling, "adaptive (per region) or fixed (finest width everywhere)")
      ->capture_default_str();
  cmd->add_option("--reconstruction", o->reconstruction,
                  "regions (bricks listed by the sample's region) or cells (baseline: locate every cell)")
      ->capture_default_str();
  cmd->add_option("--debug", o->debug, "Debug view: level, brick, region or steps")->capture_default_str();
  cmd->add_flag("--stats", o->stats, "Time the frame after a warm-up and print statistics");
  cmd->add_option("--frames", o->frames, "Frames to time with --stats (median)")->capture_default_str();
  cmd->add_flag("--json", o->json, "Print statistics as one JSON object on stdout");
  const std::function<void()> writeScene = addSceneFile(app, *cmd);
  cmd->callback([o, writeScene] {
    writeScene();
    run(*o);
  });
}

} // namespace exa::cli
