#include "exabricks/render/scene.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"
#include "exabricks/core/text.h"
#include "exabricks/render/scene_vocabulary.h"

#include "scene_settings.h"
#include "tf_json.h"

#include <nlohmann/json.hpp>

#include <cmath>

namespace exa {

Scene Scene::volumeOf(const TransferFunction& tf, const std::string& field) {
  Scene s;
  s.layers = {VolumeLayer{field, tf}};
  return s;
}

void resolveParticleRadius(Scene& scene, const Frame& frame) {
  ParticleStyle& p = scene.particles;
  if (!(p.radiusPixels > 0.f) || frame.height < 1) return;
  const Camera& c = frame.camera;
  const double viewHeight =
      c.orthographic ? c.orthoHeight : 2.0 * length(c.lookAt - c.position) * std::tan(0.5 * c.fovy * kDegree);
  p.radius = float(double(p.radiusPixels) * viewHeight / double(frame.height));
}

void Scene::validate() const {
  checkSettings(sceneSettings(), *this);
  for (const ClipPlane& p : clip.planes)
    if (!(length(p.normal) > 0.0) || !std::isfinite(length(p.normal)) || !std::isfinite(length(p.point)))
      fail("a clip plane needs a finite point and a non-zero normal");
  for (float v : iso.values)
    if (!std::isfinite(v)) fail("iso-values must be finite numbers");
  for (size_t l = 0; l < layers.size(); ++l) {
    const std::vector<OpacityPoint>& albedo = layers[l].tf.albedo;
    for (size_t i = 0; i < albedo.size(); ++i)
      if (!(albedo[i].x >= 0.f && albedo[i].x <= 1.f && albedo[i].alpha >= 0.f && albedo[i].alpha <= 1.f) ||
          (i > 0 && albedo[i].x < albedo[i - 1].x))
        fail("layer ", l, "'s albedo point ", i, " (", albedo[i].x, ", ", albedo[i].alpha,
             ") must lie in [0, 1] x [0, 1], x not decreasing");
  }
  for (size_t m = 0; m < meshes.size(); ++m) {
    if (!meshes[m].mesh) {
      if (meshes[m].source.empty()) fail("mesh ", m, " has no data");
      continue; // named by file: checked once it is read
    }
    const TriangleMesh& mesh = *meshes[m].mesh;
    if (mesh.triangles.empty()) fail("mesh ", m, " has no triangles");
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
      const vec3f& v = mesh.vertices[i];
      if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
        fail("mesh ", m, ": vertex ", i, " is not finite");
    }
    for (size_t i = 0; i < mesh.triangles.size(); ++i)
      for (int k = 0; k < 3; ++k)
        if (mesh.triangles[i][k] < 0 || size_t(mesh.triangles[i][k]) >= mesh.vertices.size())
          fail("mesh ", m, ": triangle ", i, " refers to vertex ", mesh.triangles[i][k], " of ", mesh.vertices.size());
  }
}

Frame Frame::preview(int divisor, float previewRate) const {
  Frame f = *this;
  divisor = std::max(1, divisor);
  f.width = std::max(1, width / divisor);
  f.height = std::max(1, height / divisor);
  f.rate = previewRate;
  if (f.width != width || f.height != height) f.depthLimit = f.frontOpacity = nullptr;
  return f;
}

void Frame::validate() const {
  checkSettings(frameSettings(), *this);
  checkStructuredNumber("frame.frame_index", frameIndex);
  const Camera& c = camera;
  const vec3d forward = c.lookAt - c.position;
  if (!std::isfinite(length(forward)) || !std::isfinite(length(c.up)) || !std::isfinite(length(c.position)))
    fail("camera position, look-at and up must be finite");
  if (length(forward) == 0 || length(cross(forward, c.up)) == 0)
    fail("degenerate camera: position equals look-at, or up is parallel to the view direction");
  checkStructuredNumber(c.orthographic ? "camera.ortho_height" : "camera.fov", c.orthographic ? c.orthoHeight : c.fovy);
  if (frontOpacity)
    for (size_t p = 0; p < size_t(width) * size_t(height); ++p)
      if (!(frontOpacity[p] >= 0.f && frontOpacity[p] <= 1.f))
        fail("the front opacity of pixel ", p, " is ", frontOpacity[p], "; it must lie in [0, 1]");
  if (depthLimit)
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        const float d = depthLimit[size_t(y) * size_t(width) + size_t(x)];
        if (!(d >= 0.f))
          fail("the depth limit of pixel (", x, ", ", y, ") is ", d, "; it must be a distance >= 0 (+inf: no limit)");
      }
}

// ---------------------------------------------------------------------------------------------
// JSON

namespace {

using json = nlohmann::json;

json vec(const vec3d& v) { return {v.x, v.y, v.z}; }
json vec(const vec3f& v) { return {v.x, v.y, v.z}; }
json srgb(const vec3f& linear) { return vec(linearToSrgb(linear)); }

/// Reads the keys of one JSON object with errors that name the key path.
class Reader {
public:
  Reader(const json& j, std::string source, std::string path)
      : j_(j), source_(std::move(source)), path_(std::move(path)) {
    if (!j_.is_object()) fail(where(), " must be a JSON object");
  }
  /// Fails on keys not described under `path` (knownSceneKeys).
  void only(const std::string& path) const { only(knownSceneKeys(path)); }
  /// Fails on keys not in `known`.
  void only(const std::vector<std::string>& known) const {
    for (auto it = j_.begin(); it != j_.end(); ++it) {
      bool ok = false;
      std::string list;
      for (const std::string& k : known) {
        ok = ok || it.key() == k;
        list += (list.empty() ? "" : ", ") + k;
      }
      if (!ok) fail(source_, ": unknown key \"", key(it.key()), "\" (known: ", list, ")");
    }
  }
  const json* find(const char* k) const {
    const auto it = j_.find(k);
    return it == j_.end() ? nullptr : &*it;
  }
  std::string key(const std::string& k) const { return path_.empty() ? k : path_ + "." + k; }
  std::string where() const { return source_ + (path_.empty() ? "" : ": \"" + path_ + "\""); }
  const std::string& source() const { return source_; }

  bool boolean(const char* k, bool& out) const {
    const json* v = find(k);
    if (!v) return false;
    if (!v->is_boolean()) fail(source_, ": \"", key(k), "\" must be true or false, not ", v->dump());
    out = v->get<bool>();
    return true;
  }
  template <typename T> bool number(const char* k, T& out) const {
    const json* v = find(k);
    if (!v) return false;
    if (!v->is_number()) fail(source_, ": \"", key(k), "\" must be a number, not ", v->dump());
    const double d = v->get<double>();
    if (!std::isfinite(d)) fail(source_, ": \"", key(k), "\" must be finite");
    if constexpr (std::is_integral_v<T>) {
      if (d != std::floor(d) || d < double(std::numeric_limits<T>::min()) || d > double(std::numeric_limits<T>::max()))
        fail(source_, ": \"", key(k), "\" must be an integer in range, not ", v->dump());
    }
    out = T(d);
    return true;
  }
  /// A number checked against the range the description gives `described` (such as "camera.fov").
  template <typename T> bool number(const char* k, T& out, const std::string& described) const {
    if (!number(k, out)) return false;
    try {
      checkStructuredNumber(described, double(out));
    } catch (const Error& e) {
      fail(source_, ": ", e.what());
    }
    return true;
  }
  bool string(const char* k, std::string& out) const {
    const json* v = find(k);
    if (!v) return false;
    if (!v->is_string()) fail(source_, ": \"", key(k), "\" must be a string, not ", v->dump());
    out = v->get<std::string>();
    return true;
  }
  std::vector<double> numbers(const json& v, const std::string& what, size_t count) const {
    if (!v.is_array() || (count && v.size() != count))
      fail(source_, ": \"", what, "\" must be an array of ", count, " numbers, not ", v.dump());
    std::vector<double> out;
    for (const json& x : v) {
      if (!x.is_number() || !std::isfinite(x.get<double>()))
        fail(source_, ": \"", what, "\" must hold finite numbers, not ", x.dump());
      if (const std::string why = beyondSinglePrecision(x.get<double>()); !why.empty())
        fail(source_, ": \"", what, "\": ", why);
      out.push_back(x.get<double>());
    }
    return out;
  }
  vec3d triple(const json& v, const std::string& what) const {
    const std::vector<double> n = numbers(v, what, 3);
    return {n[0], n[1], n[2]};
  }
  bool vec3(const char* k, vec3d& out) const {
    const json* v = find(k);
    if (!v) return false;
    const std::vector<double> n = numbers(*v, key(k), 3);
    out = {n[0], n[1], n[2]};
    return true;
  }
  bool color(const char* k, vec3f& linear) const {
    vec3d c;
    if (!vec3(k, c)) return false;
    for (int a = 0; a < 3; ++a)
      if (!(c[a] >= 0.0 && c[a] <= 1.0)) fail(source_, ": \"", key(k), "\" components must lie in [0, 1] (sRGB)");
    linear = srgbToLinear(vec3f(c));
    return true;
  }
  /// Reads the described settings directly under `section` of this object ("" at the top).
  template <typename Owner>
  void settings(const std::vector<Setting<Owner>>& table, const std::string& section, Owner& o) const {
    for (const Setting<Owner>& s : table)
      if (s.section() == section)
        if (const json* v = find(s.leaf().c_str())) setting(s, *v, o);
  }

  Reader child(const char* k) const { return Reader(*find(k), source_, key(k)); }

private:
  template <typename Owner> void setting(const Setting<Owner>& s, const json& v, Owner& o) const {
    const std::string what = source_ + ": \"" + s.key + "\"";
    if (s.type == SettingType::Boolean && !v.is_boolean()) fail(what, " must be true or false, not ", v.dump());
    if (s.type == SettingType::Choice && !v.is_string()) fail(what, " must be a string, not ", v.dump());
    if (s.type == SettingType::Integer || s.type == SettingType::Number) {
      if (!v.is_number()) fail(what, " must be a number, not ", v.dump());
      try {
        checkSetting(s, v.get<double>());
      } catch (const Error& e) {
        fail(source_, ": ", e.what());
      }
    }
    if (s.type == SettingType::Vector && !(v.is_null() && s.optional)) {
      try {
        checkVectorValue(s.key, s.vector, v);
      } catch (const Error& e) {
        fail(source_, ": ", e.what());
      }
    }
    s.set(o, v, what);
  }

  const json& j_;
  std::string source_, path_;
};

json cameraJson(const Camera& c) {
  return {{"position", vec(c.position)},    {"look_at", vec(c.lookAt)},     {"up", vec(c.up)}, {"fov", c.fovy},
          {"orthographic", c.orthographic}, {"ortho_height", c.orthoHeight}};
}

/// A camera object; false when it has no position. Errors name the key.
bool readCamera(const Reader& c, Camera& cam) {
  c.only("camera");
  // The keys left out take the described defaults.
  auto described = [](const char* k) {
    const json& d = structuredDefault(k);
    return vec3d(d[0].get<double>(), d[1].get<double>(), d[2].get<double>());
  };
  cam = Camera();
  cam.lookAt = described("camera.look_at");
  cam.up = described("camera.up");
  cam.fovy = structuredDefault("camera.fov").get<double>();
  cam.orthographic = structuredDefault("camera.orthographic").get<bool>();
  cam.orthoHeight = structuredDefault("camera.ortho_height").get<double>();
  const bool hasPosition = c.vec3("position", cam.position);
  c.vec3("look_at", cam.lookAt);
  c.vec3("up", cam.up);
  c.number("fov", cam.fovy, "camera.fov");
  c.boolean("orthographic", cam.orthographic);
  c.number("ortho_height", cam.orthoHeight, "camera.ortho_height");
  return hasPosition;
}

TransferFunction readTf(const Reader& r, const char* k, const TransferFunction& fallback) {
  const json* v = r.find(k);
  if (!v) return fallback;
  return transferFunctionFromJson(*v, r.source() + ": \"" + r.key(k) + "\"");
}

/// The keys directly under `section` of a scene file: the described ones, then `keys` (read but
/// no longer part of scene files).
std::vector<std::string> keysOf(const std::string& section, std::vector<std::string> keys) {
  std::vector<std::string> all = knownSceneKeys(section);
  all.insert(all.end(), keys.begin(), keys.end());
  return all;
}

template <typename Owner> void writeSettings(const std::vector<Setting<Owner>>& table, const Owner& o, json& j) {
  for (const Setting<Owner>& s : table) {
    json value = s.get(o);
    if (value.is_null()) continue; // an optional setting left unset
    json& section = s.section().empty() ? j : j[s.section()];
    section[s.leaf()] = std::move(value);
  }
}

json sceneJson(const SceneDocument& doc) {
  const Scene& s = doc.scene;
  const Frame& f = doc.frame;
  json j = json::object();
  if (!doc.input.empty()) j["input"] = doc.input;
  j["camera"] = cameraJson(f.camera);
  json layers = json::array();
  for (const VolumeLayer& l : s.layers)
    layers.push_back({{"field", l.field}, {"transfer_function", transferFunctionToJson(l.tf)}});
  j["layers"] = layers;
  json iso = {{"field", s.iso.field}, {"values", s.iso.values}};
  json isoColors = json::array();
  for (const vec3f& col : s.iso.colors)
    isoColors.push_back(srgb(col));
  iso["colors"] = isoColors;
  iso["color_field"] = s.iso.colorField;
  iso["color_map"] = transferFunctionToJson(s.iso.colorTf);
  j["iso"] = iso;
  json meshes = json::array();
  for (const SceneMesh& m : s.meshes) {
    json jm = {{"color", srgb(m.color)}};
    if (!m.source.empty()) {
      jm["file"] = m.source;
    } else if (m.mesh) {
      json verts = json::array(), tris = json::array();
      for (const vec3f& v : m.mesh->vertices)
        verts.push_back(vec(v));
      for (const vec3i& t : m.mesh->triangles)
        tris.push_back({t.x, t.y, t.z});
      jm["vertices"] = verts;
      jm["triangles"] = tris;
    }
    meshes.push_back(jm);
  }
  j["meshes"] = meshes;
  j["particles"] = {{"species", s.particles.species},
                    {"radius_by", s.particles.radiusBy},
                    {"color", srgb(s.particles.color)},
                    {"color_by", s.particles.colorBy},
                    {"color_map", transferFunctionToJson(s.particles.colorTf)}};
  json planes = json::array();
  for (const ClipPlane& p : s.clip.planes)
    planes.push_back({{"point", vec(p.point)}, {"normal", vec(p.normal)}});
  j["clip"] = {{"planes", planes}};
  if (!s.clip.box.empty())
    j["clip"]["box"] = {s.clip.box.lower.x, s.clip.box.lower.y, s.clip.box.lower.z,
                        s.clip.box.upper.x, s.clip.box.upper.y, s.clip.box.upper.z};
  j["background"] = srgb(s.background);
  writeSettings(frameSettings(), f, j);
  writeSettings(sceneSettings(), s, j);
  if (!doc.path.empty()) {
    json keys = json::array();
    for (const CameraKeyframe& k : doc.path.keyframes) {
      json jk = {{"time", k.time}, {"camera", cameraJson(k.camera)}};
      if (k.range) jk["range"] = {k.range->lower, k.range->upper};
      if (k.opacityScale) jk["opacity_scale"] = *k.opacityScale;
      if (k.isoValues) jk["iso_values"] = *k.isoValues;
      keys.push_back(jk);
    }
    j["camera_path"] = {{"keyframes", keys}, {"constant_speed", doc.path.constantSpeed}};
  }
  return j;
}

} // namespace

std::string writeSceneJson(const SceneDocument& doc) {
  json j = sceneJson(doc);
  removeFloatNoise(j);
  return j.dump(2) + "\n";
}

std::string exactSceneJson(const SceneDocument& doc) { return sceneJson(doc).dump(); }

namespace {

void readCameraPath(const Reader& p, const std::string& source, CameraPath& path) {
  p.only("camera_path");
  p.boolean("constant_speed", path.constantSpeed);
  const json* keys = p.find("keyframes");
  if (!keys || !keys->is_array() || keys->empty())
    fail(source, ": \"camera_path.keyframes\" must be a non-empty array of {\"time\", \"camera\", ...}");
  for (size_t i = 0; i < keys->size(); ++i) {
    const Reader k((*keys)[i], source, "camera_path.keyframes[" + std::to_string(i) + "]");
    k.only("camera_path.keyframes[]");
    CameraKeyframe key;
    if (!k.number("time", key.time)) fail(source, ": \"", k.key("time"), "\" is required");
    if (!k.find("camera") || !readCamera(k.child("camera"), key.camera))
      fail(source, ": \"", k.key("camera"), "\" with a \"position\" is required");
    if (const json* v = k.find("range")) {
      const std::vector<double> n = k.numbers(*v, k.key("range"), 2);
      key.range = range1f{float(n[0]), float(n[1])};
    }
    float scale = 0.f;
    if (k.number("opacity_scale", scale, "camera_path.keyframes[].opacity_scale")) key.opacityScale = scale;
    if (const json* v = k.find("iso_values")) {
      std::vector<float> values;
      for (double d : k.numbers(*v, k.key("iso_values"), 0))
        values.push_back(float(d));
      key.isoValues = values;
    }
    path.keyframes.push_back(key);
  }
  try {
    path.validate();
  } catch (const Error& e) {
    fail(source, ": ", e.what());
  }
}

void readLayers(const json& layers, const std::string& source, std::vector<VolumeLayer>& out) {
  if (!layers.is_array()) fail(source, ": \"layers\" must be an array of {\"field\", \"transfer_function\"}");
  out.clear();
  for (size_t i = 0; i < layers.size(); ++i) {
    const Reader l(layers[i], source, "layers[" + std::to_string(i) + "]");
    l.only("layers[]");
    VolumeLayer layer;
    l.string("field", layer.field);
    layer.tf = readTf(l, "transfer_function", layer.tf);
    out.push_back(layer);
  }
}

void readIso(const Reader& c, const std::string& source, IsoSurfaces& iso) {
  c.only("iso");
  c.string("field", iso.field);
  if (const json* v = c.find("values"))
    for (double d : c.numbers(*v, c.key("values"), 0))
      iso.values.push_back(float(d));
  if (const json* v = c.find("colors")) {
    if (!v->is_array()) fail(source, ": \"iso.colors\" must be an array of [r, g, b] (sRGB)");
    for (const json& col : *v) {
      const std::vector<double> n = c.numbers(col, c.key("colors"), 3);
      for (double x : n)
        if (!(x >= 0.0 && x <= 1.0)) fail(source, ": \"iso.colors\" components must lie in [0, 1] (sRGB)");
      iso.colors.push_back(srgbToLinear(vec3f(float(n[0]), float(n[1]), float(n[2]))));
    }
  }
  c.string("color_field", iso.colorField);
  iso.colorTf = readTf(c, "color_map", iso.colorTf);
}

void readParticles(const Reader& c, const std::string& source, Scene& s) {
  c.only("particles");
  ParticleStyle& p = s.particles;
  c.string("species", p.species);
  c.string("radius_by", p.radiusBy);
  c.string("color_by", p.colorBy);
  if (const json* v = c.find("color")) {
    const std::vector<double> n = c.numbers(*v, c.key("color"), 3);
    for (double x : n)
      if (!(x >= 0.0 && x <= 1.0)) fail(source, ": \"particles.color\" components must lie in [0, 1] (sRGB)");
    p.color = srgbToLinear(vec3f(float(n[0]), float(n[1]), float(n[2])));
  }
  p.colorTf = readTf(c, "color_map", p.colorTf);
  c.settings(sceneSettings(), "particles", s);
}

void readMeshes(const json& meshes, const std::string& source, std::vector<SceneMesh>& out) {
  if (!meshes.is_array()) fail(source, ": \"meshes\" must be an array");
  for (size_t i = 0; i < meshes.size(); ++i) {
    const Reader m(meshes[i], source, "meshes[" + std::to_string(i) + "]");
    m.only("meshes[]");
    SceneMesh sm;
    m.color("color", sm.color);
    if (m.string("file", sm.source)) {
      // Read by the caller (documents/scene_file.h): the library's render layer reads no files.
    } else {
      const json* v = m.find("vertices");
      const json* t = m.find("triangles");
      if (!v || !t || !v->is_array() || !t->is_array())
        fail(source, ": \"", m.key("file"), "\" or \"vertices\" and \"triangles\" arrays are needed");
      auto mesh = std::make_shared<TriangleMesh>();
      for (const json& x : *v)
        mesh->vertices.push_back(vec3f(m.triple(x, m.key("vertices"))));
      for (const json& x : *t) {
        const vec3d idx = m.triple(x, m.key("triangles"));
        mesh->triangles.push_back(vec3i(int(idx.x), int(idx.y), int(idx.z)));
      }
      sm.mesh = mesh;
    }
    out.push_back(sm);
  }
}

void readClip(const Reader& c, const std::string& source, Scene& s) {
  c.only("clip");
  if (const json* planes = c.find("planes")) {
    if (!planes->is_array()) fail(source, ": \"clip.planes\" must be an array of {\"point\", \"normal\"}");
    for (size_t i = 0; i < planes->size(); ++i) {
      const Reader p((*planes)[i], source, "clip.planes[" + std::to_string(i) + "]");
      p.only("clip.planes[]");
      ClipPlane cp;
      if (!p.vec3("point", cp.point) || !p.vec3("normal", cp.normal))
        fail(source, ": \"clip.planes[", i, "]\" needs \"point\" and \"normal\"");
      s.clip.planes.push_back(cp);
    }
  }
  if (const json* b = c.find("box"); b && !b->is_null()) {
    const std::vector<double> n = c.numbers(*b, "clip.box", 6);
    if (!(n[0] < n[3] && n[1] < n[4] && n[2] < n[5]))
      fail(source, ": \"clip.box\" needs its lower corner below its upper one");
    s.clip.box = box3d(vec3d(n[0], n[1], n[2]), vec3d(n[3], n[4], n[5]));
  }
  c.settings(sceneSettings(), "clip", s);
}

void readIntegration(const Reader& c, const std::string& source, Scene& s) {
  c.only(keysOf("integration", {"vectorized", "lazy_gradients", "join_segments"}));
  c.settings(sceneSettings(), "integration", s);
  // Renderer options that scene files once carried (RendererOptions): read and ignored.
  for (const char* key : {"vectorized", "lazy_gradients", "join_segments"}) {
    bool unused = false;
    if (c.boolean(key, unused))
      logNote(strCat(source, ": \"integration.", key,
                     "\" is ignored: it is a renderer option for benchmarks (exabricks bench, render flags), not a "
                     "scene setting"));
  }
}

} // namespace

SceneDocument readSceneJson(const std::string& text, const std::string& source) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {
    std::string m = e.what();
    if (const size_t p = m.find("] "); m.rfind("[json.exception.", 0) == 0 && p != std::string::npos)
      m = m.substr(p + 2);
    fail(source, ": invalid JSON: ", m);
  }
  SceneDocument doc;
  Scene& s = doc.scene;
  Frame& f = doc.frame;
  const Reader r(j, source, "");
  r.only("");
  r.string("input", doc.input);
  if (r.find("camera")) {
    doc.hasCamera = readCamera(r.child("camera"), f.camera);
    if (!doc.hasCamera) fail(source, ": \"camera\" needs a \"position\"");
  }
  if (r.find("camera_path")) readCameraPath(r.child("camera_path"), source, doc.path);
  if (r.find("frame")) {
    const Reader c = r.child("frame");
    c.only("frame");
    c.settings(frameSettings(), "frame", f);
    c.number("frame_index", f.frameIndex, "frame.frame_index");
  }
  if (const json* layers = r.find("layers")) readLayers(*layers, source, s.layers);
  if (r.find("iso")) readIso(r.child("iso"), source, s.iso);
  if (const json* meshes = r.find("meshes")) readMeshes(*meshes, source, s.meshes);
  if (r.find("particles")) readParticles(r.child("particles"), source, s);
  if (r.find("clip")) readClip(r.child("clip"), source, s);
  if (r.find("light")) {
    const Reader c = r.child("light");
    c.only("light");
    c.settings(sceneSettings(), "light", s);
  }
  if (r.find("pathtrace")) {
    const Reader c = r.child("pathtrace");
    c.only("pathtrace");
    c.settings(sceneSettings(), "pathtrace", s);
  }
  if (r.find("ambient_occlusion")) {
    const Reader c = r.child("ambient_occlusion");
    c.only("ambient_occlusion");
    c.settings(sceneSettings(), "ambient_occlusion", s);
  }
  if (r.find("integration")) readIntegration(r.child("integration"), source, s);
  if (r.find("legends")) {
    const Reader c = r.child("legends");
    c.only("legends");
    c.settings(sceneSettings(), "legends", s);
  }
  r.settings(sceneSettings(), "", s);
  r.color("background", s.background);
  try {
    s.validate(); // meshes named by file are checked once they are read
    if (doc.hasCamera || r.find("frame")) f.validate();
  } catch (const Error& e) {
    fail(source, ": ", e.what());
  }
  return doc;
}

} // namespace exa
