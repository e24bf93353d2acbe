// The viewer server's private parts shared by its files (server.cpp: the view's routes and the
// server's life; server_jobs.cpp: the series, movie, picture and holes routes): the server's
// state and the helpers that answer requests.
#pragma once

#include "server.h"

#include "exabricks/amr/model.h"
#include "exabricks/core/error.h"
#include "exabricks/core/log.h"
#include "exabricks/core/text.h"
#include "exabricks/documents/image.h"
#include "exabricks/io/particles.h"
#include "exabricks/render/defaults.h"
#include "exabricks/render/legends.h"
#include "exabricks/render/scene_vocabulary.h"
#include "exabricks/render/transfer_function.h"

#include "jobs.h"
#include "movie.h"
#include "pictures.h"
#include "session.h"
#include "steps.h"

#include <httplib.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <string>

namespace exa::view {

using json = nlohmann::json;

/// A client error: the status and the message the page shows.
/// Compares in time independent of where the strings differ.
inline bool sameToken(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < a.size(); ++i)
    diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

struct RequestError {
  int status;
  std::string message;
};

[[noreturn]] inline void reject(int status, const std::string& message) { throw RequestError{status, message}; }

inline void sendJson(httplib::Response& res, const json& j, int status = 200) {
  res.status = status;
  res.set_content(j.dump(), "application/json");
}

inline json parseBody(const httplib::Request& req) {
  try {
    return json::parse(req.body);
  } catch (const json::exception& e) {
    reject(400, std::string("the request body is not valid JSON: ") + e.what());
  }
}

inline double numberParam(const httplib::Request& req, const char* name, double fallback) {
  if (!req.has_param(name)) return fallback;
  double v = 0;
  if (!parseFiniteNumber(req.get_param_value(name), v)) reject(400, strCat("parameter '", name, "' is not a number"));
  return v;
}

inline json rangeJson(const range1f& r) {
  if (r.empty()) return json::array({nullptr, nullptr});
  return json::array({r.lower, r.upper});
}

/// An integer from a JSON body, or a 400 naming the key.
inline int intOf(const json& body, const char* key, const char* what) {
  const json& v = body.at(key);
  if (!v.is_number_integer() && !(v.is_number() && v.get<double>() == std::floor(v.get<double>())))
    reject(400, strCat(what, ": \"", key, "\" must be a whole number"));
  const double d = v.get<double>();
  if (!(d >= -2.0e9 && d <= 2.0e9)) reject(400, strCat(what, ": \"", key, "\" is out of range"));
  return int(d);
}

struct Server::Impl {
  ViewContent content;
  ServerOptions options;
  std::string token;
  httplib::Server http;
  std::unique_ptr<Session> session;
  std::unique_ptr<ViewSteps> steps;
  std::unique_ptr<MovieMaker> movies;
  std::unique_ptr<PictureMaker> pictures;
  std::atomic<int> streams{0};
  std::atomic<int> snapshotWaits{0};
  std::atomic<bool> stopping{false};
  int port = 0; ///< once the socket listens (connections wait there until the server runs)
  /// Whether the server is still there for a thread that reads the whole dataset (coarse levels
  /// first), which holds the mutex while it hands the dataset over.
  struct Refining {
    std::mutex mutex;
    bool alive = true;
  };
  std::shared_ptr<Refining> refining = std::make_shared<Refining>();
  /// Reads the whole dataset on a detached thread, then shows it (ViewContent::refine).
  void startRefining(const LegendText& legends);
  /// Binds the socket with the routes (throws exa::Error when it cannot).
  void listen();
  /// The content's steps, session and refinement; the first picture starts rendering.
  void start();

  /// The name a download of the view takes, as Save picture names its files: the dataset shown,
  /// the first layer's field and the size (`extension` replaces the picture's), in a
  /// Content-Disposition header.
  std::string attachment(int width, int height, const std::string& extension) const {
    const std::optional<SceneDocument> doc = session->current();
    const SceneDocument& d = doc ? *doc : content.initial;
    const StepView step = steps->current();
    std::string field;
    const int index = step.model->fieldIndex(d.scene.layers.empty() ? std::string() : d.scene.layers[0].field);
    if (index >= 0) field = step.model->fieldNames[size_t(index)];
    std::string name =
        pictureName(step.input.empty() ? "exabricks" : step.input, field, width, height, ImageFormat::Png);
    name = name.substr(0, name.size() - 4) + extension;
    return strCat("attachment; filename=\"", name, "\"");
  }

  /// A scene document from a request: parsed, its meshes resolved to the meshes loaded at start,
  /// its settings and fields checked, sizes bounded. Throws RequestError.
  SceneDocument documentFrom(const std::string& text, const char* what, bool* hasCamera = nullptr) {
    SceneDocument doc;
    try {
      doc = readSceneJson(text, what);
    } catch (const Error& e) {
      reject(400, e.what());
    }
    if (hasCamera) *hasCamera = doc.hasCamera;
    if (!doc.hasCamera) doc.frame.camera = content.initial.frame.camera;
    const StepView step = steps->current();
    doc.input = step.input;
    for (SceneMesh& m : doc.scene.meshes) {
      if (m.mesh) continue; // given inline
      const auto& known = content.initial.scene.meshes;
      const auto it =
          std::find_if(known.begin(), known.end(), [&](const SceneMesh& k) { return k.source == m.source; });
      if (it == known.end())
        reject(400, strCat(what, ": mesh '", m.source,
                           "' was not given when the viewer started (the viewer reads no file a request names; "
                           "start it with --mesh ",
                           m.source, ")"));
      m.mesh = it->mesh;
    }
    const Frame& f = doc.frame;
    if (f.width < 1 || f.height < 1 || f.width > options.maxImageSide || f.height > options.maxImageSide)
      reject(400, strCat(what, ": image size ", f.width, "x", f.height, " is outside 1..", options.maxImageSide,
                         " per side"));
    if (f.samplesPerPixel < 1 || f.samplesPerPixel > options.maxSamplesPerPixel)
      reject(400,
             strCat(what, ": samples per pixel ", f.samplesPerPixel, " is outside 1..", options.maxSamplesPerPixel));
    try {
      doc.scene.validate();
      f.validate();
      const Model& model = *step.model;
      auto check = [&](const std::string& field) {
        if (!field.empty()) model.requireField(field);
      };
      for (const VolumeLayer& l : doc.scene.layers)
        check(l.field);
      check(doc.scene.iso.field);
      check(doc.scene.iso.colorField);
    } catch (const Error& e) {
      reject(400, strCat(what, ": ", e.what()));
    }
    return doc;
  }

  json info() const {
    const StepView step = steps->current();
    const Model& model = *step.model;
    json j;
    j["name"] = content.name;
    j["input"] = step.input;
    j["step"] = step.index;
    j["steps"] = steps->size();
    j["simulation"] = simulationJson(model.simulation);
    j["can_encode_movies"] = MovieMaker::canEncode();
    j["nan_as_holes"] = steps->loadOptions().nonFinite == NonFinite::Holes;
    // What path tracing chosen on the page samples with, as the command line's does.
    j["path_tracing_defaults"] = {
        {"noise_target", kDefaultNoiseTarget}, {"samples_per_pixel", kDefaultPathTracedPasses}, {"denoise", true}};
    json fields = json::array();
    for (size_t i = 0; i < model.fieldNames.size(); ++i)
      fields.push_back({{"name", model.fieldNames[i]},
                        {"units", model.unitsOf(int(i))},
                        {"range", rangeJson(step.dataset.valueRanges.at(i))}});
    j["fields"] = fields;
    j["default_field"] = model.fieldNames.at(size_t(model.requireField("")));
    // The particle species beside the cells (from the input's headers): the page offers them.
    try {
      j["particles"] = json::parse(
          particleSpeciesJson(step.input.empty() ? std::vector<ParticleSpeciesInfo>() : listParticles(step.input)));
    } catch (const Error& e) {
      j["particles"] = json::array();
      j["particles_error"] = e.what();
    }
    const box3d wb = model.worldBounds();
    j["bounds"] = {wb.lower.x, wb.lower.y, wb.lower.z, wb.upper.x, wb.upper.y, wb.upper.z};
    const ModelSummary summary = summarize(model);
    j["cells"] = summary.cells;
    j["regions"] = summary.regions;
    json levels = json::array();
    for (const ModelSummary::Level& l : summary.levels) {
      const vec3d w = model.world.scale * double(1u << l.level);
      levels.push_back(json{{"level", l.level}, {"cell_width", {w.x, w.y, w.z}}, {"cells", l.cells}});
    }
    j["levels"] = levels;
    json maps = json::object();
    for (const std::string& name : builtinColorMapNames()) {
      const ColorMap map = builtinColorMap(name);
      json samples = json::array();
      for (int i = 0; i < 32; ++i) {
        const vec3f c = linearToSrgb(map.at(float(i) / 31.f));
        samples.push_back({c.x, c.y, c.z});
      }
      maps[name] = samples;
    }
    j["colormaps"] = maps;
    j["document"] = json::parse(writeSceneJson(content.initial));
    j["default_opacity_scale"] = step.dataset.defaultOpacityScale;
    j["limits"] = {{"max_image_side", options.maxImageSide},
                   {"max_samples_per_pixel", options.maxSamplesPerPixel},
                   {"max_request_bytes", options.maxRequestBytes}};
    return j;
  }

  /// Counts of the field's values over `bins` equal steps of the normalised value.
  json histogram(const httplib::Request& req) const {
    const StepView step = steps->current();
    const Model& model = *step.model;
    if (!req.has_param("field")) reject(400, "histogram: parameter 'field' is missing");
    const std::string name = req.get_param_value("field");
    const int field = model.fieldIndex(name);
    if (field < 0) reject(400, strCat("histogram: unknown field '", name, "'"));
    const double bins = numberParam(req, "bins", 128);
    if (!(bins >= 1 && bins <= 4096) || bins != std::floor(bins)) reject(400, "histogram: bins must be in 1..4096");
    const range1f data = step.dataset.valueRanges.at(size_t(field));
    const double lo = numberParam(req, "lo", data.empty() ? 0.0 : data.lower);
    const double hi = numberParam(req, "hi", data.empty() ? 1.0 : data.upper);
    const bool logScale = req.has_param("log") && req.get_param_value("log") == "1";
    if (!(lo < hi)) reject(400, "histogram: lo must be below hi");
    if (logScale && !(lo > 0)) reject(400, "histogram: a log histogram needs lo > 0");
    TransferFunction tf;
    tf.valueRange = range1f{float(lo), float(hi)};
    tf.logScale = logScale;
    std::vector<uint64_t> counts(size_t(bins), 0);
    uint64_t below = 0, above = 0, none = 0;
    const float flo = float(lo), fhi = float(hi);
    for (float v : model.fieldValues[size_t(field)]) {
      if (!std::isfinite(v) || (logScale && !(v > 0.f))) {
        ++none;
        continue;
      }
      if (v < flo) {
        ++below;
        continue;
      }
      if (v > fhi) {
        ++above;
        continue;
      }
      const float t = tf.normalize(v);
      counts[std::min(size_t(t * float(bins)), counts.size() - 1)]++;
    }
    return {{"counts", counts}, {"below", below}, {"above", above}, {"excluded", none},
            {"lo", lo},         {"hi", hi},       {"log", logScale}};
  }

  bool authorised(const httplib::Request& req) const {
    if (req.has_param("token") && sameToken(req.get_param_value("token"), token)) return true;
    if (req.has_header("X-Exabricks-Token") && sameToken(req.get_header_value("X-Exabricks-Token"), token)) return true;
    const std::string cookies = req.get_header_value("Cookie");
    const std::string key = strCat(cookieName(), "=");
    for (size_t at = cookies.find(key); at != std::string::npos; at = cookies.find(key, at + 1)) {
      if (at > 0 && cookies[at - 1] != ' ' && cookies[at - 1] != ';') continue;
      const size_t begin = at + key.size();
      const size_t end = cookies.find(';', begin);
      if (sameToken(cookies.substr(begin, end == std::string::npos ? std::string::npos : end - begin), token))
        return true;
    }
    return false;
  }

  /// One cookie per port: viewers on other ports of the same host keep their own.
  std::string cookieName() const { return strCat("exabricks_token_", port); }

  void routes();
  void requestRoutes();
  void frameRoutes();
  void sceneRoutes();
  void seriesRoutes();
  void movieRoutes();
  void pictureRoutes();
};

} // namespace exa::view
