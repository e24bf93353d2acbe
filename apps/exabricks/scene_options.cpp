#include "scene_options.h"

#include "exabricks/amr/scenes.h"
#include "exabricks/core/log.h"
#include "exabricks/core/text.h"
#include "exabricks/documents/mesh.h"
#include "exabricks/documents/scene_file.h"
#include "exabricks/documents/transfer_function_file.h"
#include "exabricks/render/defaults.h"
#include "exabricks/render/overlay.h"
#include "exabricks/render/scene_vocabulary.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace exa::cli {
namespace {

/// A flag's value checked against the range of the scene setting it sets.
/// Three numbers of a flag for a described vector setting, checked against its kind.
vec3f checkedVector(const char* flag, const char* key, const std::vector<float>& v) {
  if (v.size() != 3) failUsage(flag, " expects three numbers separated by commas");
  const vec3f value(v[0], v[1], v[2]);
  try {
    checkSceneVector(key, value);
  } catch (const Error& e) {
    failUsage(flag, ": ", e.what());
  }
  return value;
}

template <typename T> T checked(const char* flag, const char* key, T value) {
  try {
    checkSceneSetting(key, double(value));
  } catch (const Error& e) {
    failUsage(flag, ": ", e.what());
  }
  return value;
}

vec3d toVec(const std::vector<double>& v, const char* what) {
  if (v.size() != 3) failUsage(what, " needs three numbers x,y,z");
  return {v[0], v[1], v[2]};
}

std::vector<double> parseNumbers(const std::string& text, const char* what) {
  std::vector<double> out;
  std::istringstream in(text);
  for (std::string part; std::getline(in, part, ',');) {
    double v = 0;
    if (!parseFiniteNumber(part, v)) failUsage(what, ": '", part, "' is not a number");
    if (const std::string why = beyondSinglePrecision(v); !why.empty()) failUsage(what, ": ", why);
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
TransferFunction applyTransferFunctionOptions(TransferFunction tf, const RenderOptions& o, const std::string& tfFile,
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
    std::vector<double> r;
    for (const std::string& part : o.range)
      for (double v : parseNumbers(part, "--range"))
        r.push_back(v);
    if (r.size() != 2 || !(r[0] < r[1])) failUsage("--range expects LOW,HIGH with LOW < HIGH");
    tf.valueRange = range1f{float(r[0]), float(r[1])};
  }
  if (o.logScale) tf.logScale = true;
  if (o.opacityScale > 0.f) tf.opacityScale = o.opacityScale;
  return tf;
}

/// Where a flag's help is listed.
enum class FlagGroup { Image, Camera, Integration, Surfaces, PathTracing };
/// A flag's form: it takes the setting's value, or sets a switch on or off.
enum class FlagForm { Value, On, Off };

/// The flags that set one described scene setting each: their help, type, default and checks
/// are the setting's (scene_vocabulary.h); they are registered and applied from this table.
struct SettingFlag {
  const char* flag;
  const char* key;
  FlagGroup group;
  FlagForm form = FlagForm::Value;
};

constexpr SettingFlag kSettingFlags[] = {
    {"--spp", "frame.samples_per_pixel", FlagGroup::Image},
    {"--noise-target", "frame.noise_target", FlagGroup::Image},
    {"--denoise", "frame.denoise", FlagGroup::Image},
    {"--rate", "frame.rate", FlagGroup::Image},
    {"--seed", "frame.seed", FlagGroup::Image},
    {"--no-jitter", "frame.jitter", FlagGroup::Image, FlagForm::Off},
    {"--colorbar", "legends.color_bar", FlagGroup::Image, FlagForm::On},
    {"--annotate", "legends.annotation", FlagGroup::Image, FlagForm::On},
    {"--alpha", "alpha", FlagGroup::Camera, FlagForm::On},
    {"--shading", "shading", FlagGroup::Integration},
    {"--traversal", "integration.traversal", FlagGroup::Integration},
    {"--no-skip", "integration.space_skipping", FlagGroup::Integration, FlagForm::Off},
    {"--no-uniform-stride", "integration.uniform_stride", FlagGroup::Integration, FlagForm::Off},
    {"--no-early-termination", "integration.early_termination", FlagGroup::Integration, FlagForm::Off},
    {"--sampling", "integration.sampling", FlagGroup::Integration},
    {"--reconstruction", "integration.reconstruction", FlagGroup::Integration},
    {"--debug", "debug", FlagGroup::Integration},
    {"--no-volume", "volume", FlagGroup::Integration, FlagForm::Off},
    {"--clip-meshes", "clip.meshes", FlagGroup::Surfaces, FlagForm::On},
    {"--particle-radius", "particles.radius", FlagGroup::Surfaces},
    {"--particle-radius-pixels", "particles.radius_pixels", FlagGroup::Surfaces},
    {"--ao", "ambient_occlusion.rays", FlagGroup::Surfaces},
    {"--ao-length", "ambient_occlusion.length", FlagGroup::Surfaces},
    {"--ao-volume", "ambient_occlusion.volume", FlagGroup::Surfaces, FlagForm::On},
    {"--integrator", "integration.integrator", FlagGroup::PathTracing},
    {"--albedo", "pathtrace.albedo", FlagGroup::PathTracing},
    {"--anisotropy", "pathtrace.anisotropy", FlagGroup::PathTracing},
    {"--bounces", "pathtrace.bounces", FlagGroup::PathTracing},
    {"--emission", "pathtrace.emission", FlagGroup::PathTracing},
};

/// Registers the group's setting flags with the help, type and default of their settings.
void addSettingFlags(RenderOptions& o, CLI::App& cmd, FlagGroup group) {
  const nlohmann::json vocabulary = nlohmann::json::parse(sceneVocabularyJson());
  for (const SettingFlag& f : kSettingFlags) {
    if (f.group != group) continue;
    const auto s =
        std::find_if(vocabulary.begin(), vocabulary.end(), [&](const nlohmann::json& e) { return e["key"] == f.key; });
    const std::string key = f.key, help = (*s)["help"], type = (*s)["type"];
    if (f.form != FlagForm::Value) {
      cmd.add_flag(std::string(f.flag))
          ->description((f.form == FlagForm::Off ? "Off: " : "") + help + " (scene key " + key + ")");
      continue;
    }
    std::string typeName = type == "integer"   ? "INT"
                           : type == "number"  ? "FLOAT"
                           : type == "boolean" ? "{on,off}"
                                               : "TEXT";
    if (type == "choice") {
      typeName.clear();
      for (const nlohmann::json& c : (*s)["choices"])
        typeName += (typeName.empty() ? "{" : ",") + c.get<std::string>();
      typeName += "}";
    }
    cmd.add_option(f.flag, o.settings[f.flag], help + " (scene key " + key + ")")
        ->type_name(typeName)
        ->default_str(type == "boolean" ? ((*s)["default"].get<bool>() ? "on" : "off") : sceneSettingDefaultText(key));
  }
}

/// Applies the setting flags given; errors name the flag and the key.
void applySettingFlags(const RenderOptions& o, const CLI::App& cmd, SceneDocument& doc) {
  for (const SettingFlag& f : kSettingFlags) {
    if (cmd.count(f.flag) == 0) continue;
    const std::string text = f.form == FlagForm::Value ? o.settings.at(f.flag)
                             : f.form == FlagForm::On  ? "true"
                                                       : "false";
    try {
      setSceneSettingText(doc.scene, doc.frame, f.key, text, f.flag);
    } catch (const Error& e) {
      const std::string m = e.what();
      failUsage(m.rfind(f.flag, 0) == 0 ? m : std::string(f.flag) + ": " + m);
    }
  }
  if (cmd.count("--debug") && doc.scene.debug == DebugView::Level)
    doc.scene.legends.levelLegend = true; // the command line's level view has its legend
}

/// The image: its size and samples, the first layer's transfer function, the legends.
void addImageOptions(RenderOptions& o, CLI::App& cmd) {
  cmd.add_option("--size", o.size, "Image size WIDTHxHEIGHT")->capture_default_str();
  addSettingFlags(o, cmd, FlagGroup::Image);
  cmd.add_option("--colormap", o.colormap, "Built-in colour map")->capture_default_str()->check(colormapName());
  cmd.add_option("--tf", o.tfFile, "Transfer function file (ParaView preset or exabricks JSON)");
  cmd.add_option("--opacity", o.opacity, "Opacity points x,alpha,... over the normalised value")
      ->delimiter(',')
      ->check(singleNumber());
  cmd.add_option("--opacity-scale", o.opacityScale, sceneSettingHelp("transfer_function.opacity_scale"))
      ->check(singleNumber());
  cmd.add_option("--range", o.range, sceneSettingHelp("transfer_function.range"))->delimiter(',');
  cmd.add_flag("--log", o.logScale, "Map values logarithmically (every layer)");
  cmd.add_flag("--linear", o.linear, "Map values linearly even where the data spans many decades");
}

/// The camera and the background.
void addCameraOptions(RenderOptions& o, CLI::App& cmd) {
  cmd.add_flag("--frame-all", o.frameAll, "Default view: frame the whole data, not only its visible part");
  cmd.add_option("--position", o.position, sceneSettingHelp("camera.position"))->delimiter(',')->check(singleNumber());
  cmd.add_option("--look-at", o.lookAt, sceneSettingHelp("camera.look_at"))->delimiter(',')->check(singleNumber());
  cmd.add_option("--up", o.up, sceneSettingHelp("camera.up"))->delimiter(',')->check(singleNumber());
  cmd.add_option("--fov", o.fov, sceneSettingHelp("camera.fov"))->capture_default_str()->check(singleNumber());
  cmd.add_flag("--ortho", o.ortho, "Orthographic projection");
  const CLI::Validator finite(
      [](std::string& text) {
        const double v = std::strtod(text.c_str(), nullptr);
        return std::isfinite(v) ? std::string() : "must be a finite number, not " + text;
      },
      "FINITE");
  cmd.add_option("--azimuth", o.azimuth, "Default view: degrees around +z")->capture_default_str()->check(finite);
  const CLI::Validator latitude(
      [](std::string& text) {
        const double v = std::strtod(text.c_str(), nullptr);
        return v >= -90.0 && v <= 90.0 ? std::string() : "must be in [-90, 90] degrees, not " + text;
      },
      "DEGREES");
  cmd.add_option("--elevation", o.elevation, "Default view: degrees above the x-y plane (-90 to 90)")
      ->capture_default_str()
      ->check(latitude);
  cmd.add_option("--background", o.background, sceneSettingHelp("background"))->delimiter(',')->check(singleNumber());
  addSettingFlags(o, cmd, FlagGroup::Camera);
}

/// Shading and light, the integration, the debug views and the volume layers.
void addIntegrationOptions(RenderOptions& o, CLI::App& cmd) {
  addSettingFlags(o, cmd, FlagGroup::Integration);
  cmd.add_option("--light", o.light, "headlight, or the direction x,y,z light travels")->capture_default_str();
  cmd.add_option("--layer", o.layers,
                 "Another field in the volume: FIELD, FIELD=COLORMAP or FIELD=TF_FILE (repeatable)");
}

/// Iso-surfaces, meshes, clipping and ambient occlusion.
void addSurfaceOptions(RenderOptions& o, CLI::App& cmd) {
  cmd.add_option("--iso", o.iso, "Iso-values v1,v2,... of implicit iso-surfaces")
      ->delimiter(',')
      ->check(singleNumber());
  cmd.add_option("--iso-field", o.isoField, sceneSettingHelp("iso.field"));
  cmd.add_option("--iso-color", o.isoColor, "Iso-surface colours r,g,b[,r,g,b...] (sRGB), one per value")
      ->delimiter(',')
      ->check(singleNumber());
  cmd.add_option("--iso-color-field", o.isoColorField, "Colour the iso-surfaces by this field");
  cmd.add_option("--iso-colormap", o.isoColormap, "Colour map for --iso-color-field")
      ->capture_default_str()
      ->check(colormapName());
  cmd.add_flag("--iso-color-log", o.isoColorLog, "Map --iso-color-field logarithmically");
  cmd.add_option("--iso-color-range", o.isoColorRange, "Value range LOW,HIGH for --iso-color-field")
      ->delimiter(',')
      ->check(singleNumber());
  cmd.add_option("--mesh", o.meshes, sceneSettingHelp("meshes[].file") + " (repeatable)");
  cmd.add_option("--mesh-color", o.meshColor, "Mesh colours r,g,b[,r,g,b...] (sRGB), one per mesh")
      ->delimiter(',')
      ->check(singleNumber());
  cmd.add_option("--clip-plane", o.clipPlanes,
                 "Remove the half-space in front of a plane: px,py,pz,nx,ny,nz (world; repeatable)");
  cmd.add_option("--clip-box", o.clipBox, sceneSettingHelp("clip.box"))->delimiter(',')->check(singleNumber());
  addSettingFlags(o, cmd, FlagGroup::Surfaces);
  addParticleOptions(o, cmd);
}

/// Path tracing.
void addPathTracingOptions(RenderOptions& o, CLI::App& cmd) {
  addSettingFlags(o, cmd, FlagGroup::PathTracing);
  cmd.add_option("--environment", o.environment, sceneSettingHelp("pathtrace.environment") + " (default 1,1,1)")
      ->delimiter(',')
      ->check(singleNumber());
  cmd.add_option("--sky", o.sky, sceneSettingHelp("pathtrace.sky"))->delimiter(',')->check(singleNumber());
  cmd.add_option("--ground", o.ground, sceneSettingHelp("pathtrace.ground"))->delimiter(',')->check(singleNumber());
  cmd.add_option("--sun", o.sun,
                 "Path tracing: a sun light travelling along dx,dy,dz (world) with irradiance INTENSITY and an "
                 "angular diameter ANGLE in degrees (default 0.53): dx,dy,dz,INTENSITY[,ANGLE]")
      ->delimiter(',')
      ->check(singleNumber());
}

} // namespace

void RenderOptions::add(CLI::App& cmd) {
  in.add(cmd);
  addImageOptions(*this, cmd);
  addCameraOptions(*this, cmd);
  addIntegrationOptions(*this, cmd);
  addSurfaceOptions(*this, cmd);
  addPathTracingOptions(*this, cmd);
  cmd.add_option("--scene", sceneFile,
                 "Scene file (JSON, see docs/rendering.md); options given on the command line override it");
}

void addDeviceOption(CLI::App& cmd, std::string& device) {
  cmd.add_option("--device", device, sceneSettingHelp("device"))
      ->check(CLI::IsMember(deviceChoices()))
      ->capture_default_str();
}

void MarchFlags::add(CLI::App& cmd) {
  addDeviceOption(cmd, device);
  cmd.add_flag("--scalar", scalar,
               "Measurement: reconstruct one sample after another (no SIMD batches; the reference loop)");
  cmd.add_flag("--no-lazy-gradients", noLazyGradients,
               "Measurement: reconstruct gradients with every batch, also after samples the transfer function hides");
  cmd.add_flag("--no-join-segments", noJoinSegments,
               "Measurement: one batch per region segment, instead of batches filled from consecutive segments");
  cmd.add_flag("--no-majorant-grid", noMajorantGrid,
               "Measurement: path tracing against the regions' majorants alone, without the majorant grid");
}

RendererOptions MarchFlags::options() const {
  RendererOptions r;
  r.vectorized = !scalar;
  r.lazyGradients = !noLazyGradients;
  r.joinSegments = !noJoinSegments;
  r.majorantGrid = !noMajorantGrid;
  return r;
}

namespace {

/// Which options the command line gave, and which apply: all of them without a scene file,
/// only the ones given over a scene file.
struct OptionUse {
  const CLI::App& cmd;
  bool fromFile;
  bool given(const char* name) const { return cmd.count(name) > 0; }
  bool apply(const char* name) const { return !fromFile || given(name); }
};

void applyFrameOptions(const RenderOptions& o, const OptionUse& u, Frame& f) {
  if (u.apply("--size")) parseSize(o.size, f.width, f.height);
}

/// The first volume layer (the field and its transfer function) and the further layers.
void applyLayerOptions(const RenderOptions& o, const OptionUse& u, Scene& s) {
  if (o.linear && o.logScale) failUsage("--log and --linear exclude each other");
  if (u.given("--opacity-scale")) checked("--opacity-scale", "transfer_function.opacity_scale", o.opacityScale);
  if (s.layers.empty()) s.layers.push_back(VolumeLayer{});
  VolumeLayer& first = s.layers[0];
  if (u.apply("--field")) first.field = o.in.field;
  const bool colormapGiven = u.given("--colormap") || (!u.fromFile && o.tfFile.empty());
  first.tf = applyTransferFunctionOptions(u.fromFile || !o.tfFile.empty() ? first.tf : defaultTransferFunction(), o,
                                          o.tfFile, colormapGiven ? &o.colormap : nullptr, true);
  if (!u.apply("--layer")) return;
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

/// The light, the background and the alpha channel.
void applyLightOptions(const RenderOptions& o, const OptionUse& u, Scene& s) {
  if (u.apply("--light")) {
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
  if (u.apply("--background")) {
    if (o.background.size() != 3) failUsage("--background expects r,g,b (sRGB, 0..1)");
    for (float c : o.background)
      if (!(c >= 0.f && c <= 1.f)) failUsage("--background components must lie in [0, 1]");
    s.background = srgbToLinear(vec3f(o.background[0], o.background[1], o.background[2]));
  }
}

/// The volume on or off, clipping and ambient occlusion.
void applyClipOptions(const RenderOptions& o, const OptionUse& u, Scene& s) {
  if (u.apply("--clip-plane")) {
    s.clip.planes.clear();
    for (const std::string& text : o.clipPlanes) {
      const std::vector<double> v = parseNumbers(text, "--clip-plane");
      if (v.size() != 6 || (v[3] == 0 && v[4] == 0 && v[5] == 0))
        failUsage("--clip-plane expects px,py,pz,nx,ny,nz with a non-zero normal, got '", text, "'");
      s.clip.planes.push_back({vec3d(v[0], v[1], v[2]), vec3d(v[3], v[4], v[5])});
    }
  }
  if (u.apply("--clip-box")) {
    s.clip.box = box3d();
    if (!o.clipBox.empty()) {
      const auto& b = o.clipBox;
      if (b.size() != 6 || !(b[0] < b[3] && b[1] < b[4] && b[2] < b[5]))
        failUsage("--clip-box expects x0,y0,z0,x1,y1,z1 with the lower corner below the upper one");
      s.clip.box = box3d(vec3d(b[0], b[1], b[2]), vec3d(b[3], b[4], b[5]));
    }
  }
}

void applyPathTracingOptions(const RenderOptions& o, const OptionUse& u, Scene& s) {
  PathTracing& pt = s.pathTracing;
  if (u.given("--environment")) pt.environment = checkedVector("--environment", "pathtrace.environment", o.environment);
  if (u.given("--sky")) pt.sky = checkedVector("--sky", "pathtrace.sky", o.sky);
  if (u.given("--ground")) pt.ground = checkedVector("--ground", "pathtrace.ground", o.ground);
  if (u.given("--sun")) {
    const auto& v = o.sun;
    if (v.size() != 4 && v.size() != 5) failUsage("--sun expects dx,dy,dz,INTENSITY[,ANGLE]");
    pt.sunDirection = checkedVector("--sun", "pathtrace.sun_direction", {v[0], v[1], v[2]});
    pt.sunIntensity = checked("--sun", "pathtrace.sun_intensity", v[3]);
    if (v.size() == 5) pt.sunAngle = checked("--sun", "pathtrace.sun_angle", v[4]);
  }
}

void applyIsoOptions(const RenderOptions& o, const OptionUse& u, Scene& s) {
  if (!o.isoColorRange.empty() && (o.isoColorRange.size() != 2 || !(o.isoColorRange[0] < o.isoColorRange[1])))
    failUsage("--iso-color-range expects LOW,HIGH with LOW < HIGH");
  if (o.iso.empty() && !u.fromFile && (!o.isoField.empty() || !o.isoColorField.empty() || !o.isoColor.empty()))
    failUsage("iso-surface options need --iso VALUES");
  for (float v : o.iso)
    if (!std::isfinite(v)) failUsage("--iso values must be finite numbers");
  IsoSurfaces& iso = s.iso;
  if (u.apply("--iso")) iso.values = o.iso;
  if (u.apply("--iso-field")) iso.field = o.isoField.empty() ? o.in.field : o.isoField;
  if (u.apply("--iso-color")) iso.colors = colorList(o.isoColor, "--iso-color");
  if (u.apply("--iso-color-field")) iso.colorField = o.isoColorField;
  if (u.apply("--iso-colormap")) iso.colorTf.colorMap = builtinColorMap(o.isoColormap);
  if (u.apply("--iso-color-log")) iso.colorTf.logScale = o.isoColorLog;
  if (u.apply("--iso-color-range"))
    iso.colorTf.valueRange = o.isoColorRange.empty() ? range1f() : range1f{o.isoColorRange[0], o.isoColorRange[1]};
}

/// Meshes: read here, so that a bad mesh file fails before the (longer) model build.
void applyMeshOptions(const RenderOptions& o, const OptionUse& u, Scene& s) {
  if (!u.apply("--mesh") && !u.apply("--mesh-color")) return;
  const std::vector<vec3f> meshColors = colorList(o.meshColor, "--mesh-color");
  if (u.apply("--mesh")) {
    s.meshes.clear();
    for (const std::string& path : o.meshes)
      s.meshes.push_back({std::make_shared<TriangleMesh>(readMesh(path)), vec3f(0.6f, 0.6f, 0.62f), path});
  }
  if (!meshColors.empty())
    for (size_t i = 0; i < s.meshes.size(); ++i)
      s.meshes[i].color = meshColors[i % meshColors.size()];
}

} // namespace

SceneDocument sceneFromOptions(const RenderOptions& o, const CLI::App& cmd) {
  const bool fromFile = !o.sceneFile.empty();
  SceneDocument doc = fromFile ? readSceneFile(o.sceneFile) : SceneDocument();
  const OptionUse u{cmd, fromFile};
  Scene& s = doc.scene;
  if (!o.in.input.empty())
    doc.input = o.in.input;
  else if (fromFile && doc.input.empty())
    failUsage(o.sceneFile, " names no input: give the dataset it shows (exabricks ", cmd.get_name(), " INPUT --scene ",
              o.sceneFile, ")");
  if (doc.input == kEmbeddedInput) doc.input.clear(); // the default dataset

  applyFrameOptions(o, u, doc.frame);
  applyLayerOptions(o, u, s);
  applySettingFlags(o, cmd, doc);
  applyLightOptions(o, u, s);
  applyClipOptions(o, u, s);
  applyPathTracingOptions(o, u, s);
  applySampling(cmd, fromFile, doc);
  applyIsoOptions(o, u, s);
  applyMeshOptions(o, u, s);
  applyParticleOptions(o, cmd, u.fromFile, s);
  if (!s.volume && s.iso.values.empty() && s.meshes.empty() && !s.particles.show)
    failUsage("--no-volume leaves nothing to draw: add --iso, --mesh or --particles");
  s.validate();
  return doc;
}

std::vector<std::string> neededFields(const Scene& s) {
  std::vector<std::string> names;
  bool all = false;
  auto add = [&](const std::string& n) {
    if (n.empty())
      all = true;
    else if (std::find(names.begin(), names.end(), n) == names.end())
      names.push_back(n);
  };
  for (const VolumeLayer& l : s.layers)
    add(l.field);
  if (!s.iso.values.empty()) {
    if (!s.iso.field.empty()) add(s.iso.field);
    if (!s.iso.colorField.empty()) add(s.iso.colorField);
  }
  return all ? std::vector<std::string>() : names;
}

namespace {
bool keepsSceneCamera(const CLI::App& cmd, const SceneDocument& doc) {
  auto given = [&](const char* name) { return cmd.count(name) > 0; };
  return doc.hasCamera && !given("--azimuth") && !given("--elevation") && !given("--fov") && !given("--ortho");
}
} // namespace

bool framesVisibleData(const RenderOptions& o, const CLI::App& cmd, const SceneDocument& doc) {
  return !keepsSceneCamera(cmd, doc) && !o.frameAll;
}

Camera cameraFromOptions(const RenderOptions& o, const CLI::App& cmd, const SceneDocument& doc, const Model& model,
                         const box3d& visible, const WholeData* whole) {
  checked("--fov", "camera.fov", o.fov);
  const box3i cb = whole ? whole->cellBounds : model.cellBounds();
  const box3d all = model.world.toWorld(cb);
  const box3d target = o.frameAll || visible.empty() ? all : visible;
  Camera camera =
      keepsSceneCamera(cmd, doc) ? doc.frame.camera : Camera::frame(target, o.azimuth, o.elevation, o.fov, o.ortho);
  if (!o.position.empty()) camera.position = toVec(o.position, "--position");
  if (!o.lookAt.empty()) camera.lookAt = toVec(o.lookAt, "--look-at");
  if (!o.up.empty()) camera.up = toVec(o.up, "--up");
  return camera;
}

int applyDataDefaults(const RenderOptions& o, const CLI::App& cmd, Scene& scene, const Model& model,
                      const DatasetInfo& dataset, const WholeData* whole, bool warn, const DefaultChoices* chosen) {
  VolumeLayer& first = scene.layers.at(0);
  const int field = model.requireField(first.field);
  if (first.field.empty() && model.fieldNames.size() > 1)
    logNote(strCat("field '", model.fieldNames[size_t(field)], "' (the default; -f chooses another of ",
                   model.fieldNames.size(), ")"));
  // The default field by its name: a scene file written from here says which field it shows.
  if (first.field.empty()) first.field = model.fieldNames[size_t(field)];
  if (choosesTransferFunction(o)) {
    const DefaultChoices c = chosen ? *chosen : firstTransferFunction(cmd, scene, field, model, dataset, whole);
    first.tf = c.tf;
    for (const std::string& note : c.commandLineNotes())
      logNote(note);
  }
  if (cmd.count("--linear"))
    for (VolumeLayer& l : scene.layers)
      l.tf.logScale = false;
  if (warn)
    for (const std::string& w : sceneWarnings(scene, model, dataset))
      logWarning(w);
  return field;
}

SceneDocument withAbsolutePaths(SceneDocument doc) {
  std::error_code ec;
  doc.input = doc.input.empty() ? kEmbeddedInput : std::filesystem::absolute(doc.input, ec).lexically_normal().string();
  for (SceneMesh& m : doc.scene.meshes)
    if (!m.source.empty()) m.source = std::filesystem::absolute(m.source, ec).lexically_normal().string();
  return doc;
}

std::string datasetLabel(const std::string& input) { return legendDatasetLabel(input); }

LegendText legendText(const std::string& input, const WholeData* whole) {
  LegendText t;
  t.dataset = datasetLabel(input);
  if (whole) {
    t.levels = whole->levels;
    t.cellBounds = whole->cellBounds;
  }
  return t;
}

} // namespace exa::cli
