// exabricks render: volume rendering of an AMR field to PNG (and optionally PFM).
#include "commands.h"
#include "common.h"

#include "exabricks/core/log.h"
#include "exabricks/io/image.h"
#include "exabricks/io/mesh.h"
#include "exabricks/io/scene_file.h"
#include "exabricks/render/defaults.h"
#include "exabricks/render/overlay.h"
#include "exabricks/render/renderer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
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
  bool linear = false;
  bool frameAll = false;
  bool colorbar = false;
  bool annotate = false;
  std::vector<double> position, lookAt, up;
  double fov = 40.0;
  bool ortho = false;
  double azimuth = 30.0, elevation = 25.0;
  std::vector<float> background{0.f, 0.f, 0.f};
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
  // Surfaces and effects.
  bool noVolume = false;
  std::vector<std::string> layers;   ///< FIELD=COLORMAP or FIELD=TF_FILE
  std::vector<float> iso;
  std::string isoField;
  std::vector<float> isoColor;       ///< sRGB triples, one per iso-value (cycled)
  std::string isoColorField;
  std::string isoColormap = "cool-to-warm";
  std::vector<float> isoColorRange;
  bool isoColorLog = false;
  std::vector<std::string> meshes;
  std::vector<float> meshColor;      ///< sRGB triples, one per mesh (cycled)
  std::vector<std::string> clipPlanes; ///< px,py,pz,nx,ny,nz each
  std::vector<double> clipBox;
  bool clipMeshes = false;
  int aoRays = 0;
  float aoLength = 0.f;
  bool aoVolume = false;
  std::string sceneFile;
  std::string writeScene;
};

template <typename T> T pick(const std::string& what, const std::string& value,
                             std::initializer_list<std::pair<const char*, T>> choices) {
  std::string names;
  for (const auto& [name, v] : choices) {
    if (value == name) return v;
    names += (names.empty() ? "" : ", ") + std::string(name);
  }
  failUsage("unknown ", what, " '", value, "' (choose from: ", names, ")");
}

vec3d toVec(const std::vector<double>& v, const char* what) {
  if (v.size() != 3) failUsage(what, " needs three numbers x,y,z");
  return {v[0], v[1], v[2]};
}

std::vector<double> parseNumbers(const std::string& text, const char* what) {
  std::vector<double> out;
  std::istringstream in(text);
  for (std::string part; std::getline(in, part, ',');) {
    size_t used = 0;
    double v = 0;
    try {
      v = std::stod(part, &used);
    } catch (...) {
      used = 0;
    }
    if (used == 0 || used != part.size() || !std::isfinite(v)) failUsage(what, ": '", part, "' is not a number");
    out.push_back(v);
  }
  return out;
}

/// sRGB triples -> linear-RGB colours.
std::vector<vec3f> colorList(const std::vector<float>& v, const char* what) {
  if (v.size() % 3 != 0) failUsage(what, " expects r,g,b triples (sRGB, 0..1)");
  std::vector<vec3f> out;
  for (size_t i = 0; i < v.size(); i += 3) {
    for (size_t k = 0; k < 3; ++k)
      if (!(v[i + k] >= 0.f && v[i + k] <= 1.f)) failUsage(what, " components must lie in [0, 1]");
    out.push_back({srgbToLinear(v[i]), srgbToLinear(v[i + 1]), srgbToLinear(v[i + 2])});
  }
  return out;
}

/// The options of one volume layer's transfer function, applied over `tf`: a file replaces
/// it, then every option that was given overrides its part.
TransferFunction applyTransferFunctionOptions(TransferFunction tf, const RenderCmdOptions& o, const std::string& tfFile,
                                              const std::string* colormap, bool withRange) {
  if (!tfFile.empty()) {
    bool preset = false;
    tf = readTransferFunction(tfFile, &preset);
    if (preset) {
      // As ParaView applies a preset: its points span the data's range (or --range), and its
      // opacity takes the default scale of built-in maps.
      tf.valueRange = range1f();
      tf.opacityScale = 0.f;
    }
  }
  if (colormap) tf.colorMap = builtinColorMap(*colormap);
  if (!o.opacity.empty()) {
    if (o.opacity.size() % 2 != 0 || o.opacity.size() < 2)
      failUsage("--opacity expects pairs 'x,alpha' of normalised value and opacity");
    tf.opacity.clear();
    for (size_t i = 0; i < o.opacity.size(); i += 2) {
      if (!(o.opacity[i] >= 0.f && o.opacity[i] <= 1.f && o.opacity[i + 1] >= 0.f && o.opacity[i + 1] <= 1.f))
        failUsage("--opacity values must lie in [0, 1]");
      if (i > 0 && !(o.opacity[i] > o.opacity[i - 2])) failUsage("--opacity positions must increase");
      tf.opacity.push_back({o.opacity[i], o.opacity[i + 1]});
    }
  }
  if (withRange && !o.range.empty()) {
    if (o.range.size() != 2 || !(o.range[0] < o.range[1])) failUsage("--range expects LOW,HIGH with LOW < HIGH");
    tf.valueRange = range1f{o.range[0], o.range[1]};
  }
  if (o.logScale) tf.logScale = true;
  if (o.opacityScale > 0.f) tf.opacityScale = o.opacityScale;
  return tf;
}

/// The scene and frame the options describe, over the scene file when one is given: without a
/// file every option applies (defaults included); with one, only the options given.
SceneDocument sceneFromOptions(const RenderCmdOptions& o, const CLI::App& cmd) {
  const bool fromFile = !o.sceneFile.empty();
  SceneDocument doc = fromFile ? readSceneFile(o.sceneFile) : SceneDocument();
  auto given = [&](const char* name) { return cmd.count(name) > 0; };
  auto apply = [&](const char* name) { return !fromFile || given(name); };
  Scene& s = doc.scene;
  Frame& f = doc.frame;
  if (!o.in.input.empty()) doc.input = o.in.input;

  if (apply("--size")) parseSize(o.size, f.width, f.height);
  if (apply("--spp")) {
    if (o.spp < 1 || o.spp > 65536) failUsage("--spp must be in 1..65536");
    f.samplesPerPixel = o.spp;
  }
  if (apply("--rate")) f.rate = o.rate;
  if (apply("--seed")) f.seed = o.seed;
  if (apply("--no-jitter")) f.jitter = !o.noJitter;

  // The first volume layer: the field and its transfer function.
  if (o.linear && o.logScale) failUsage("--log and --linear exclude each other");
  if (given("--opacity-scale") && !(o.opacityScale > 0.f && std::isfinite(o.opacityScale)))
    failUsage("--opacity-scale must be a positive number (leave it out for the dataset's default)");
  if (s.layers.empty()) s.layers.push_back(VolumeLayer{});
  VolumeLayer& first = s.layers[0];
  if (apply("--field")) first.field = o.in.field;
  const bool colormapGiven = given("--colormap") || (!fromFile && o.tfFile.empty());
  first.tf = applyTransferFunctionOptions(fromFile || !o.tfFile.empty() ? first.tf : defaultTransferFunction(),
                                          o, o.tfFile, colormapGiven ? &o.colormap : nullptr, true);
  if (apply("--layer")) {
    s.layers.resize(1);
    for (const std::string& spec : o.layers) {
      const size_t eq = spec.find('=');
      const std::string name = spec.substr(0, eq);
      if (name.empty()) failUsage("--layer expects FIELD or FIELD=COLORMAP or FIELD=TF_FILE, got '", spec, "'");
      std::string file, colormap = o.colormap;
      if (eq != std::string::npos) {
        const std::string what = spec.substr(eq + 1);
        if (std::ifstream(what).good())
          file = what;
        else
          colormap = what;
      }
      s.layers.push_back({name, applyTransferFunctionOptions(defaultTransferFunction(), o, file,
                                                             file.empty() ? &colormap : nullptr, false)});
    }
  }

  if (apply("--shading"))
    s.shading = pick<Shading>("shading", o.shading,
                              {{"analytic", Shading::Analytic}, {"central", Shading::Central},
                               {"clamped", Shading::ClampedCentral}, {"none", Shading::None}});
  Integration& in = s.integration;
  if (apply("--traversal")) {
    in.autoTraversal = o.traversal == "auto";
    if (!in.autoTraversal)
      in.traversal = pick<TraversalKind>("traversal", o.traversal,
                                         {{"kd", TraversalKind::KdTree}, {"embree", TraversalKind::Embree}});
  }
  if (apply("--sampling"))
    in.sampling = pick<Sampling>("sampling", o.sampling, {{"adaptive", Sampling::Adaptive}, {"fixed", Sampling::Fixed}});
  if (apply("--reconstruction"))
    in.reconstruction = pick<Reconstruction>("reconstruction", o.reconstruction,
                                             {{"regions", Reconstruction::Regions},
                                              {"cells", Reconstruction::CellLocation}});
  if (apply("--no-skip")) in.spaceSkipping = !o.noSkip;
  if (apply("--no-early-termination")) in.earlyTermination = !o.noEarlyTermination;
  if (apply("--debug"))
    s.debug = pick<DebugView>("debug view", o.debug,
                              {{"none", DebugView::None}, {"level", DebugView::Level}, {"brick", DebugView::Brick},
                               {"region", DebugView::Region}, {"steps", DebugView::Steps}});
  if (apply("--light")) {
    s.light.headlight = o.light == "headlight";
    if (!s.light.headlight) {
      std::vector<float> d;
      std::istringstream lin(o.light);
      for (std::string part; std::getline(lin, part, ',');) {
        try {
          d.push_back(std::stof(part));
        } catch (...) {
          failUsage("--light expects 'headlight' or a direction x,y,z, got '", o.light, "'");
        }
      }
      if (d.size() != 3 || (d[0] == 0 && d[1] == 0 && d[2] == 0))
        failUsage("--light expects 'headlight' or a non-zero direction x,y,z");
      s.light.direction = vec3f(d[0], d[1], d[2]);
    }
  }
  if (apply("--background")) {
    if (o.background.size() != 3) failUsage("--background expects r,g,b (sRGB, 0..1)");
    for (float c : o.background)
      if (!(c >= 0.f && c <= 1.f)) failUsage("--background components must lie in [0, 1]");
    s.background = srgbToLinear(vec3f(o.background[0], o.background[1], o.background[2]));
  }
  if (apply("--alpha")) s.keepAlpha = o.alpha;

  if (apply("--no-volume")) s.volume = !o.noVolume;
  if (apply("--clip-plane")) {
    s.clip.planes.clear();
    for (const std::string& text : o.clipPlanes) {
      const std::vector<double> v = parseNumbers(text, "--clip-plane");
      if (v.size() != 6 || (v[3] == 0 && v[4] == 0 && v[5] == 0))
        failUsage("--clip-plane expects px,py,pz,nx,ny,nz with a non-zero normal, got '", text, "'");
      s.clip.planes.push_back({vec3d(v[0], v[1], v[2]), vec3d(v[3], v[4], v[5])});
    }
  }
  if (apply("--clip-box")) {
    s.clip.box = box3d();
    if (!o.clipBox.empty()) {
      const auto& b = o.clipBox;
      if (b.size() != 6 || !(b[0] < b[3] && b[1] < b[4] && b[2] < b[5]))
        failUsage("--clip-box expects x0,y0,z0,x1,y1,z1 with the lower corner below the upper one");
      s.clip.box = box3d(vec3d(b[0], b[1], b[2]), vec3d(b[3], b[4], b[5]));
    }
  }
  if (apply("--clip-meshes")) s.clip.meshes = o.clipMeshes;
  if (apply("--ao")) {
    if (o.aoRays < 0 || o.aoRays > 1024) failUsage("--ao must be in 0..1024 rays");
    s.ao.rays = o.aoRays;
  }
  if (apply("--ao-length")) {
    if (!(o.aoLength >= 0.f)) failUsage("--ao-length must not be negative");
    s.ao.length = o.aoLength;
  }
  if (apply("--ao-volume")) s.ao.volume = o.aoVolume;

  // Iso-surfaces.
  if (!o.isoColorRange.empty() && (o.isoColorRange.size() != 2 || !(o.isoColorRange[0] < o.isoColorRange[1])))
    failUsage("--iso-color-range expects LOW,HIGH with LOW < HIGH");
  if (o.iso.empty() && !fromFile && (!o.isoField.empty() || !o.isoColorField.empty() || !o.isoColor.empty()))
    failUsage("iso-surface options need --iso VALUES");
  for (float v : o.iso)
    if (!std::isfinite(v)) failUsage("--iso values must be finite numbers");
  IsoSurfaces& iso = s.iso;
  if (apply("--iso")) iso.values = o.iso;
  if (apply("--iso-field")) iso.field = o.isoField.empty() ? o.in.field : o.isoField;
  if (apply("--iso-color")) iso.colors = colorList(o.isoColor, "--iso-color");
  if (apply("--iso-color-field")) iso.colorField = o.isoColorField;
  if (apply("--iso-colormap")) iso.colorTf.colorMap = builtinColorMap(o.isoColormap);
  if (apply("--iso-color-log")) iso.colorTf.logScale = o.isoColorLog;
  if (apply("--iso-color-range"))
    iso.colorTf.valueRange = o.isoColorRange.empty() ? range1f() : range1f{o.isoColorRange[0], o.isoColorRange[1]};

  // Meshes: read here, so that a bad mesh file fails before the (longer) model build.
  if (apply("--mesh") || apply("--mesh-color")) {
    const std::vector<vec3f> meshColors = colorList(o.meshColor, "--mesh-color");
    if (apply("--mesh")) {
      s.meshes.clear();
      for (const std::string& path : o.meshes)
        s.meshes.push_back({std::make_shared<TriangleMesh>(readMesh(path)), vec3f(0.6f, 0.6f, 0.62f), path});
    }
    if (!meshColors.empty())
      for (size_t i = 0; i < s.meshes.size(); ++i) s.meshes[i].color = meshColors[i % meshColors.size()];
  }
  if (!s.volume && s.iso.values.empty() && s.meshes.empty())
    failUsage("--no-volume leaves nothing to draw: add --iso or --mesh");
  s.validate();
  return doc;
}

/// Fields the scene needs; empty means all (a layer names the default field).
std::vector<std::string> neededFields(const Scene& s) {
  std::vector<std::string> names;
  bool all = false;
  auto add = [&](const std::string& n) {
    if (n.empty()) all = true;
    else if (std::find(names.begin(), names.end(), n) == names.end()) names.push_back(n);
  };
  for (const VolumeLayer& l : s.layers) add(l.field);
  if (!s.iso.values.empty()) {
    if (!s.iso.field.empty()) add(s.iso.field);
    if (!s.iso.colorField.empty()) add(s.iso.colorField);
  }
  return all ? std::vector<std::string>() : names;
}

/// The camera: the scene file's, or framing from azimuth and elevation the part of the data the
/// transfer function shows (all of it with --frame-all, or when nothing is visible); explicit
/// position, look-at and up override either.
Camera cameraFromOptions(const RenderCmdOptions& o, const CLI::App& cmd, const SceneDocument& doc, const Model& model,
                         const box3d& visible) {
  auto given = [&](const char* name) { return cmd.count(name) > 0; };
  if (!(o.fov > 0 && o.fov < 180)) failUsage("--fov must be in (0, 180) degrees");
  const box3i cb = model.cellBounds();
  const box3d all(model.world.toWorld(vec3d(cb.lower)), model.world.toWorld(vec3d(cb.upper)));
  const box3d target = o.frameAll || visible.empty() ? all : visible;
  const bool reframe = given("--azimuth") || given("--elevation") || given("--fov") || given("--ortho");
  Camera camera = doc.hasCamera && !reframe ? doc.frame.camera
                                           : Camera::frame(target, o.azimuth, o.elevation, o.fov, o.ortho);
  if (!o.position.empty()) camera.position = toVec(o.position, "--position");
  if (!o.lookAt.empty()) camera.lookAt = toVec(o.lookAt, "--look-at");
  if (!o.up.empty()) camera.up = toVec(o.up, "--up");
  return camera;
}

/// The image format the output's extension names: PNG (also without an extension, as for a
/// device or a pipe), or JPEG for .jpg / .jpeg.
bool isJpeg(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".png" || ext.empty()) return false;
  if (ext == ".jpg" || ext == ".jpeg") return true;
  failUsage("-o ", path, ": unknown image format '", ext, "' (write .png, .jpg or .jpeg)");
}

/// The scene document as a file records it: paths made absolute, so that it reads the same from
/// any folder.
SceneDocument withAbsolutePaths(SceneDocument doc) {
  std::error_code ec;
  if (!doc.input.empty()) doc.input = std::filesystem::absolute(doc.input, ec).lexically_normal().string();
  for (SceneMesh& m : doc.scene.meshes)
    if (!m.source.empty()) m.source = std::filesystem::absolute(m.source, ec).lexically_normal().string();
  return doc;
}

/// The colour bar, annotations and level legend the options ask for, drawn into the image in a
/// colour that stands out against the background.
void drawOverlays(const RenderCmdOptions& o, const Scene& scene, const Frame& frame, const Model& model,
                  const DatasetInfo& dataset, int field, Image& image) {
  const vec3f bg = scene.background;
  const float luminance = 0.2126f * bg.x + 0.7152f * bg.y + 0.0722f * bg.z;
  const vec3f ink = luminance > 0.3f ? vec3f(0.f) : vec3f(1.f);
  const std::string name = model.fieldNames[size_t(field)];
  if (scene.debug == DebugView::Level) {
    std::vector<int> levels;
    for (const ModelSummary::Level& l : summarize(model).levels) levels.push_back(l.level);
    drawLevelLegend(image, levels, ink);
  }
  if (o.colorbar && scene.debug == DebugView::None && scene.volume) {
    TransferFunction tf = scene.layers.at(0).tf;
    if (tf.valueRange.empty()) tf.valueRange = dataset.valueRanges[size_t(field)];
    drawColorBar(image, tf, name, ink);
  }
  if (o.annotate) {
    const box3i cb = model.cellBounds();
    drawBoxOutline(image, frame.camera,
                   box3d(model.world.toWorld(vec3d(cb.lower)), model.world.toWorld(vec3d(cb.upper))), ink * 0.6f);
    std::vector<std::string> lines{o.in.name(), "field " + name};
    const SimulationState& sim = model.simulation;
    if (sim.hasTime() || sim.hasCycle())
      lines.push_back(strCat(sim.hasTime() ? strCat("time ", sim.time) : std::string(),
                             sim.hasTime() && sim.hasCycle() ? ", " : "",
                             sim.hasCycle() ? strCat("cycle ", sim.cycle) : std::string()));
    drawLines(image, lines, ink);
  }
}

void run(const RenderCmdOptions& o, const CLI::App& cmd) {
  if (o.frames < 1 || o.frames > 1000) failUsage("--frames must be in 1..1000");
  const bool jpeg = isJpeg(o.output);
  if (jpeg && cmd.count("--alpha")) failUsage("--alpha needs a PNG output (JPEG has no alpha channel)");
  SceneDocument doc = sceneFromOptions(o, cmd);
  Scene& scene = doc.scene;
  Frame& frame = doc.frame;

  Timer loadTimer;
  LoadOptions lo = o.in.loadOptions(false);
  lo.fields = neededFields(scene);
  const Model model = loadModel(doc.input, lo);
  const double loadSeconds = loadTimer.seconds();
  const DatasetInfo dataset = DatasetInfo::of(model);
  auto given = [&](const char* name) { return cmd.count(name) > 0; };
  const bool fromFile = !o.sceneFile.empty();

  // The first picture: the default field named, and transfer-function defaults adapted to the
  // data unless a file or the options chose them.
  VolumeLayer& first = scene.layers.at(0);
  const int field = model.requireField(first.field);
  if (first.field.empty() && model.fieldNames.size() > 1)
    logNote(strCat("field '", model.fieldNames[size_t(field)], "' (the default; -f chooses another of ",
                   model.fieldNames.size(), ")"));
  if (!fromFile && o.tfFile.empty()) {
    const DefaultChoices c = adaptTransferFunction(model, dataset, field, first.tf, !given("--log") && !given("--linear"),
                                                   !given("--opacity"));
    first.tf = c.tf;
    for (const std::string& note : c.notes) logNote(note);
  }
  if (given("--linear"))
    for (VolumeLayer& l : scene.layers) l.tf.logScale = false;
  for (const std::string& w : sceneWarnings(scene, model, dataset)) logWarning(w);

  Renderer renderer(model, dataset);
  const SceneUpdate update = renderer.setScene(scene);
  if (!scene.iso.values.empty())
    logInfo(strCat("iso-surface regions: ", renderer.isoRegions(), " of ", model.regions.regions.size(),
                   ", built in ", update.isoSeconds, " s"));
  frame.camera = cameraFromOptions(o, cmd, doc, model, renderer.visibleBounds());
  frame.validate();
  doc.hasCamera = true;
  if (!o.writeScene.empty()) writeSceneFile(o.writeScene, withAbsolutePaths(doc));

  // A frame is samplesPerPixel passes into one buffer; a progress line on a terminal.
  FrameBuffer buffer(frame.width, frame.height);
  const bool showProgress = logLevel() >= LogLevel::Warning && isatty(STDERR_FILENO) && !o.json;
  auto renderFrame = [&](RenderStats& stats) {
    buffer.clear();
    Progress progress("rendering", uint64_t(buffer.tileCount()) * uint64_t(frame.samplesPerPixel));
    if (!showProgress) progress.finish();
    PassControl control;
    control.progress = [&](uint64_t, uint64_t) { progress.advance(1); };
    renderer.renderPasses(frame, buffer, frame.samplesPerPixel, control);
    progress.finish();
    stats = buffer.stats();
  };
  RenderStats stats;
  std::vector<double> frameSeconds;
  if (o.stats) {
    renderFrame(stats); // warm-up, not counted
    for (int f = 0; f < o.frames; ++f) {
      renderFrame(stats);
      frameSeconds.push_back(stats.seconds);
    }
    std::sort(frameSeconds.begin(), frameSeconds.end());
    stats.seconds = frameSeconds[frameSeconds.size() / 2];
  } else {
    renderFrame(stats);
  }
  Image image = buffer.resolve();
  drawOverlays(o, scene, frame, model, dataset, field, image);
  if (imageIsEmpty(image))
    logWarning(strCat("the image is empty: nothing in view is visible (", renderer.visibleRegions(), " of ",
                      model.regions.regions.size(), " regions may be; check --range, --opacity and the camera)"));
  if (jpeg)
    writeJpeg(o.output, image, scene.background);
  else
    writePng(o.output, image, scene.keepAlpha, scene.background);
  if (!o.floatOutput.empty()) writePfm(o.floatOutput, image, scene.background);
  logInfo(strCat("wrote ", o.output));

  const char* traversal = renderer.traversalInUse() == TraversalKind::Embree ? "embree" : "kd";
  if (o.json) {
    nlohmann::json j;
    j["output"] = o.output;
    j["width"] = frame.width;
    j["height"] = frame.height;
    j["samples_per_pixel"] = frame.samplesPerPixel;
    j["frame_seconds"] = stats.seconds;
    j["frames"] = frameSeconds.empty() ? 1 : frameSeconds.size();
    j["rays"] = stats.rays;
    j["samples"] = stats.samples;
    j["regions_visited"] = stats.regionsVisited;
    j["samples_per_second"] = stats.samplesPerSecond();
    j["visible_regions"] = renderer.visibleRegions();
    j["regions"] = model.regions.regions.size();
    j["transfer_function_update_seconds"] = update.volumeSeconds;
    j["load_seconds"] = loadSeconds;
    j["traversal"] = traversal;
    j["surface_hits"] = stats.surfaceHits;
    j["iso_samples"] = stats.isoSamples;
    j["ao_rays"] = stats.aoRays;
    j["iso_regions"] = renderer.isoRegions();
    j["iso_update_seconds"] = update.isoSeconds;
    j["meshes"] = renderer.meshCount();
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
                model.regions.regions.size(), update.volumeSeconds);
    std::printf("traversal        %s\n", renderer.traversalInUse() == TraversalKind::Embree ? "embree" : "kd-tree");
    if (!scene.iso.values.empty())
      std::printf("iso regions      %zu of %zu (built in %.4f s), %llu iso samples\n", renderer.isoRegions(),
                  model.regions.regions.size(), update.isoSeconds, (unsigned long long)stats.isoSamples);
    if (!scene.iso.values.empty() || !scene.meshes.empty())
      std::printf("surface hits     %llu, ambient occlusion rays %llu\n", (unsigned long long)stats.surfaceHits,
                  (unsigned long long)stats.aoRays);
    std::printf("load + build     %.3f s\n", loadSeconds);
  }
}

} // namespace

void addRender(CLI::App& app) {
  auto o = std::make_shared<RenderCmdOptions>();
  CLI::App* cmd = app.add_subcommand("render", "Volume-render a field to a PNG image");
  o->in.add(*cmd);
  cmd->add_option("-o,--output", o->output, "Image to write: .png, or .jpg / .jpeg")->required();
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
  cmd->add_flag("--log", o->logScale, "Map values logarithmically (every layer)");
  cmd->add_flag("--linear", o->linear, "Map values linearly even where the data spans many decades");
  cmd->add_flag("--colorbar", o->colorbar, "Draw a labelled colour bar of the first layer");
  cmd->add_flag("--annotate", o->annotate, "Write the dataset, field and simulation time, and outline the domain");
  cmd->add_flag("--frame-all", o->frameAll, "Default view: frame the whole data, not only its visible part");
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
  cmd->add_flag("--no-volume", o->noVolume, "Draw surfaces only");
  cmd->add_option("--layer", o->layers,
                  "Another field in the volume: FIELD, FIELD=COLORMAP or FIELD=TF_FILE (repeatable)");
  cmd->add_option("--iso", o->iso, "Iso-values v1,v2,... of implicit iso-surfaces")->delimiter(',');
  cmd->add_option("--iso-field", o->isoField, "Field of the iso-surfaces (default: the rendered field)");
  cmd->add_option("--iso-color", o->isoColor, "Iso-surface colours r,g,b[,r,g,b...] (sRGB), one per value")
      ->delimiter(',');
  cmd->add_option("--iso-color-field", o->isoColorField, "Colour the iso-surfaces by this field");
  cmd->add_option("--iso-colormap", o->isoColormap, "Colour map for --iso-color-field")->capture_default_str();
  cmd->add_flag("--iso-color-log", o->isoColorLog, "Map --iso-color-field logarithmically");
  cmd->add_option("--iso-color-range", o->isoColorRange, "Value range LOW,HIGH for --iso-color-field")
      ->delimiter(',');
  cmd->add_option("--mesh", o->meshes, "Triangle mesh (OBJ, PLY or .tris) in world space (repeatable)");
  cmd->add_option("--mesh-color", o->meshColor, "Mesh colours r,g,b[,r,g,b...] (sRGB), one per mesh")
      ->delimiter(',');
  cmd->add_option("--clip-plane", o->clipPlanes,
                  "Remove the half-space in front of a plane: px,py,pz,nx,ny,nz (world; repeatable)");
  cmd->add_option("--clip-box", o->clipBox, "Keep only the inside of a box x0,y0,z0,x1,y1,z1 (world)")
      ->delimiter(',');
  cmd->add_flag("--clip-meshes", o->clipMeshes, "Clip meshes too");
  cmd->add_option("--ao", o->aoRays, "Ambient occlusion rays per surface hit (0: off)")->capture_default_str();
  cmd->add_option("--ao-length", o->aoLength, "Ambient occlusion ray length, world units (0: a tenth of the diagonal)");
  cmd->add_flag("--ao-volume", o->aoVolume, "Let the volume attenuate ambient occlusion rays");
  cmd->add_flag("--stats", o->stats, "Time the frame after a warm-up and print statistics");
  cmd->add_option("--frames", o->frames, "Frames to time with --stats (median)")->capture_default_str();
  cmd->add_flag("--json", o->json, "Print statistics as one JSON object on stdout");
  cmd->add_option("--scene", o->sceneFile,
                  "Scene file (JSON, see docs/rendering.md); options given on the command line override it");
  cmd->add_option("--write-scene", o->writeScene, "Write the scene and frame in effect as a JSON scene file");
  cmd->callback([o, cmd] { run(*o, *cmd); });
}

} // namespace exa::cli
